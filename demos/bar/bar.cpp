#include "bar.h"
#include "support.h"
#include "time_loop.h"

#include "dembridge/bridge/coupled.h"
#include "dembridge/dem/material_file.h"
#include "dembridge/dem/output.h"
#include "dembridge/dem/packing.h"
#include "dembridge/dem/skin.h"
#include "dembridge/shell/analytic.h"
#include "dembridge/shell/mesh.h"
#include "dembridge/shell/output.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <numbers>
#include <numeric>
#include <sstream>

namespace dembridge::demo
{
namespace
{

struct Probe
{
  std::string key;
  double x = 0.0;
  std::vector<double> values;
};

/// FE displacement along the bar: the mean of a dof component over each
/// column of nodes (same x), linearly interpolated between columns.
class FeColumns
{
public:
  FeColumns(std::span<const double> x, int bs, int comp) : _bs(bs), _comp(comp)
  {
    std::map<long, std::vector<std::int32_t>> cols;
    for (std::size_t k = 0; k < x.size() / 3; ++k)
      cols[std::lround(x[3 * k] * 1e9)].push_back(static_cast<std::int32_t>(k));
    for (auto& [key, nodes] : cols)
    {
      _x.push_back(key * 1e-9);
      _nodes.push_back(nodes);
    }
  }
  double at(std::span<const double> u, double xp) const
  {
    auto mean = [&](std::size_t c) {
      double s = 0.0;
      for (auto k : _nodes[c])
        s += u[_bs * k + _comp];
      return s / _nodes[c].size();
    };
    std::size_t c = 0;
    while (c + 2 < _x.size() && _x[c + 1] < xp)
      ++c;
    const double t = std::clamp((xp - _x[c]) / (_x[c + 1] - _x[c]), 0.0, 1.0);
    return (1.0 - t) * mean(c) + t * mean(c + 1);
  }
  const std::vector<double>& x() const { return _x; }
  double xmax() const { return _x.back(); }

private:
  int _bs, _comp;
  std::vector<double> _x;
  std::vector<std::vector<std::int32_t>> _nodes;
};

/// Mean displacement component of a set of particles.
double mean_displacement(const dem::Particles& p, std::span<const std::int32_t> ids, int comp)
{
  double s = 0.0;
  for (auto i : ids)
    s += p.x[3 * i + comp] - p.x0[3 * i + comp];
  return s / ids.size();
}

std::vector<std::int32_t> particles_near(const dem::Particles& p, double xp, double half)
{
  std::vector<std::int32_t> ids;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (std::abs(p.x0[3 * i] - xp) < half)
      ids.push_back(static_cast<std::int32_t>(i));
  if (ids.empty())
    throw std::runtime_error("no sphere within " + std::to_string(half) + " m of the probe x = "
                             + std::to_string(xp) + " m");
  return ids;
}

double smooth_ramp(double t, double T) { return t >= T ? 1.0 : 0.5 * (1.0 - std::cos(std::numbers::pi * t / T)); }
} // namespace

namespace
{
/// One case of the bar, in the phases of a run: set-up (parameters,
/// regions, the models, solvers, conditions, probes, output), the time
/// loop, and the summary. Members are declared in the order they are built:
/// the coupler last among the models, as it holds the weighted state of the
/// shell model, the particles and the links until it is destroyed.
class BarRun
{
public:
  explicit BarRun(const BarConfig& c) : _c(c) {}

