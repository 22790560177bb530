#include "impact.h"
#include "support.h"
#include "time_loop.h"

#include "dembridge/dem/output.h"
#include "dembridge/dem/packing.h"
#include "dembridge/dem/solver.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace dembridge::demo
{
using namespace dembridge::dem;

namespace
{
using V3 = std::array<double, 3>;

double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

double mean(const std::vector<double>& v)
{
  double s = 0.0;
  for (double x : v)
    s += x;
  return v.empty() ? 0.0 : s / v.size();
}

std::string fmt(double v, int precision = 4)
{
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

/// Where the outcome stands.
enum class Outcome
{
  running,
  perforated, ///< it touched the slab, its tail is past the rear face and nothing touches it
  missed,     ///< its tail is past the rear face and it never touched the slab
  stopped,    ///< the projectile's speed along its path fell to zero (or reversed)
  time_up     ///< the duration was reached first
};

const char* outcome_name(Outcome o)
{
  switch (o)
  {
  case Outcome::running: return "running";
  case Outcome::perforated: return "perforated";
  case Outcome::missed: return "missed";
  case Outcome::stopped: return "stopped";
  case Outcome::time_up: return "time up";
  }
  return "";
}

/// One impact run: set-up (slab, projectile, supports, domain, time step),
/// the time loop with its history, frames and progress, and the
/// measurements at the end.
class ImpactRun
{
public:
  explicit ImpactRun(const ImpactConfig& cfg) : _cfg(cfg), _s(cfg.scenario) {}

  nlohmann::json run()
  {
    if (_cfg.restart)
      _ckpt = std::make_unique<Checkpointer>(*_cfg.restart, _cfg.output_dir);
    build_target();
    build_projectile();
    set_up_solver();
    describe();
    start_or_resume(_ckpt.get(), [this] { resume(); }, [this] { open_output(); });
    print_header();
    loop();
    report();
    return _out;
  }

private:
  // ---- set-up ---------------------------------------------------------------
  void build_target()
  {
    const TargetSpec& t = _s.target;
    _lo = {-0.5 * t.size[0], -0.5 * t.size[1], -t.thickness};
    _hi = {0.5 * t.size[0], 0.5 * t.size[1], 0.0};
    const Region region = box_region(_lo, _hi);
    if (_s.reinforcement.any())
      make_the_bars();
    // the dem module's errors name the region; the user's keys are these
    const std::string keys = "target.mean_radius_m = " + fmt(t.mean_radius) + " m in the slab (target.size_m ["
                             + fmt(t.size[0]) + ", " + fmt(t.size[1]) + "] m, thickness_m " + fmt(t.thickness)
                             + " m)";
    if (!t.packing_file.empty())
      _pk = read_target_packing(region);
    else
      _pk = with_context(keys, [&] { return pack(region); });
    if (_pk.size() == 0)
      throw std::runtime_error("target: no sphere in the slab (target.mean_radius_m " + fmt(t.mean_radius)
                               + " m against its size): use smaller spheres");
    // a packing file's spheres that overlap a bar are left out (a generated
    // packing was made around the bars: pack_around_bars), unless the bars
    // are embedded; the solid fraction is then taken over the spheres kept
    if (_s.reinforcement.any() && !_s.reinforcement.embedded && !t.packing_file.empty())
      clear_bars(_pk.x, _pk.r);
    _fraction = concrete_fraction(_pk, region, _bars); // over the slab's volume less the bars'
    const Material& mat = _s.material.material;
    _p = make_particles(_pk.x, _pk.r, mat.density, _fraction);
    const auto bulk = with_context(keys, [&] { return bulk_spheres(region, _p.x, _p.r); });
    _lambda = lambda_for_mean_links(_p.x, _p.r, _s.material.links_per_sphere, bulk);
    _links = create_links(_p, _lambda, mat);
    if (_s.reinforcement.any())
      _bonds = create_bonds(_bars, _p, _s.reinforcement.bond_reach > 0.0 ? _s.reinforcement.bond_reach
                                                                         : 0.5 * mean(_p.r));
    _rmax = *std::max_element(_p.r.begin(), _p.r.end());
    _rmin = *std::min_element(_p.r.begin(), _p.r.end());
    _initial_links.assign(_p.size(), 0);
    for (std::size_t k = 0; k < _links.size(); ++k)
    {
      ++_initial_links[_links.a[k]];
      ++_initial_links[_links.b[k]];
    }
  }

  /// The slab's packing, graded along the projectile's path if the
  /// scenario asks for finer spheres there (fine_scale); with bars, packed
  /// round them (pack_around_bars), so that no void is left beside a bar
  /// (removing the spheres on the bars from a plain packing and lining the
  /// bars leaves a loose layer round them: validation.md 7b.2).
  Packing pack(const Region& region) const
  {
    const TargetSpec& t = _s.target;
    PackingOptions po;
    po.mean_radius = t.mean_radius;
    po.radius_ratio = t.radius_ratio;
    po.seed = t.seed;
    if (t.fine())
      po.size_scale = fine_scale(_s);
    if (!_cfg.quiet)
    {
      std::cout << "packing the slab (" << fmt(region.volume) << " m^3, mean radius " << t.mean_radius << " m";
      if (t.fine())
        std::cout << ", " << t.fine_mean() << " m within " << t.fine_radius << " m of the path";
      std::cout << ")..." << std::endl;
    }
    if (!_s.reinforcement.any() || _s.reinforcement.embedded)
      return generate_packing(region, po);
    ConcretePacking c = pack_around_bars(region, _bars, po);
    if (!_cfg.quiet)
      std::cout << "the bars' room: " << c.removed << " spheres removed, " << c.added << " added against the bars"
                << std::endl;
    return std::move(c.packing);
  }

  /// The bars of the scenario (make_bars), their elements at most
  /// element_length_m long (0: the mean sphere diameter).
  void make_the_bars()
  {
    const ReinforcementSpec& b = _s.reinforcement;
    const double h = b.element_length > 0.0 ? b.element_length : 2.0 * _s.target.mean_radius;
    try
    {
      _bars = make_bars(bar_lines(_s), {b.steel}, {b.bond}, h);
      _bars.sphere_contacts = !b.embedded;
    }
    catch (const std::exception& e)
    {
      throw std::runtime_error(std::string("reinforcement: ") + e.what());
    }
  }

  /// Leaves out the spheres (x, r) that overlap a bar by more than the
  /// packing's tolerance (1e-3 of the smallest radius).
  void clear_bars(std::vector<double>& x, std::vector<double>& r)
  {
    const double rmin = *std::min_element(r.begin(), r.end());
    const auto on = spheres_on_bars(_bars, x, r, 1e-3 * rmin);
    std::size_t kept = 0;
    for (std::size_t i = 0; i < r.size(); ++i)
      if (!on[i])
      {
        for (int k = 0; k < 3; ++k)
          x[3 * kept + k] = x[3 * i + k];
        r[kept++] = r[i];
      }
    _spheres_on_bars = r.size() - kept;
    x.resize(3 * kept);
    r.resize(kept);
  }

  /// A packing file's spheres, those centred in the slab (a sphere outside
  /// it is an error: the file is not this slab's).
  Packing read_target_packing(const Region& region) const
  {
    Packing pk = read_packing(_s.target.packing_file);
    std::size_t outside = 0;
    for (std::size_t i = 0; i < pk.size(); ++i)
      if (region.sdf({pk.x[3 * i], pk.x[3 * i + 1], pk.x[3 * i + 2]}) > 0.0)
        ++outside;
    if (pk.size() == 0 || outside == pk.size())
      throw std::runtime_error("target.packing_file " + _s.target.packing_file + ": no sphere in the slab ["
                               + fmt(_lo[0]) + ", " + fmt(_hi[0]) + "] x [" + fmt(_lo[1]) + ", " + fmt(_hi[1])
                               + "] x [" + fmt(_lo[2]) + ", 0] m");
    if (outside > 0)
      throw std::runtime_error("target.packing_file " + _s.target.packing_file + ": " + std::to_string(outside) + " of "
                               + std::to_string(pk.size()) + " spheres are centred outside the slab (size_m, "
                               "thickness_m): not this slab's packing");
    check_packing_fits(region, pk, "target.packing_file " + _s.target.packing_file);
    return pk;
  }

  void build_projectile()
  {
    const ProjectileSpec& q = _s.projectile;
    const Shape sh = projectile_shape(q); // checked when the scenario was read
    _dir = path_direction(q);
    const V3 aim{q.aim[0], q.aim[1], 0.0};
    const V3 tip{aim[0] - q.standoff * _dir[0], aim[1], aim[2] - q.standoff * _dir[2]};
    const double density = q.mass > 0.0 ? q.mass / sh.volume() : q.density;
    RigidBody b = make_projectile("projectile", sh, density, tip, _dir,
                                  {q.velocity * _dir[0], q.velocity * _dir[1], q.velocity * _dir[2]});
    b.friction = q.friction;
    _shape = sh;
    // no sphere may overlap the projectile at the start
    for (std::size_t i = 0; i < _p.size(); ++i)
    {
      const auto d = signed_distance(sh, b.to_body({_p.x[3 * i], _p.x[3 * i + 1], _p.x[3 * i + 2]}));
      if (d.d < _p.r[i])
        throw std::runtime_error("projectile: it overlaps the target at the start (a sphere at (" + fmt(_p.x[3 * i]) + ", "
                                 + fmt(_p.x[3 * i + 1]) + ", " + fmt(_p.x[3 * i + 2]) + ") m is "
                                 + fmt(_p.r[i] - d.d) + " m into it): increase projectile.standoff_m or move "
                                 "projectile.aim_m");
    }
    _body = b;
    _ke0 = b.kinetic_energy();
  }

  void set_up_solver()
  {
    const RunSpec& run = _s.run;
    const Material& mat = _s.material.material;
    _dt_crit = _s.reinforcement.any() ? critical_time_step(_p, _links, mat, _bars) : critical_time_step(_p, _links, mat);
    if (run.dt > _dt_crit)
      throw std::runtime_error("run.dt_s = " + fmt(run.dt) + " s is above the critical time step " + fmt(_dt_crit)
                               + " s (links, projectile contact and bars): give a smaller one, or 0 for safety_factor x "
                                 "critical");
    _dt = run.dt > 0.0 ? run.dt : run.safety * _dt_crit;
    const ProjectileSpec& q = _s.projectile;
    // the time to cross the slab at the striking speed sets the output's
    // pace; the run goes on for up to 4 x that, unless decided earlier
    _crossing = (q.standoff + _s.target.thickness / std::abs(_dir[2]) + q.length) / q.velocity;
    _duration = run.duration > 0.0 ? run.duration : 4.0 * _crossing;
    _nsteps = static_cast<std::int64_t>(std::ceil(_duration / _dt));
    _crossing_steps = std::max<std::int64_t>(1, static_cast<std::int64_t>(_crossing / _dt));
    _solver = std::make_unique<DemSolver>(_p, _links, mat, _dt, run.damping, run.skin > 0.0 ? run.skin : 0.5 * _rmin);
    set_up_supports();
    const double margin = run.domain_margin > 0.0 ? run.domain_margin : _s.target.thickness;
    _solver->set_domain({_lo[0] - margin, _lo[1] - margin, _lo[2] - margin},
                        {_hi[0] + margin, _hi[1] + margin, _hi[2] + margin});
    _solver->add_body(_body);
    if (_s.reinforcement.any())
      _solver->add_bars(_bars);
    _solver->start();
    _history_every = run.history_every > 0 ? run.history_every : std::max<std::int64_t>(1, _crossing_steps / 250);
  }

  void set_up_supports()
  {
    const TargetSpec& t = _s.target;
    if (t.supports == "none")
      return;
    const double w = t.support_width > 0.0 ? t.support_width : 2.0 * _rmax;
    const V3 lo = _lo, hi = _hi;
    auto near_side = [=](const V3& x)
    { return x[0] < lo[0] + w || x[0] > hi[0] - w || x[1] < lo[1] + w || x[1] > hi[1] - w; };
    std::vector<std::int32_t> ids;
    if (t.supports == "sides")
      ids = DemSolver::select(_p, near_side, "target.supports = \"sides\": the lateral faces' band (support_width_m)");
    else
      ids = DemSolver::select(_p, [&](const V3& x) { return x[2] < lo[2] + w && near_side(x); },
                              "target.supports = \"rear-edges\": the rear face's edge band (support_width_m)");
    _supported = ids.size();
    _solver->add_motion({"supports", std::move(ids), MotionKind::fixed, {true, true, true}, {}});
  }

  /// With finer spheres along the path, the mean radius of those centred
  /// within target.fine_radius_m of it (none: nullopt, as without them).
  std::optional<double> fine_mean_radius() const
  {
    if (!_s.target.fine())
      return std::nullopt;
    const auto scale = fine_scale(_s);
    const double fine = _s.target.fine_mean() / _s.target.mean_radius;
    double sum = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < _p.size(); ++i)
      if (scale({_p.x[3 * i], _p.x[3 * i + 1], _p.x[3 * i + 2]}) <= fine)
      {
        sum += _p.r[i];
        ++n;
      }
    if (n == 0)
      return std::nullopt;
    return sum / static_cast<double>(n);
  }

  void describe()
  {
    _out["scenario"] = _s.name;
    _out["particles"] = _p.size();
    _out["links"] = _links.size();
    _out["lambda"] = _lambda;
    _out["packing_fraction"] = _fraction;
    _out["mean_radius_m"] = mean(_p.r);
    _out["supported_spheres"] = _supported;
    _out["dt_s"] = _dt;
    _out["dt_critical_s"] = _dt_crit;
    _out["duration_s"] = _duration;
    _out["projectile_mass_kg"] = _body.mass;
    _out["striking_velocity_m_s"] = _s.projectile.velocity;
    const auto fine = fine_mean_radius();
    if (fine)
      _out["fine_mean_radius_m"] = *fine;
    else if (_s.target.fine())
      std::cerr << "warning: no sphere centre lies within target.fine_radius_m (" << _s.target.fine_radius
                << " m) of the path: fine_mean_radius_m is left out, spheres_across_diameter counts all the "
                   "spheres"
                << std::endl;
    _out["spheres_across_diameter"] = _s.projectile.diameter / (2.0 * fine.value_or(mean(_p.r)));
    if (_s.reinforcement.any())
    {
      double mass = 0.0;
      for (double m : _bars.m)
        mass += m;
      _out["reinforcement"] = {{"bars", _bars.line.empty() ? 0 : _bars.line.back() + 1},
                               {"elements", _bars.elements()},
                               {"bonds", _bonds},
                               {"bar_mass_kg", mass},
                               {"spheres_left_out", _spheres_on_bars},
                               {"embedded", _s.reinforcement.embedded}};
    }
  }

  // ---- output and restart ---------------------------------------------------
  std::filesystem::path dir() const { return _cfg.output_dir; }

  /// The output series, new or (root: a checkpoint's) continued.
  void open_writer(const checkpoint::Group* root)
  {
    const auto file = dir() / "particles.xdmf";
    _writer = root ? std::make_unique<ParticleWriter>(file, _links, _p.size(), true, root->group("particles_xdmf"))
                   : std::make_unique<ParticleWriter>(file, _links, _p.size(), true);
    _writer->add_surface("projectile", body_surface(_shape));
    if (_s.reinforcement.any())
    {
      const auto bars = dir() / "bars.xdmf";
      const auto& b = _solver->bars();
      _bar_writer = root ? std::make_unique<BarWriter>(bars, b, root->group("bars_xdmf"))
                         : std::make_unique<BarWriter>(bars, b);
    }
  }

  void open_output()
  {
    if (_cfg.output_dir.empty())
      return;
    std::filesystem::create_directories(dir());
    write_json(dir() / "scenario.json", _s.resolved);
    if (_s.target.packing_file.empty())
      write_packing(dir() / "packing.txt", _pk);
    open_writer(nullptr);
    write_frame();
    _csv.open(dir() / "history.csv");
    _csv << "time_s,tip_x_m,tip_y_m,tip_z_m,depth_m,velocity_x_m_s,velocity_y_m_s,velocity_z_m_s,speed_m_s,"
            "path_velocity_m_s,contact_force_n,contacts,links_broken,spheres_removed,projectile_kinetic_j,"
            "target_kinetic_j,elastic_j,dissipated_j,removed_j,imbalance_j\n";
    write_row();
  }

  void resume()
  {
    const auto file = _ckpt->open_restart();
    const auto root = file.root();
    _solver->load(root.group("dem"));
    const auto run = root.group("run");
    std::vector<double> tracked;
    run.read("tracked", tracked);
    if (tracked.size() != 3)
      run.fail("tracked", "not the 3 values of the run's tracking (file damaged?)");
    _max_depth = tracked[0];
    _touched = tracked[1] != 0.0;
    _peak_force = tracked[2];
    _out["restarted_from_step"] = _solver->steps();
    if (_cfg.output_dir.empty())
      return;
    open_writer(&root);
    reopen_text(_csv, dir() / "history.csv", run.read_int("csv_bytes"));
  }

  void save(const checkpoint::Group& root)
  {
    _solver->save(root.group("dem"));
    const auto run = root.group("run");
    run.write("tracked", std::vector<double>{_max_depth, _touched ? 1.0 : 0.0, _peak_force});
    if (_writer)
      _writer->save(root.group("particles_xdmf"));
    if (_bar_writer)
      _bar_writer->save(root.group("bars_xdmf"));
    if (_csv.is_open())
      run.write_int("csv_bytes", flushed_size(_csv, dir() / "history.csv"));
  }

  void write_frame()
  {
    const RigidBody& b = _solver->body(0);
    _writer->write(_solver->time(), _p, _links, std::span<const RigidBody>(&b, 1));
    if (_bar_writer)
      _bar_writer->write(_solver->time(), _solver->bars());
  }

  // ---- the projectile's state -----------------------------------------------
  V3 tip() const { return _solver->body(0).to_world({0.0, 0.0, 0.0}); }
  V3 tail() const { return _solver->body(0).to_world({-_shape.length, 0.0, 0.0}); }
  double path_velocity() const { return dot(_solver->body(0).v, _dir); }
  /// The contacts' force on the projectile against its path [N] (> 0 resists).
  double contact_force() const { return -dot(_solver->body(0).f, _dir); }

  std::size_t broken() const
  {
    return _links.count(LinkState::broken_tension) + _links.count(LinkState::broken_shear);
  }

  void write_row()
  {
    if (!_csv.is_open())
      return;
    const RigidBody& b = _solver->body(0);
    const auto e = _solver->energy();
    const V3 x = tip();
    _csv << std::setprecision(10) << _solver->time() << ',' << x[0] << ',' << x[1] << ',' << x[2] << ',' << -x[2]
         << ',' << b.v[0] << ',' << b.v[1] << ',' << b.v[2] << ',' << std::sqrt(dot(b.v, b.v)) << ','
         << path_velocity() << ',' << contact_force() << ',' << _solver->body_contacts(0).ids.size() << ','
         << broken() << ',' << _solver->removed().count << ',' << e.body_kinetic << ',' << e.kinetic + e.bar_kinetic
         << ',' << e.elastic + e.body_contact + e.bar_elastic << ','
         << e.softening + e.compaction + e.breakage + e.friction + e.body_friction + e.damping + e.bar_plastic
                + e.bar_opening + e.bar_slip + e.bar_broken
         << ',' << e.removed << ','
         << e.imbalance() << '\n' << std::flush; // whole rows, as far as the frames, if the run is killed
  }

  void print_header() const
  {
    if (_cfg.quiet)
      return;
    const Material& m = _s.material.material;
    std::cout << "# concrete: " << _s.material.file << ": E " << m.youngs_modulus << " Pa, T " << m.tensile
              << " Pa, C0 " << m.cohesion << " Pa, rate effect " << (m.rate_fc > 0 ? fmt(m.rate_fc) + " Pa" : "off")
              << "\n# " << _p.size() << " spheres (" << fmt(_out["spheres_across_diameter"].get<double>(), 3)
              << " across the projectile), " << _links.size() << " links (lambda " << fmt(_lambda) << "), "
              << _supported << " held\n";
    if (_s.reinforcement.any())
      std::cout << "# reinforcement: " << _out["reinforcement"]["bars"] << " bars of " << _s.reinforcement.bar_diameter
                << " m" << (_s.reinforcement.embedded ? " (embedded)" : "") << ", " << _bars.elements()
                << " elements, " << _bonds << " bonds; f_y " << _s.reinforcement.steel.yield
                << " Pa, bond tau_max " << _s.reinforcement.bond.tau_max << " Pa\n";
    std::cout << "# projectile " << fmt(_body.mass) << " kg at " << _s.projectile.velocity
              << " m/s (" << fmt(_ke0) << " J); dt " << fmt(_dt) << " s (critical " << fmt(_dt_crit) << "), up to "
              << _nsteps << " steps (" << fmt(_duration) << " s)\n"
              << "      time [s]  speed [m/s]  depth [m]  force [N]  broken  removed  imbalance/KE0\n";
  }

  void progress() const
  {
    const auto e = _solver->energy();
    std::cout << std::setw(14) << fmt(_solver->time()) << std::setw(13) << fmt(path_velocity()) << std::setw(11)
              << fmt(-tip()[2]) << std::setw(11) << fmt(contact_force(), 3) << std::setw(8) << broken()
              << std::setw(9) << _solver->removed().count << std::setw(15) << fmt(e.imbalance() / _ke0, 3)
              << std::endl;
  }

  // ---- the time loop --------------------------------------------------------
  Outcome outcome()
  {
    const double depth = -tip()[2];
    _max_depth = std::max(_max_depth, depth);
    const bool touching = !_solver->body_contacts(0).ids.empty();
    _touched = _touched || touching;
    _peak_force = std::max(_peak_force, contact_force());
    // stopped: at rest, rebounding, or coasting below 2 % of the striking
    // speed (0.04 % of its energy left: the depth no longer changes)
    if (_touched && path_velocity() <= 0.02 * _s.projectile.velocity)
      return Outcome::stopped;
    if (-tail()[2] > _s.target.thickness + _s.projectile.diameter && !touching)
      return _touched ? Outcome::perforated : Outcome::missed;
    return Outcome::running;
  }

  /// The shared time loop (time_loop.h): the outcome is its end condition;
  /// history rows every _history_every steps, frames every crossing /
  /// frames, progress every 2 s, each also at the last step.
  void loop()
  {
    const std::int64_t frame_every = std::max<std::int64_t>(1, _crossing_steps / _s.run.frames);
    const LoopPlan plan{.done = _solver->steps(),
                        .last = _nsteps,
                        .rows = {_history_every},
                        .frames = {frame_every},
                        .prints = {}, // at the end, and by the clock
                        .print_seconds = 2.0,
                        .checkpoints = _ckpt.get()};
    LoopHooks h = solver_hooks(*_solver);
    h.finished = [this](std::int64_t)
    {
      _outcome = outcome();
      return _outcome != Outcome::running;
    };
    h.row = [this](std::int64_t, bool) { write_row(); };
    if (_writer)
      h.frame = [this](std::int64_t, bool) { write_frame(); };
    if (!_cfg.quiet)
      h.progress = [this](std::int64_t, bool) { progress(); };
    h.save = [this](const checkpoint::Group& g) { save(g); };
    if (!run_time_loop(plan, h).finished)
      _outcome = Outcome::time_up;
    if (_writer)
    {
      _writer->close();
      if (_bar_writer)
        _bar_writer->close();
    }
  }

  // ---- measurements ---------------------------------------------------------
  void report()
  {
    const RigidBody& b = _solver->body(0);
    // perforated: it touched the slab and its tail passed the rear face
    const bool perforated = _outcome == Outcome::perforated
                            || (_outcome == Outcome::time_up && _touched && -tail()[2] > _s.target.thickness);
    _out["outcome"] = outcome_name(_outcome);
    _out["perforated"] = perforated;
    _out["residual_velocity_m_s"] = perforated ? std::sqrt(dot(b.v, b.v)) : 0.0;
    _out["final_path_velocity_m_s"] = path_velocity();
    // without contact, no penetration (the tip's depth alone says nothing)
    _out["penetration_depth_m"] = _touched ? std::clamp(_max_depth, 0.0, _s.target.thickness) : 0.0;
    _out["touched"] = _touched;
    _out["tip_depth_max_m"] = _max_depth;
    _out["peak_contact_force_n"] = _peak_force;
    measure_damage();
    report_energy();
    _out["links_broken"] = broken();
    _out["links_broken_tension"] = _links.count(LinkState::broken_tension);
    _out["links_broken_shear"] = _links.count(LinkState::broken_shear);
    _out["steps"] = _solver->steps();
    _out["time_s"] = _solver->time();
    const auto& tm = _solver->timings();
    _out["step_time_s"] = {{"links_and_contacts", tm.forces}, {"links", tm.forces - tm.contacts},
                           {"sphere_contacts", tm.contacts}, {"projectile_contacts", tm.bodies},
                           {"neighbours", tm.neighbours}, {"integration", tm.integration}};
    const double link_steps = static_cast<double>(_links.size()) * _solver->steps();
    const double wall = tm.forces + tm.bodies + tm.neighbours + tm.integration;
    _out["seconds_per_link_step"] = link_steps > 0 ? wall / link_steps : 0.0;
    _out["seconds_per_particle_step"] = wall / (static_cast<double>(_p.size()) * std::max<std::int64_t>(1, _solver->steps()));
    _out["neighbour_rebuilds"] = _solver->neighbours().builds();
    _out["neighbour_partial_rebuilds"] = _solver->neighbours().partial_builds();
    if (_s.reinforcement.any())
      report_bars();
  }

  void report_bars()
  {
    const Bars& b = _solver->bars();
    double eps_p = 0.0, force = 0.0;
    std::size_t broken_elements = 0, open = 0;
    for (std::size_t e = 0; e < b.elements(); ++e)
    {
      eps_p = std::max(eps_p, std::abs(b.plastic[e]));
      force = std::max(force, std::abs(b.force[e]));
      broken_elements += b.broken[e];
    }
    for (std::size_t k = 0; k < b.bonds(); ++k)
      open += b.open[k];
    auto& r = _out["reinforcement"];
    r["max_plastic_strain"] = eps_p;
    r["max_axial_force_n"] = force;
    r["elements_broken"] = broken_elements;
    r["bonds_open"] = open;
    _out["step_time_s"]["bars"] = _solver->timings().bars;
  }

  void measure_damage()
  {
    const auto& gone = _solver->removed_flags();
    CraterInput in;
    in.x0 = _p.x0;
    in.r = _p.r;
    in.m = _p.m;
    in.detached.assign(_p.size(), 0);
    std::vector<int> lost(_p.size(), 0);
    for (std::size_t k = 0; k < _links.size(); ++k)
      if (_links.state[k] != LinkState::intact)
      {
        ++lost[_links.a[k]];
        ++lost[_links.b[k]];
      }
    double ejected = _solver->removed().mass;
    for (std::size_t i = 0; i < _p.size(); ++i)
    {
      in.detached[i] = gone[i] || (_initial_links[i] > 0 && lost[i] == _initial_links[i]);
      if (in.detached[i] && !gone[i])
      {
        const double* x = &_p.x[3 * i];
        const bool outside = x[0] < _lo[0] || x[0] > _hi[0] || x[1] < _lo[1] || x[1] > _hi[1] || x[2] < _lo[2]
                             || x[2] > _hi[2];
        if (outside)
          ejected += _p.m[i];
      }
    }
    in.thickness = _s.target.thickness;
    in.layer = 2.0 * _rmax;
    in.fraction = _fraction;
    in.tunnel = 2.0 * _s.projectile.diameter;
    const auto [front, rear] = measure_craters(in);
    _out["front_crater_diameter_m"] = front.diameter;
    _out["front_crater_depth_m"] = front.depth;
    _out["front_crater_mass_kg"] = front.mass;
    _out["rear_scab_diameter_m"] = rear.diameter;
    _out["rear_scab_depth_m"] = rear.depth;
    _out["rear_scab_mass_kg"] = rear.mass;
    _out["ejected_mass_kg"] = ejected;
    _out["spheres_removed"] = _solver->removed().count;
    _out["removed_mass_kg"] = _solver->removed().mass;
  }

  void report_energy()
  {
    const auto e = _solver->energy();
    const double ke = _solver->body(0).kinetic_energy();
    _out["energy"] = {{"projectile_initial_j", _ke0},
                      {"projectile_final_j", ke},
                      {"projectile_lost_j", _ke0 - ke},
                      {"target_kinetic_j", e.kinetic},
                      {"elastic_j", e.elastic},
                      {"contact_elastic_j", e.body_contact},
                      {"softening_j", e.softening},
                      {"compaction_j", e.compaction},
                      {"breakage_j", e.breakage},
                      {"friction_j", e.friction},
                      {"projectile_friction_j", e.body_friction},
                      {"damping_j", e.damping},
                      {"removed_j", e.removed},
                      {"bar_kinetic_j", e.bar_kinetic},
                      {"bar_elastic_j", e.bar_elastic},
                      {"bar_plastic_j", e.bar_plastic},
                      {"bond_slip_j", e.bar_slip},
                      {"bond_opening_j", e.bar_opening},
                      {"bar_broken_j", e.bar_broken},
                      {"support_work_j", e.prescribed_work},
                      {"imbalance_j", e.imbalance()},
                      {"imbalance_share", e.imbalance() / _ke0}};
  }

  const ImpactConfig& _cfg;
  const Scenario& _s;
  nlohmann::json _out;
  V3 _lo{}, _hi{}, _dir{};
  Packing _pk;
  Particles _p;
  Links _links;
  std::vector<int> _initial_links;
  double _fraction = 0.0, _lambda = 0.0, _rmax = 0.0, _rmin = 0.0;
  Shape _shape;
  RigidBody _body;
  double _ke0 = 0.0;
  double _dt = 0.0, _dt_crit = 0.0, _duration = 0.0, _crossing = 0.0;
  std::int64_t _nsteps = 0, _crossing_steps = 1, _history_every = 1;
  std::size_t _supported = 0;
  std::unique_ptr<DemSolver> _solver;
  std::unique_ptr<Checkpointer> _ckpt;
  std::unique_ptr<ParticleWriter> _writer;
  std::unique_ptr<BarWriter> _bar_writer;
  Bars _bars;
  std::size_t _bonds = 0, _spheres_on_bars = 0;
  std::ofstream _csv;
  double _max_depth = -1e300, _peak_force = 0.0;
  bool _touched = false;
  Outcome _outcome = Outcome::running;
};

} // namespace

nlohmann::json run_impact(const ImpactConfig& cfg)
{
  Stopwatch clock;
  auto out = ImpactRun(cfg).run();
  out["wall_s"] = clock.seconds();
  return out;
}

} // namespace dembridge::demo
