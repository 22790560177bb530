// The impact run (impact_run.h): its time loop, output, checkpoints and
// measurements; run_impact.
#include "impact_run.h"
#include "support.h"
#include "time_loop.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace dembridge::demo
{
namespace impl
{

double mean(const std::vector<double>& v)
{
  double s = 0.0;
  for (double x : v)
    s += x;
  return v.empty() ? 0.0 : s / v.size();
}

std::string fmt(double v, int precision)
{
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

double target_kinetic(const DemEnergy& e) { return e.kinetic + e.bar_kinetic; }

double elastic_all(const DemEnergy& e) { return e.elastic + e.body_contact + e.bar_elastic; }

double dissipated(const DemEnergy& e)
{
  return e.softening + e.compaction + e.breakage + e.friction + e.body_friction + e.damping + e.bar_plastic
         + e.bar_opening + e.bar_slip + e.bar_broken;
}

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

nlohmann::json ImpactRun::run()
{
  if (_cfg.restart)
    _ckpt = std::make_unique<Checkpointer>(*_cfg.restart, _cfg.output_dir);
  if (_s.shells.coupled())
  {
    if (!_cfg.coupling)
      throw std::runtime_error("shells.model = \"coupled\": this program was built without the shells (use "
                               "build/bin/impact)");
    _coupling = _cfg.coupling(_s); // its checks before the packing
  }
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

void ImpactRun::open_writer(const checkpoint::Group* root)
{
  const auto file = dir() / "particles.xdmf";
  _writer = root ? std::make_unique<ParticleWriter>(file, _links, _p.size(), true, root->group("particles_xdmf"))
                 : std::make_unique<ParticleWriter>(file, _links, _p.size(), true);
  if (!pulsed())
    _writer->add_surface("projectile", body_surface(_shape));
  if (bars())
  {
    const auto bars = dir() / "bars.xdmf";
    const auto& b = _solver->bars();
    _bar_writer = root ? std::make_unique<BarWriter>(bars, b, root->group("bars_xdmf"))
                       : std::make_unique<BarWriter>(bars, b);
  }
  if (_coupling)
    _coupling->open_output(dir(), root);
}

void ImpactRun::open_output()
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
  if (pulsed())
    _csv << "time_s,load_n,load_work_j,links_broken,spheres_removed,target_kinetic_j,elastic_j,dissipated_j,"
            "removed_j,imbalance_j";
  else
    _csv << "time_s,tip_x_m,tip_y_m,tip_z_m,depth_m,velocity_x_m_s,velocity_y_m_s,velocity_z_m_s,speed_m_s,"
          "path_velocity_m_s,contact_force_n,contacts,links_broken,spheres_removed,projectile_kinetic_j,"
          "target_kinetic_j,elastic_j,dissipated_j,removed_j,imbalance_j";
  if (_coupling)
    _csv << ",shell_kinetic_j,shell_strain_j,multiplier_work_j,constraint_residual_m_s,shell_max_deflection_m";
  _csv << ",support_reaction_n";
  for (std::size_t q = 0; q < _s.shells.deflection_points.size(); ++q)
    _csv << ",deflection_" << q << "_m";
  _csv << '\n';
  write_row();
}

void ImpactRun::resume()
{
  const auto file = _ckpt->open_restart();
  const auto root = file.root();
  if (_coupling)
    _coupling->load(root);
  else
    _solver->load(root.group("dem"));
  const auto run = root.group("run");
  std::vector<double> tracked;
  run.read("tracked", tracked);
  if (tracked.size() != 3)
    run.fail("tracked", "not the 3 values of the run's tracking (file damaged?)");
  _max_depth = tracked[0];
  _touched = tracked[1] != 0.0;
  _peak_force = tracked[2];
  if (_track)
    _track->load(run.group("deflections"));
  _out["restarted_from_step"] = _solver->steps();
  if (_cfg.output_dir.empty())
    return;
  open_writer(&root);
  reopen_text(_csv, dir() / "history.csv", run.read_int("csv_bytes"));
}

void ImpactRun::save(const checkpoint::Group& root)
{
  if (_coupling)
    _coupling->save(root);
  else
    _solver->save(root.group("dem"));
  const auto run = root.group("run");
  run.write("tracked", std::vector<double>{_max_depth, _touched ? 1.0 : 0.0, _peak_force});
  if (_track)
    _track->save(run.group("deflections"));
  if (_writer)
    _writer->save(root.group("particles_xdmf"));
  if (_bar_writer)
    _bar_writer->save(root.group("bars_xdmf"));
  if (_csv.is_open())
    run.write_int("csv_bytes", flushed_size(_csv, dir() / "history.csv"));
}

void ImpactRun::write_frame()
{
  const auto bodies = pulsed() ? std::span<const RigidBody>() : std::span<const RigidBody>(&_solver->body(0), 1);
  _writer->write(_solver->time(), _p, _links, bodies);
  if (_bar_writer)
    _bar_writer->write(_solver->time(), _solver->bars());
  if (_coupling)
    _coupling->write_frame();
}

std::size_t ImpactRun::broken() const
{
  return _links.count(LinkState::broken_tension) + _links.count(LinkState::broken_shear);
}

void ImpactRun::write_row()
{
  if (!_csv.is_open())
    return;
  if (pulsed())
    return write_pulse_row();
  const RigidBody& b = _solver->body(0);
  const auto e = _solver->energy();
  const ShellsEnergy f = shells_energy();
  const V3 x = tip();
  _csv << std::setprecision(10) << _solver->time() << ',' << x[0] << ',' << x[1] << ',' << x[2] << ',' << -x[2]
       << ',' << b.v[0] << ',' << b.v[1] << ',' << b.v[2] << ',' << std::sqrt(dot(b.v, b.v)) << ','
       << path_velocity() << ',' << contact_force() << ',' << _solver->body_contacts(0).ids.size() << ','
       << broken() << ',' << _solver->removed().count << ',' << e.body_kinetic << ',' << target_kinetic(e) << ','
       << elastic_all(e) << ',' << dissipated(e) << ',' << e.removed << ',' << e.imbalance() + f.imbalance;
  end_row(f);
}

void ImpactRun::write_pulse_row()
{
  const auto e = _solver->energy();
  const ShellsEnergy f = shells_energy();
  _csv << std::setprecision(10) << _solver->time() << ',' << _s.pulse.force(_solver->time()) << ','
       << e.external_work << ',' << broken() << ',' << _solver->removed().count << ',' << target_kinetic(e) << ','
       << elastic_all(e) << ',' << dissipated(e) << ',' << e.removed << ',' << e.imbalance() + f.imbalance;
  end_row(f);
}

void ImpactRun::end_row(const ShellsEnergy& f)
{
  if (_coupling)
    _csv << ',' << f.kinetic << ',' << f.strain << ',' << f.multiplier_work << ',' << _residual << ','
         << _coupling->max_deflection();
  _csv << ',' << support_reaction();
  for (double w : point_deflections())
    _csv << ',' << w;
  _csv << '\n' << std::flush; // whole rows, as far as the frames, if the run is killed
}

ShellsEnergy ImpactRun::shells_energy() const { return _coupling ? _coupling->energy() : ShellsEnergy{}; }

double ImpactRun::imbalance() const { return _solver->energy().imbalance() + shells_energy().imbalance; }

void ImpactRun::print_header() const
{
  if (_cfg.quiet)
    return;
  const Material& m = _s.material.material;
  std::cout << "# concrete: " << _s.material.file << ": E " << m.youngs_modulus << " Pa, T " << m.tensile
            << " Pa, C0 " << m.cohesion << " Pa, rate effect " << (m.rate_fc > 0 ? fmt(m.rate_fc) + " Pa" : "off")
            << "\n# " << _p.size() << " spheres (" << fmt(_out["spheres_across_diameter"].get<double>(), 3)
            << " across the projectile), " << _links.size() << " links (lambda " << fmt(_lambda) << "), "
            << (_s.target.supports == "frame" ? "on a rigid frame " + fmt(_s.target.support_width) + " m wide"
                                              : std::to_string(_supported) + " held")
            << "\n";
  if (bars())
    std::cout << "# reinforcement: " << _out["reinforcement"]["bars"] << " bars of " << _s.reinforcement.bar_diameter
              << " m" << (_s.reinforcement.embedded ? " (embedded)" : "") << ", " << _out["reinforcement"]["elements"]
              << " elements, " << _bonds << " bonds; f_y " << _s.reinforcement.steel.yield
              << " Pa, bond tau_max " << _s.reinforcement.bond.tau_max << " Pa\n";
  if (pulsed())
  {
    std::cout << "# pulse: " << fmt(_s.pulse.peak_force) << " N half sine over " << fmt(_s.pulse.duration) << " s on "
              << _loaded.size() << " spheres; dt " << fmt(_dt) << " s (critical " << fmt(_dt_crit) << "), "
              << _nsteps << " steps (" << fmt(_duration) << " s)\n"
              << "      time [s]   load [N]  max |w| [m]  broken  imbalance/work\n";
    return;
  }
  std::cout << "# projectile " << fmt(_body.mass) << " kg at " << _s.projectile.velocity
            << " m/s (" << fmt(_ke0) << " J); dt " << fmt(_dt) << " s (critical " << fmt(_dt_crit) << "), up to "
            << _nsteps << " steps (" << fmt(_duration) << " s)\n"
            << "      time [s]  speed [m/s]  depth [m]  force [N]  broken  removed  imbalance/KE0\n";
}

void ImpactRun::progress() const
{
  if (pulsed())
  {
    double w = 0.0;
    for (double x : point_deflections())
      w = std::max(w, std::abs(x));
    if (_coupling)
      w = std::max(w, _coupling->max_deflection());
    // the share once the load has done some work: over its first steps the
    // work is too small a scale (a twentieth of the pulse)
    const double work = std::abs(_solver->energy().external_work);
    const bool started = _solver->time() >= 0.05 * _s.pulse.duration && work > 0.0;
    std::cout << std::setw(14) << fmt(_solver->time()) << std::setw(11) << fmt(_s.pulse.force(_solver->time()), 3)
              << std::setw(13) << fmt(w, 3) << std::setw(8) << broken() << std::setw(16)
              << (started ? fmt(imbalance() / work, 3) : std::string("-")) << std::endl;
    return;
  }
  std::cout << std::setw(14) << fmt(_solver->time()) << std::setw(13) << fmt(path_velocity()) << std::setw(11)
            << fmt(-tip()[2]) << std::setw(11) << fmt(contact_force(), 3) << std::setw(8) << broken()
            << std::setw(9) << _solver->removed().count << std::setw(15) << fmt(imbalance() / _ke0, 3)
            << std::endl;
}

Outcome ImpactRun::outcome()
{
  if (pulsed())
    return Outcome::running; // to the run's duration
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

void ImpactRun::loop()
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
  if (_coupling) // the steps whose state is read project their velocities
    h.step = [this, frame_every](std::int64_t k)
    { _residual = _coupling->step(k % _history_every == 0 || k % frame_every == 0 || k == _nsteps); };
  h.finished = [this](std::int64_t)
  {
    _outcome = outcome();
    if (_outcome != Outcome::running && _coupling)
      _coupling->observe(); // the last step's state is read
    return _outcome != Outcome::running;
  };
  if (_track)
    h.after_step = [this](std::int64_t) { _track->add(_solver->time(), point_deflections()); };
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
    if (_coupling)
      _coupling->close_output();
  }
}

void ImpactRun::report_pulse()
{
  _out["outcome"] = outcome_name(_outcome);
  _out["perforated"] = false;
  const auto e = _solver->energy();
  const ShellsEnergy f = shells_energy();
  const double unbooked = e.imbalance() + f.imbalance;
  // as history.csv's columns: the bars' terms with the spheres'
  _out["energy"] = {{"load_work_j", e.external_work},
                    {"target_kinetic_j", target_kinetic(e)},
                    {"elastic_j", elastic_all(e)},
                    {"dissipated_j", dissipated(e)},
                    {"support_work_j", e.prescribed_work},
                    {"imbalance_j", unbooked},
                    {"imbalance_share", e.external_work != 0.0 ? unbooked / std::abs(e.external_work) : 0.0}};
  if (_coupling)
  {
    auto& j = _out["energy"];
    j["shell_kinetic_j"] = f.kinetic;
    j["shell_strain_j"] = f.strain;
    j["multiplier_work_j"] = f.multiplier_work;
  }
}

void ImpactRun::report()
{
  if (pulsed())
    report_pulse();
  else
    report_projectile();
  if (_track)
    _out["deflection_points"] = _track->report();
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
  if (bars())
    report_bars();
  if (_coupling)
    _out["coupling"].update(_coupling->report());
  _out["peak_memory_mb"] = peak_memory_mb();
}

void ImpactRun::report_projectile()
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
}

void ImpactRun::report_bars()
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

void ImpactRun::measure_damage()
{
  const auto& gone = _solver->removed_flags();
  CraterInput in;
  in.x0 = _p.x0;
  in.r = _p.r;
  in.m = _coupling ? _masses : _p.m;
  in.detached.assign(_p.size(), 0);
  std::vector<int> lost(_p.size(), 0);
  for (std::size_t k = 0; k < _links.size(); ++k)
    if (_links.state[k] != LinkState::intact)
    {
      ++lost[_links.a[k]];
      ++lost[_links.b[k]];
    }
  if (_coupling)
    report_band_damage(lost);
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
        ejected += in.m[i];
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

void ImpactRun::report_band_damage(const std::vector<int>& lost)
{
  // the overlap's spheres: those whose energy weight 1 - eta is below 1
  // (1 in the DE-only core)
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < _p.size(); ++i)
    if (_p.weight[i] < 1.0 && _initial_links[i] > 0)
    {
      sum += static_cast<double>(lost[i]) / _initial_links[i];
      ++n;
    }
  _out["coupling"]["band_damage"] = n > 0 ? sum / static_cast<double>(n) : 0.0;
}

void ImpactRun::report_energy()
{
  const auto e = _solver->energy();
  const ShellsEnergy f = shells_energy();
  const double unbooked = e.imbalance() + f.imbalance; // the budget's error
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
                    {"imbalance_j", unbooked},
                    {"imbalance_share", unbooked / _ke0}};
  if (_coupling)
  {
    auto& j = _out["energy"];
    j["shell_kinetic_j"] = f.kinetic;
    j["shell_strain_j"] = f.strain;
    j["multiplier_work_j"] = f.multiplier_work;
  }
}

} // namespace impl

nlohmann::json run_impact(const ImpactConfig& cfg)
{
  Stopwatch clock;
  if (cfg.scenario.shells.shells_only() && !cfg.shells_only)
    throw std::runtime_error("shells.model = \"fe\": this program was built without the shells (use build/bin/impact)");
  auto out = cfg.scenario.shells.shells_only() ? cfg.shells_only(cfg) : impl::ImpactRun(cfg).run();
  out["wall_s"] = clock.seconds();
  return out;
}

} // namespace dembridge::demo