  nlohmann::json run()
  {
    check_config(_c);
    if (_c.restart)
      _ckpt = std::make_unique<Checkpointer>(*_c.restart, _c.output);
    resolve_parameters();
    lay_out_regions();
    build_fe();
    build_de();
    build_solvers();
    apply_conditions();
    set_up_probes();
    start_or_resume(_ckpt.get(), [this] { resume(); }, [this] { open_output(); });
    march();
    return summary();
  }

private:
  // ---- set-up ---------------------------------------------------------------
  /// The same concrete on both sides; loads, times and damping resolved
  /// from the options' "0 = automatic".
  void resolve_parameters()
  {
    _tension = _c.load == "tension";
    _dynamic = _c.regime == "dynamic";
    _use_fe = _c.model != "de";
    _use_de = _c.model != "fe";
    _comp = _tension ? 0 : 2;
    _mf = dem::read_material(_c.material);
    _mat = _mf.material;
    _mat.tensile = _mat.cohesion = 1e12; // linear elastic validation
    _sm.youngs_modulus = _c.fe_youngs_modulus > 0.0
                             ? _c.fe_youngs_modulus
                             : _mf.macroscopic.value("youngs_modulus_pa", _mat.youngs_modulus);
    _sm.poisson_ratio = _mf.macroscopic.value("poisson_ratio", _mat.poisson_ratio);
    _sm.density = _mat.density;
    _sm.thickness = _c.width;
    _E = _sm.youngs_modulus;
    _nu = _sm.poisson_ratio;
    _rho = _sm.density;
    _f1 = bar_first_frequency(_c, _E, _nu, _rho);
    const double T1 = 1.0 / _f1;
    _force = _c.static_force != 0.0 ? _c.static_force : (_tension ? 1e5 : 2e4);
    _d0 = _c.end_displacement != 0.0 ? _c.end_displacement : (_tension ? 5e-5 : 2e-4);
    _ramp = _c.ramp_time > 0.0 ? _c.ramp_time : T1;
    _end_time = _c.end_time > 0.0 ? _c.end_time : (_dynamic ? _ramp + 4.0 * T1 : 3.0 * T1);
    _damping = _dynamic ? 0.0 : (_c.damping >= 0.0 ? _c.damping : 4.0 * std::numbers::pi * _f1);
    if (_dynamic && _end_time < _ramp + 1.5 * T1)
      refuse_value("end-time [s]", _end_time,
          "at least ramp-time + 1.5 first periods (" + std::to_string(_ramp + 1.5 * T1)
              + " s) to measure a frequency");
  }

  /// Where the shells end and the spheres start (the overlap: whole FE layers).
  void lay_out_regions()
  {
    const double L = _c.length;
    _rmax = 2.0 * _c.mean_radius * _c.radius_ratio / (1.0 + _c.radius_ratio);
    _fe_end = L;
    _de_start = 0.0;
    if (_c.model == "coupled")
    {
      const double k = _c.overlap_start / _c.fe_size;
      if (std::abs(k - std::round(k)) > 1e-6)
        refuse_value("overlap-start [m]", _c.overlap_start,
            "a multiple of fe-size (" + std::to_string(_c.fe_size) + " m), so the overlap is whole FE layers");
      _de_start = _c.overlap_start;
      _fe_end = _de_start + _c.overlap_layers * _c.fe_size;
      if (!(_de_start > 0.0 && _fe_end < L - 2.0 * _rmax))
        refuse_value("overlap end [m]", _fe_end, "overlap inside (0, length - 2 Rmax): check overlap-start and overlap-layers");
    }
    if (_use_fe)
    {
      const double k = _fe_end / _c.fe_size, kw = _c.width / _c.fe_size;
      if (std::abs(k - std::round(k)) > 1e-6 || std::abs(kw - std::round(kw)) > 1e-6)
        refuse_value("fe-size [m]", _c.fe_size, "a divisor of the FE region's length and of the width");
    }
    // The DE bar's packing starts one mean radius behind the clamp plane
    // x = 0: the held layer (centres within Rmax of the packing's face) is
    // then centred on it and the bar is free from x = 0 to L, as the shells
    // are (a packing from x = 0 would hold a layer centred near x = R: a span
    // 1.2 % shorter and a first bending frequency 2.4 % higher at R = 1 cm).
    _de_from = _c.model == "de" ? -_c.mean_radius : _de_start;
  }

  void build_fe()
  {
    if (!_use_fe)
      return;
    auto mesh = shell::create_shell_rectangle(MPI_COMM_WORLD, _fe_end, _c.width,
                                              static_cast<int>(std::round(_fe_end / _c.fe_size)),
                                              static_cast<int>(std::round(_c.width / _c.fe_size)),
                                              shell::parse_cell(_c.cell));
    _fe = std::make_unique<shell::FEModel>(mesh, _sm);
    _cols = std::make_unique<FeColumns>(_fe->node_coordinates(), _fe->block_size(), _comp);
  }

