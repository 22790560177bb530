// The slab all in shells under the pulse (impact --model fe; coupled_slab.h,
// run_shell_slab): the coupled slab's shells without the hole, the same
// section, edges and deflection points, loaded by the scenario's pulse on
// the nodes of its disc; the shared time loop, history.csv, shell.xdmf and
// the summary. The elastic reference of the other two models
// (docs/impact.md, "Elastic checks").
#include "coupled_slab.h"
#include "deflection.h"
#include "impact.h"

#include "support.h"
#include "time_loop.h"

#include "dembridge/shell/explicit.h"
#include "dembridge/shell/gmsh.h"
#include "dembridge/shell/output.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace dembridge::demo
{
namespace
{

class ShellSlabRun
{
public:
  explicit ShellSlabRun(const ImpactConfig& cfg) : _cfg(cfg), _s(cfg.scenario) {}

  nlohmann::json run()
  {
    if (_cfg.restart)
      _ckpt = std::make_unique<Checkpointer>(*_cfg.restart, _cfg.output_dir);
    build();
    describe();
    start_or_resume(_ckpt.get(), [this] { resume(); }, [this] { open_output(); });
    if (!_cfg.quiet)
      std::cout << "# " << _fe->num_nodes() << " shell nodes, " << _fe->num_cells() << " cells; pulse "
                << _s.pulse.peak_force << " N over " << _s.pulse.duration << " s on " << _load_nodes
                << " nodes; dt " << _dt << " s (critical " << _dt_crit << "), " << _nsteps << " steps\n"
                << "      time [s]   load [N]  max |w| [m]\n";
    loop();
    report();
    return _out;
  }

private:
  void build()
  {
    Stopwatch clock;
    _spec = slab_plan(_s);
    shell::SlabOutline o;
    o.lx = _spec.size[0];
    o.ly = _spec.size[1];
    o.size = _spec.element_size;
    o.outer_size = _spec.outer_element_size;
    o.centre = {_spec.centre[0] + 0.5 * _spec.size[0], _spec.centre[1] + 0.5 * _spec.size[1]};
    shell::Placement pl;
    pl.origin = {-0.5 * _spec.size[0], -0.5 * _spec.size[1], -0.5 * _spec.thickness};
    _fe = std::make_unique<shell::FEModel>(shell::mesh_outline(MPI_COMM_WORLD, o, _spec.cell, pl), shell_material(_s));
    if (_s.reinforcement.layers > 0)
      _fe->set_reinforcement(shell_steel(_s, _fe->nodal_normals()[2] >= 0.0 ? 1.0 : -1.0));
    _frame_nodes = bridge::slab_frame_springs(*_fe, _spec, _fe->material().youngs_modulus); // the step counts them
    const auto mass = _fe->lumped_mass();
    _dt_crit = _fe->critical_time_step(mass);
    const RunSpec& run = _s.run;
    if (run.dt > _dt_crit)
      throw std::runtime_error("run.dt_s = " + number_text(run.dt) + " s is above the shells' critical time step "
                               + number_text(_dt_crit) + " s: give a smaller one, or 0 for safety_factor x critical");
    _dt = run.dt > 0.0 ? run.dt : run.safety * _dt_crit;
    _solver = std::make_unique<shell::ExplicitSolver>(mass, _fe->internal_force_fn(), _dt, run.damping);
    _supports = bridge::slab_support_dofs(*_fe, _spec);
    if (!_supports.empty())
      _solver->add_motion({"supports", _supports, shell::MotionKind::fixed, {}});
    _solver->add_load(pulse_load());
    _points = std::make_unique<ShellPoints>(*_fe, _s);
    const std::vector<double> zero(_fe->num_dofs(), 0.0);
    _solver->set_state(zero, zero);
    _nsteps = static_cast<std::int64_t>(std::ceil(run.duration / _dt));
    _history_every = run.history_every > 0 ? run.history_every : std::max<std::int64_t>(1, _nsteps / 250);
    if (!_s.shells.deflection_points.empty())
      _track = std::make_unique<DeflectionTrack>(_s.shells.deflection_points, _s.pulse.duration);
    _setup_s = clock.seconds();
  }

  /// The pulse on the nodes within its disc, each its share of the disc's
  /// tributary area, along -z.
  shell::NodalLoad pulse_load()
  {
    const PulseSpec& pu = _s.pulse;
    const double radius = pu.radius > 0.0 ? pu.radius : 0.5 * _s.projectile.diameter;
    const auto x = _fe->node_coordinates();
    const auto area = _fe->nodal_measure();
    const auto& aim = _s.projectile.aim;
    shell::NodalLoad l{"pulse", {}, {}, [pu](double t) { return pu.force(t); }};
    double total = 0.0;
    for (std::size_t k = 0; k < _fe->num_nodes(); ++k)
      if (std::hypot(x[3 * k] - aim[0], x[3 * k + 1] - aim[1]) <= radius * (1.0 + 1e-9))
      {
        l.dofs.push_back(static_cast<std::int32_t>(k * _fe->block_size() + (pu.in_plane() ? 0 : 2)));
        l.weights.push_back(area[k]);
        total += area[k];
      }
    // the node at the disc's centre always lies in it (mesh_outline); -z,
    // or +x in plane
    for (double& w : l.weights)
      w *= (pu.in_plane() ? 1.0 : -1.0) / total;
    _load_nodes = l.dofs.size();
    return l;
  }

  std::vector<double> point_deflections() const { return _points->deflections(_solver->u()); }

  double max_deflection() const { return demo::max_deflection(*_fe, _solver->u()); }
  double support_reaction() const { return demo::support_reaction(*_fe, _solver->reactions(), _solver->u()); }

  void describe()
  {
    const char* edges[] = {"free", "simply-supported", "clamped", "frame"};
    _out["scenario"] = _s.name;
    _out["model"] = _s.shells.model;
    _out["shells"] = {{"element_size_m", _spec.element_size},
                      {"outer_element_size_m", _spec.outer_element_size > 0.0 ? _spec.outer_element_size
                                                                               : _spec.element_size},
                      {"edges", edges[static_cast<int>(_spec.edges)]},
                      {"shell_nodes", _fe->num_nodes()},
                      {"shell_cells", _fe->num_cells()},
                      {"supported_shell_dofs", _supports.size()},
            {"frame_nodes", _frame_nodes},
                      {"shell_setup_s", _setup_s}};
    _out["pulse"] = {{"peak_force_n", _s.pulse.peak_force},
                     {"duration_s", _s.pulse.duration},
                     {"impulse_n_s", 2.0 / std::numbers::pi * _s.pulse.peak_force * _s.pulse.duration},
                     {"loaded_nodes", _load_nodes}};
    _out["dt_s"] = _dt;
    _out["dt_critical_s"] = _dt_crit;
    _out["duration_s"] = _s.run.duration;
  }

  std::filesystem::path dir() const { return _cfg.output_dir; }

  void open_output()
  {
    if (_cfg.output_dir.empty())
      return;
    std::filesystem::create_directories(dir());
    write_json(dir() / "scenario.json", _s.resolved);
    _writer = std::make_unique<shell::XdmfWriter>(*_fe, dir() / "shell.xdmf");
    write_frame();
    _csv.open(dir() / "history.csv");
    _csv << "time_s,load_n,load_work_j,shell_kinetic_j,shell_strain_j,support_work_j,imbalance_j,"
            "shell_max_deflection_m,support_reaction_n";
    for (std::size_t q = 0; q < _points->size(); ++q)
      _csv << ",deflection_" << q << "_m";
    _csv << '\n';
    write_row();
  }

  void resume()
  {
    const auto file = _ckpt->open_restart();
    const auto root = file.root();
    _solver->load(root.group("shells"));
    if (_track)
      _track->load(root.group("run").group("deflections"));
    _out["restarted_from_step"] = _solver->steps();
    if (_cfg.output_dir.empty())
      return;
    _writer = std::make_unique<shell::XdmfWriter>(*_fe, dir() / "shell.xdmf", root.group("shell_xdmf"));
    reopen_text(_csv, dir() / "history.csv", root.group("run").read_int("csv_bytes"));
  }

  void save(const checkpoint::Group& root)
  {
    _solver->save(root.group("shells"));
    const auto run = root.group("run");
    if (_track)
      _track->save(run.group("deflections"));
    if (_writer)
      _writer->save(root.group("shell_xdmf"));
    if (_csv.is_open())
      run.write_int("csv_bytes", flushed_size(_csv, dir() / "history.csv"));
  }

  void write_frame() { _writer->write(_solver->time(), _solver->u(), _solver->v()); }

  void write_row()
  {
    if (!_csv.is_open())
      return;
    const auto e = _solver->energy();
    _csv << std::setprecision(10) << _solver->time() << ',' << _s.pulse.force(_solver->time()) << ','
         << e.external_work << ',' << e.kinetic << ',' << e.strain << ',' << e.prescribed_work << ','
         << e.imbalance() << ',' << max_deflection() << ',' << support_reaction();
    for (double w : point_deflections())
      _csv << ',' << w;
    _csv << '\n' << std::flush;
  }

  void loop()
  {
    const std::int64_t frame_every = std::max<std::int64_t>(1, _nsteps / std::max(1, _s.run.frames));
    const LoopPlan plan{.done = _solver->steps(),
                        .last = _nsteps,
                        .rows = {_history_every},
                        .frames = {frame_every},
                        .prints = {},
                        .print_seconds = 2.0,
                        .checkpoints = _ckpt.get()};
    LoopHooks h = solver_hooks(*_solver);
    if (_track)
      h.after_step = [this](std::int64_t) { _track->add(_solver->time(), point_deflections()); };
    h.row = [this](std::int64_t, bool) { write_row(); };
    if (_writer)
      h.frame = [this](std::int64_t, bool) { write_frame(); };
    if (!_cfg.quiet)
      h.progress = [this](std::int64_t, bool)
      {
        std::cout << std::setw(14) << _solver->time() << std::setw(11) << _s.pulse.force(_solver->time())
                  << std::setw(13) << max_deflection() << std::endl;
      };
    h.save = [this](const checkpoint::Group& g) { save(g); };
    run_time_loop(plan, h);
    if (_writer)
      _writer->close();
  }

  void report()
  {
    const auto e = _solver->energy();
    _out["outcome"] = "time up";
    _out["perforated"] = false;
    _out["steps"] = _solver->steps();
    _out["time_s"] = _solver->time();
    _out["energy"] = {{"load_work_j", e.external_work},
                      {"shell_kinetic_j", e.kinetic},
                      {"shell_strain_j", e.strain},
                      {"support_work_j", e.prescribed_work},
                      {"damping_j", e.damping},
                      {"imbalance_j", e.imbalance()},
                      {"imbalance_share", e.external_work != 0.0 ? e.imbalance() / std::abs(e.external_work) : 0.0}};
    _out["shells"]["shell_max_deflection_m"] = max_deflection();
    if (_track)
      _out["deflection_points"] = _track->report();
    _out["peak_memory_mb"] = peak_memory_mb();
  }

  const ImpactConfig& _cfg;
  const Scenario& _s;
  nlohmann::json _out;
  bridge::SlabSpec _spec;
  std::unique_ptr<shell::FEModel> _fe;
  std::unique_ptr<shell::ExplicitSolver> _solver;
  std::unique_ptr<Checkpointer> _ckpt;
  std::unique_ptr<shell::XdmfWriter> _writer;
  std::unique_ptr<DeflectionTrack> _track;
  std::vector<std::int32_t> _supports;
  std::size_t _frame_nodes = 0; // shell nodes on the frame (Edges::frame)
  std::unique_ptr<ShellPoints> _points; // shells.deflection_points_m
  std::size_t _load_nodes = 0;
  std::ofstream _csv;
  double _dt = 0.0, _dt_crit = 0.0, _setup_s = 0.0;
  std::int64_t _nsteps = 0, _history_every = 1;
};

} // namespace

nlohmann::json run_shell_slab(const ImpactConfig& cfg) { return ShellSlabRun(cfg).run(); }

} // namespace dembridge::demo