  void build_de()
  {
    if (!_use_de)
      return;
    const double h = _c.width;
    dem::PackingOptions po;
    po.mean_radius = _c.mean_radius;
    po.radius_ratio = _c.radius_ratio;
    po.seed = _c.seed;
    const auto region = dem::box_region({_de_from, 0.0, -0.5 * h}, {_c.length, _c.width, 0.5 * h});
    // the dem module's errors name the region; the user's options are these
    std::ostringstream mean_radius;
    mean_radius << _c.mean_radius;
    const std::string opts = "--mean-radius " + mean_radius.str() + " m in the DE part of the bar (--length, "
                             "--width, --overlap-start)";
    const auto pk = with_context(opts, [&] { return dem::generate_packing(region, po); });
    double solid = 0.0;
    for (double r : pk.r)
      solid += 4.0 / 3.0 * std::numbers::pi * r * r * r;
    _p = dem::make_particles(pk.x, pk.r, _mat.density, solid / region.volume);
    _links = dem::create_links(
        _p, with_context(opts, [&] { return dem::lambda_for_bulk_links(region, _p.x, _p.r, _mf.links_per_sphere); }),
        _mat);
    _floppy = dem::floppy_spheres(_p, _links).size();
    if (_c.skin_compensation)
    {
      // the faces' skin, two Rmax deep, stiffened to the bulk's links per
      // sphere: without it the bar is 5.9-7.9 % too compliant in bending
      // for the E it shows in tension (docs/method.md, "Skin compensation")
      const double rmx = *std::max_element(_p.r.begin(), _p.r.end());
      _skin = dem::compensate_skin(_p, _links, region, 2.0 * rmx);
    }
  }

  void build_solvers()
  {
    if (_c.model == "coupled")
    {
      bridge::CouplingOptions o;
      o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, _fe_end, _de_start};
      o.safety = _c.safety;
      o.damping_fe = o.damping_de = _damping;
      _coupled = std::make_unique<bridge::CoupledSolver>(*_fe, _p, _links, _mat, o);
      _fes = &_coupled->fe();
      _des = &_coupled->de();
      _dt = _coupled->dt();
      _steps_info = {{"dt_coupled_s", _coupled->dt_coupled()}, {"dt_fe_alone_s", _coupled->dt_fe()},
                     {"dt_de_alone_s", _coupled->dt_de()}, {"constrained_particles", _coupled->constrained()},
                     {"placed_by_nearest_rule", _coupled->coupling().outside()}};
    }
    else if (_c.model == "fe")
    {
      const auto m = _fe->lumped_mass();
      const double dtc = _fe->critical_time_step(m);
      _dt = _c.safety * dtc;
      _fe_alone = std::make_unique<shell::ExplicitSolver>(m, _fe->internal_force_fn(), _dt, _damping);
      _fes = _fe_alone.get();
      _steps_info = {{"dt_critical_s", dtc}};
    }
    else
    {
      const double dtc = dem::particle_critical_time_step(_p, _links);
      _dt = _c.safety * dtc;
      _de_alone = std::make_unique<dem::DemSolver>(_p, _links, _mat, _dt, _damping, 0.5 * _c.mean_radius);
      _des = _de_alone.get();
      _steps_info = {{"dt_critical_s", dtc}};
    }
  }

  /// Support at x = 0 and the load at x = length, then the initial state.
  void apply_conditions()
  {
    const double L = _c.length;
    const int bs = _use_fe ? _fe->block_size() : 0;
    std::vector<int> all(6);
    std::iota(all.begin(), all.end(), 0);
    if (_use_fe)
    {
      const auto x = _fe->node_coordinates();
      _fes->add_motion({"support",
                        shell::node_dofs(shell::select_nodes(x, [&](const auto& q) { return q[0] < 1e-9; }, "end x = 0"), bs, all),
                        shell::MotionKind::fixed, {}});
      if (_c.model == "fe")
        _end_nodes = shell::select_nodes(x, [&](const auto& q) { return q[0] > L - 1e-9; }, "loaded end");
    }
    if (_use_de)
    {
      if (_c.model == "de")
      {
        const double held_to = _de_from + _rmax;
        _clamp_ids = dem::DemSolver::select(_p, [&](const auto& q) { return q[0] < held_to; }, "end x = 0");
        _des->add_motion({"support", _clamp_ids, dem::MotionKind::fixed, {true, true, true}, {}});
      }
      const double rmax = _rmax;
      _end_ids = dem::DemSolver::select(_p, [&](const auto& q) { return q[0] > L - rmax; }, "loaded end");
    }
    const std::array<bool, 3> comps{_tension, false, !_tension};
    const std::array<double, 3> dir{_tension ? 1.0 : 0.0, 0.0, _tension ? 0.0 : 1.0};
    const double d0 = _d0, ramp = _ramp, force = _force;
    auto d_of_t = [=](double t) { return d0 * smooth_ramp(t, ramp); };
    if (!_end_nodes.empty())
    {
      const std::vector<int> one{_comp};
      const auto dofs = shell::node_dofs(_end_nodes, bs, one);
      if (_dynamic)
        _fes->add_motion({"end", dofs, shell::MotionKind::displacement, d_of_t});
      else
        _fes->add_load({"end", dofs, _fe->boundary_load_weights(_end_nodes), [=](double) { return force; }});
    }
    if (!_end_ids.empty())
    {
      // Both through a rigid end plate: the end spheres move as one along the
      // load (an equal share on each would push the few loosely bonded ones
      // far out and spoil the mean end displacement). In bending the plate
      // is hinged at its centroid, free to rotate as the shell's loaded edge
      // is: a plate that only translates clamps the rotation of the end
      // layer (about 1 cm deep in x) and takes 2 % of the clamp's moment. In
      // tension it only translates: the paper's end displacement, uniform
      // over the face.
      const bool hinged = !_tension;
      if (_dynamic)
        _des->add_motion({"end", _end_ids, dem::MotionKind::displacement, comps, d_of_t, hinged});
      else
      {
        const double share = force / _end_ids.size();
        _des->add_force({"end", _end_ids, dir, [=](double) { return share; }, true, hinged});
      }
    }
    if (_coupled)
      _coupled->start(std::vector<double>(_fe->num_dofs(), 0.0), std::vector<double>(_fe->num_dofs(), 0.0));
    else if (_fes)
      _fes->set_state(std::vector<double>(_fe->num_dofs(), 0.0), std::vector<double>(_fe->num_dofs(), 0.0));
    else
      _des->start();
  }

  /// Probes: in the DE where there are spheres, else on the shell.
  void set_up_probes()
  {
    _probes = {{"probe_0_75", _c.probe_de, {}},
               {"probe_0_4351", _c.model == "fe" ? _c.probe_overlap_fe : _c.probe_overlap, {}}};
    _probe_ids.assign(_probes.size(), {});
    for (std::size_t k = 0; k < _probes.size(); ++k)
      if (_use_de && _probes[k].x > _de_start)
        _probe_ids[k] = particles_near(_p, _probes[k].x, _c.mean_radius);
      else if (!_use_fe || _probes[k].x > _fe_end)
        throw std::runtime_error("probe x = " + std::to_string(_probes[k].x) + " m lies in no model region");
  }

  void open_output()
  {
    if (_c.output.empty())
      return;
    const std::filesystem::path dir(_c.output);
    std::filesystem::create_directories(dir);
    if (_use_fe)
      _shell_out = std::make_unique<shell::XdmfWriter>(*_fe, dir / "shell.xdmf");
    if (_use_de)
      _part_out = std::make_unique<dem::ParticleWriter>(dir / "particles.xdmf", _links, _p.size(), false);
    _csv.open(dir / "history.csv");
    _csv << "t_s,probe_0_75_m,probe_0_4351_m,end_m\n";
  }

  /// Continues from the checkpoint: the end released if it was, the
  /// solvers' state, the probe histories, the output files up to the
  /// checkpoint.
  void resume()
  {
    const auto file = _ckpt->open_restart();
    const auto root = file.root();
    const auto run = root.group("run");
    const bool released = run.read_int("released") != 0;
    if (_dynamic && released)
      release(); // the conditions as they were at the checkpoint
    _released = released;
    if (_coupled)
      _coupled->load(root.group("coupled"));
    else if (_fe_alone)
      _fe_alone->load(root.group("shell"));
    else
      _de_alone->load(root.group("dem"));
    run.read("t_after", _t_after);
    _after.assign(_probes.size(), {});
    for (std::size_t k = 0; k < _probes.size(); ++k)
      run.read("after_" + std::to_string(k), _after[k]);
    _restarted_from = steps_done();
    if (_c.output.empty())
      return;
    const std::filesystem::path dir(_c.output);
    if (_use_fe)
      _shell_out = std::make_unique<shell::XdmfWriter>(*_fe, dir / "shell.xdmf", root.group("shell_xdmf"));
    if (_use_de)
      _part_out = std::make_unique<dem::ParticleWriter>(dir / "particles.xdmf", _links, _p.size(), false,
                                                        root.group("particles_xdmf"));
    reopen_text(_csv, dir / "history.csv", run.read_int("csv_bytes"));
  }

  /// The checkpoint: the solvers, the release, the probe histories, the
  /// output files' extent.
  void save(const checkpoint::Group& root)
  {
    if (_coupled)
      _coupled->save(root.group("coupled"));
    else if (_fe_alone)
      _fe_alone->save(root.group("shell"));
    else
      _de_alone->save(root.group("dem"));
    const auto run = root.group("run");
    run.write_int("released", _released ? 1 : 0);
    run.write("t_after", _t_after);
    for (std::size_t k = 0; k < _after.size(); ++k)
      run.write("after_" + std::to_string(k), _after[k]);
    if (_shell_out)
      _shell_out->save(root.group("shell_xdmf"));
    if (_part_out)
      _part_out->save(root.group("particles_xdmf"));
    if (_csv.is_open())
      run.write_int("csv_bytes", flushed_size(_csv, std::filesystem::path(_c.output) / "history.csv"));
  }

  // ---- run ------------------------------------------------------------------
  std::int64_t steps_done() const { return _fes ? _fes->steps() : _des->steps(); }
  double probe_value(std::size_t k) const
  {
    return _probe_ids[k].empty() ? _cols->at(_fes->u(), _probes[k].x)
                                 : mean_displacement(_p, _probe_ids[k], _comp);
  }
  double end_value() const
  {
    return _end_ids.empty() ? _cols->at(_fes->u(), _c.length) : mean_displacement(_p, _end_ids, _comp);
  }
  void write_frame(double t)
  {
    if (_shell_out)
      _shell_out->write(t, _fes->u(), _fes->v());
    if (_part_out)
      _part_out->write(t, _p, _links);
  }
  /// The ramp reached d0: the end is let go.
  void release()
  {
    if (_fes && !_end_nodes.empty())
      _fes->remove_motion("end");
    if (_des && !_end_ids.empty())
      _des->remove_motion("end");
    _released = true;
  }

  void march()
  {
    _nsteps = static_cast<std::int64_t>(std::ceil(_end_time / _dt));
    const std::int64_t nsteps = _nsteps;
    if (!_c.quiet)
      std::printf("# bar: %s model, %s, %s: %zu spheres, %zu shell nodes, dt %.4g s, %lld steps to %.4g s "
                  "(beam theory: first frequency %.5g Hz)\n",
                  _c.model.c_str(), _c.load.c_str(), _c.regime.c_str(), _p.size(), _use_fe ? _fe->num_nodes() : 0,
                  _dt, static_cast<long long>(nsteps), _end_time, _f1);
    const std::int64_t every = std::max<std::int64_t>(1, nsteps / _c.frames);
    if (_restarted_from < 0) // a new run (a restarted one has its history)
    {
      _after.assign(_probes.size(), {});
      _released = !_dynamic;
      write_frame(0.0);
    }
    // the shared time loop (time_loop.h): up to 2000 CSV rows, the frames,
    // 10 progress lines, each also at the end
    const LoopPlan plan{.done = steps_done(),
                        .last = nsteps,
                        .rows = {std::max<std::int64_t>(1, nsteps / 2000)},
                        .frames = {every},
                        .prints = {std::max<std::int64_t>(1, nsteps / 10)},
                        .checkpoints = _ckpt.get()};
    double t = 0.0, v0 = 0.0, v1 = 0.0; // the step's time [s] and probe values [m]
    LoopHooks h;
    h.step = [&](std::int64_t k)
    {
      if (_coupled)
        _coupled->step(k % every == 0 || k == nsteps); // observed where frames are written
      else if (_fes)
      {
        const double s0 = _clock.seconds();
        _fes->step();
        _step_clock += _clock.seconds() - s0;
      }
      else
        _des->step();
      t = k * _dt;
    };
    h.time = [&] { return t; };
    h.after_step = [&](std::int64_t)
    {
      if (!_released && t >= _ramp)
        release();
      v0 = probe_value(0);
      v1 = probe_value(1);
      if (_dynamic && _released)
      {
        _t_after.push_back(t);
        _after[0].push_back(v0);
        _after[1].push_back(v1);
      }
    };
    if (_csv.is_open())
      h.row = [&](std::int64_t, bool)
      { _csv << t << ',' << v0 << ',' << v1 << ',' << end_value() << '\n' << std::flush; }; // whole rows if killed
    h.frame = [&](std::int64_t, bool) { write_frame(t); };
    if (!_c.quiet)
      h.progress = [&](std::int64_t k, bool)
      {
        std::printf("  t %.4e s  step %lld/%lld  probe 0.75: %.4e m  probe %.4g: %.4e m  end %.4e m  (%.1f s)\n", t,
                    static_cast<long long>(k), static_cast<long long>(nsteps), v0, _probes[1].x, v1, end_value(),
                    _clock.seconds());
      };
    h.save = [this](const checkpoint::Group& g) { save(g); };
    run_time_loop(plan, h);
  }

  // ---- summary --------------------------------------------------------------
  nlohmann::json summary()
  {
    nlohmann::json out = {{"model", _c.model},
                          {"load", _c.load},
                          {"regime", _c.regime},
                          {"particles", _p.size()},
                          {"links", _links.size()},
                          {"floppy_spheres", _floppy},
                          {"shell_nodes", _use_fe ? _fe->num_nodes() : 0},
                          {"youngs_modulus_pa", _E},
                          {"poisson_ratio", _nu},
                          {"density_kg_m3", _rho},
                          {"beam_theory_frequency_hz", _f1},
                          {"dt_s", _dt},
                          {"steps", _nsteps},
                          {"end_time_s", _end_time},
                          {"time_step", _steps_info}};
    if (_use_de)
      out["skin_compensation"] = {{"on", _c.skin_compensation},
                                  {"spheres", _skin.spheres},
                                  {"links", _skin.links},
                                  {"bulk_links_per_sphere", _skin.bulk_links},
                                  {"max_sphere_factor", _skin.max_factor},
                                  {"mean_link_factor", _skin.mean_link_factor}};
    for (std::size_t k = 0; k < _probes.size(); ++k)
    {
      nlohmann::json pj = {{"x_m", _probes[k].x}, {"final_displacement_m", probe_value(k)}};
      if (_dynamic)
      {
        pj["first_frequency_hz"] = crossing_frequency(_t_after, _after[k]);
        pj["amplitude_m"] = amplitude(_after[k]);
      }
      out[_probes[k].key] = pj;
    }
    if (_dynamic)
    {
      out["end_displacement_m"] = _d0;
      out["ramp_time_s"] = _ramp;
    }
    else
      measure_statics(out);
    timings(out);
    if (_restarted_from >= 0)
      out["restarted_from_step"] = _restarted_from;
    out["wall_s"] = _clock.seconds();
    return out;
  }

  /// Beam theory along the bar, over the span from the support to the load:
  /// a shell support or load acts at its edge (x = 0, L), a held or loaded
  /// set of spheres at the mean x of their centres (the material between a
  /// face and the first centres has no links: it is not modelled).
  void measure_statics(nlohmann::json& out)
  {
    const double L = _c.length, E = _E, nu = _nu, force = _force;
    const bool tension = _tension;
    const shell::analytic::BeamSection sec{_c.width, _c.width};
    auto mean_x = [&](const std::vector<std::int32_t>& ids) {
      double s = 0.0;
      for (auto i : ids)
        s += _p.x0[3 * i];
      return s / ids.size();
    };
    const double x_support = _c.model == "de" ? mean_x(_clamp_ids) : 0.0;
    const double x_load = _end_ids.empty() ? L : mean_x(_end_ids), span = x_load - x_support;
    const double G = E / (2.0 * (1.0 + nu)), A = sec.area(), I = sec.second_moment(), kappa = 5.0 / 6.0;
    auto theory = [&](double x) {
      const double s = std::clamp(x - x_support, 0.0, span);
      return tension ? force * s / (E * A)
                     : force / (E * I) * (span * s * s / 2.0 - s * s * s / 6.0) + force * s / (kappa * G * A);
    };
    const double uend = end_value(), uref = theory(x_load);
    out["beam_span_m"] = span;
    out["static_force_n"] = force;
    out["static_end_displacement_m"] = uend;
    out["reference_end_displacement_m"] = uref;
    out["static_relative_error"] = uend / uref - 1.0;
    out["damping_per_s"] = _damping;
    // shape: FE columns, and 2-radius slabs of spheres
    std::vector<std::array<double, 3>> rows; // x, u, source (0 FE, 1 DE)
    if (_use_fe)
      for (double x : _cols->x())
        rows.push_back({x, _cols->at(_fes->u(), x), 0.0});
    if (_use_de)
      for (double x = _de_start + _c.mean_radius; x < L; x += 2.0 * _c.mean_radius)
      {
        const auto ids = particles_near(_p, x, _c.mean_radius);
        rows.push_back({x, mean_displacement(_p, ids, _comp), 1.0});
      }
    double worst = 0.0;
    for (const auto& r : rows)
      worst = std::max(worst, std::abs(r[1] - theory(r[0])) / std::abs(uref));
    out["shape_max_deviation_rel"] = worst;
    if (tension && _use_de)
    {
      // strain on the middle half of the DE region, by least squares
      double sx = 0, su = 0, sxx = 0, sxu = 0, n = 0;
      for (const auto& r : rows)
        if (r[2] == 1.0 && r[0] > _de_start + 0.25 * (L - _de_start) && r[0] < _de_start + 0.75 * (L - _de_start))
        {
          sx += r[0], su += r[1], sxx += r[0] * r[0], sxu += r[0] * r[1], n += 1;
        }
      const double slope = (n * sxu - sx * su) / (n * sxx - sx * sx);
      out["measured_youngs_modulus_pa"] = force / (sec.area() * slope);
    }
    if (!_c.output.empty())
    {
      std::ostringstream s;
      s << "x_m,displacement_m,beam_theory_m,source\n";
      for (const auto& r : rows)
        s << r[0] << ',' << r[1] << ',' << theory(r[0]) << ',' << (r[2] == 0.0 ? "fe" : "de") << '\n';
      write_text(std::filesystem::path(_c.output) / "shape.csv", s.str());
    }
  }

  void timings(nlohmann::json& out) const
  {
    if (_coupled)
    {
      const auto& tm = _coupled->timings();
      out["step_time_s"] = {{"fe", tm.fe}, {"de", tm.de}, {"multipliers", tm.multipliers}};
    }
    else if (_des)
      out["step_time_s"] = {{"de", _de_alone->timings().forces + _de_alone->timings().neighbours
                                       + _de_alone->timings().integration}};
    else
      out["step_time_s"] = {{"fe", _step_clock}};
    if (_des)
      out["de_step_split_s"] = {{"forces", _des->timings().forces},
                                {"neighbours", _des->timings().neighbours},
                                {"integration", _des->timings().integration}};
  }

  // ---- state ----------------------------------------------------------------
  const BarConfig& _c;
  Stopwatch _clock;
  // resolved parameters
  bool _tension = false, _dynamic = false, _use_fe = false, _use_de = false;
  int _comp = 0;
  dem::MaterialFile _mf;
  dem::Material _mat;
  shell::Material _sm;
  double _E = 0.0, _nu = 0.0, _rho = 0.0, _f1 = 0.0, _force = 0.0, _d0 = 0.0, _ramp = 0.0,
         _end_time = 0.0, _damping = 0.0;
  // regions
  double _rmax = 0.0, _fe_end = 0.0, _de_start = 0.0, _de_from = 0.0;
  // models (the coupler after them: it gives their state back when destroyed)
  std::unique_ptr<shell::FEModel> _fe;
  std::unique_ptr<FeColumns> _cols;
  dem::Particles _p;
  dem::Links _links;
  dem::SkinCompensation _skin;
  std::size_t _floppy = 0; // spheres free to turn (dem::floppy_spheres)
  std::unique_ptr<shell::ExplicitSolver> _fe_alone;
  std::unique_ptr<bridge::CoupledSolver> _coupled;
  std::unique_ptr<dem::DemSolver> _de_alone;
  shell::ExplicitSolver* _fes = nullptr;
  dem::DemSolver* _des = nullptr;
  double _dt = 0.0;
  nlohmann::json _steps_info;
  // conditions and probes
  std::vector<std::int32_t> _end_nodes, _end_ids, _clamp_ids;
  std::vector<Probe> _probes;
  std::vector<std::vector<std::int32_t>> _probe_ids;
  // output
  std::unique_ptr<shell::XdmfWriter> _shell_out;
  std::unique_ptr<dem::ParticleWriter> _part_out;
  std::ofstream _csv;
  // the run
  std::int64_t _nsteps = 0;
  bool _released = false;
  double _step_clock = 0.0;
  std::vector<double> _t_after;
  std::vector<std::vector<double>> _after;
  std::unique_ptr<Checkpointer> _ckpt;
  std::int64_t _restarted_from = -1; // the step a restarted run continued from
};
} // namespace

nlohmann::json run_bar(const BarConfig& c) { return BarRun(c).run(); }

} // namespace dembridge::demo
