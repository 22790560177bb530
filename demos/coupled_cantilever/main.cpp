// coupled_cantilever: a bar of square section, shells from the clamped end
// x = 0 to x = fe-length, discrete elements from x = de-start to the free
// end x = length, tied in the overlap [de-start, fe-length] by the
// bridging-domain method (energy weights, fictive elements, Lagrange
// multipliers). Free vibration from a velocity in the first axial or bending mode
// shape of a cantilever; prints the energy budget and the constraint residual,
// measures the first frequency at the free end and compares it with the
// all-shell cantilever of the same length and material (shell_cantilever's
// procedure).
//
// Sample runs:
//   build/bin/coupled_cantilever --load axial --output out/coupled --summary out/coupled.json
//   build/bin/coupled_cantilever --load bending --periods 2
//   build/bin/coupled_cantilever --fe solid --load bending
// Output: DIR/shell.xdmf (FE fields), DIR/particles.xdmf (spheres), DIR/history.csv.
#include "cantilever.h"
#include "options.h"
#include "restart.h"
#include "fe_runtime.h"
#include "support.h"
#include "time_loop.h"

#include "dembridge/bridge/coupled.h"
#include "dembridge/dem/material_file.h"
#include "dembridge/dem/output.h"
#include "dembridge/dem/packing.h"
#include "dembridge/shell/analytic.h"
#include "dembridge/shell/mesh.h"
#include "dembridge/shell/output.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <numbers>
#include <memory>
#include <numeric>
#include <sstream>

namespace
{
using namespace dembridge;

struct CoupledCantileverConfig
{
  std::string load = "axial", fe_kind = "shell", cell = "auto", material_file, output, summary;
  double length = 0.2, width = 0.05, fe_length = 0.12, de_start = 0.08, mean_radius = 3e-3;
  double amplitude = 1e-6, periods = 2.0, safety = 0.8;
  int nx = 12, ny = 5, nz = 5, frames = 20;
  unsigned seed = 1;
  demo::RestartOptions restart;
};

/// The run in its phases: checks, the materials, the shell and the DE
/// parts, the coupler, the all-shell reference, the clamp and the initial
/// velocity, the output, the time loop and the summary. The coupler is
/// declared after the model, particles and links it holds.
class CoupledCantileverRun
{
public:
  explicit CoupledCantileverRun(CoupledCantileverConfig c) : _c(std::move(c)) {}

  nlohmann::json run()
  {
    check();
    _ckpt = std::make_unique<demo::Checkpointer>(_c.restart, _c.output);
    resolve_materials();
    build_fe();
    build_de();
    couple();
    reference();
    clamp_and_start();
    if (_ckpt->restarting())
      resume();
    else
      open_output();
    march();
    return summary();
  }

private:
  // ---- set-up ---------------------------------------------------------------
  void check()
  {
    if (_c.fe_kind != "shell" && _c.fe_kind != "solid")
      throw std::runtime_error("--fe " + _c.fe_kind + ": allowed are shell, solid");
    _solid = _c.fe_kind == "solid";
    const bool solid_cell = _c.cell == "hexahedron" || _c.cell == "tetrahedron";
    if (_c.cell == "auto")
      _c.cell = _solid ? "hexahedron" : "quadrilateral";
    else if (solid_cell != _solid)
      throw std::runtime_error("--cell " + _c.cell + " with --fe " + _c.fe_kind + ": allowed are "
                               + (_solid ? "hexahedron, tetrahedron" : "triangle, quadrilateral"));
    if (_c.load != "axial" && _c.load != "bending")
      throw std::runtime_error("load '" + _c.load + "': allowed are axial, bending");
    if (!(_c.de_start < _c.fe_length && _c.fe_length < _c.length && _c.de_start > 0.0))
      throw std::runtime_error("need 0 < de-start < fe-length < length (the overlap is [de-start, fe-length])");
    _axial = _c.load == "axial";
  }

  /// DE side: the material as identified; the shell takes the same E, nu, density.
  void resolve_materials()
  {
    _mf = dem::read_material(_c.material_file);
    _mat = _mf.material;
    _mat.tensile = _mat.cohesion = 1e12; // elastic vibration
    _sm.youngs_modulus = _mf.macroscopic.value("youngs_modulus_pa", _mat.youngs_modulus);
    _sm.poisson_ratio = _mf.macroscopic.value("poisson_ratio", _mat.poisson_ratio);
    _sm.density = _mat.density;
    _sm.thickness = _c.width;
    std::cout << "# shell material: E " << _sm.youngs_modulus << " Pa, nu " << _sm.poisson_ratio
              << ", rho " << _sm.density << " kg/m^3 (measured on the DE sample)\n";
  }

  void build_fe()
  {
    const double w = _c.width;
    auto mesh = _solid ? shell::create_solid_box(MPI_COMM_WORLD, {_c.fe_length, w, w}, {_c.nx, _c.ny, _c.nz},
                                                 shell::parse_cell(_c.cell),
                                                 shell::Placement::rotation_about({1, 0, 0}, 0.0, {0.0, 0.0, -0.5 * w}))
                       : shell::create_shell_rectangle(MPI_COMM_WORLD, _c.fe_length, w, _c.nx, _c.ny,
                                                       shell::parse_cell(_c.cell));
    _fe = std::make_unique<shell::FEModel>(mesh, _sm);
  }

  void build_de()
  {
    dem::PackingOptions po;
    po.mean_radius = _c.mean_radius;
    po.seed = _c.seed;
    const double h = _c.width;
    const auto region = dem::box_region({_c.de_start, 0.0, -0.5 * h}, {_c.length, _c.width, 0.5 * h});
    // the dem module's errors name the region; the user's options are these
    std::ostringstream mean_radius;
    mean_radius << _c.mean_radius;
    const std::string opts = "--mean-radius " + mean_radius.str() + " m in the DE part (--length, "
                             "--width, --de-start)";
    const auto pk = demo::with_context(opts, [&] { return dem::generate_packing(region, po); });
    double solid_volume = 0.0;
    for (double r : pk.r)
      solid_volume += 4.0 / 3.0 * std::numbers::pi * r * r * r;
    _p = dem::make_particles(pk.x, pk.r, _mat.density, solid_volume / region.volume);
    _links = dem::create_links(
        _p,
        demo::with_context(opts, [&] { return dem::lambda_for_bulk_links(region, _p.x, _p.r, _mf.links_per_sphere); }),
        _mat);
    _floppy = dem::floppy_spheres(_p, _links);
    if (!_floppy.empty())
      std::cout << "# " << _floppy.size() << " spheres have their links on one line (dem::floppy_spheres): "
                << "free to turn about it, left out of the tip's mean\n";
  }

  void couple()
  {
    bridge::CouplingOptions o;
    o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, _c.fe_length, _c.de_start};
    o.safety = _c.safety;
    _s = std::make_unique<bridge::CoupledSolver>(*_fe, _p, _links, _mat, o);
    const auto& s = *_s;
    std::cout << _p.size() << " spheres, " << _links.size() << " links, " << _fe->num_nodes()
              << " shell nodes, " << s.constrained() << " constrained spheres ("
              << s.coupling().outside() << " placed by the nearest-element rule); dt " << s.dt()
              << " s = safety x coupled critical " << s.dt_coupled() << " s (alone: FE " << s.dt_fe()
              << " s, DE " << s.dt_de() << " s)\n";
  }

  /// The all-shell cantilever of the same bar (shell_cantilever's procedure).
  void reference()
  {
    demo::CantileverConfig ref;
    ref.load = _c.load;
    ref.cell = _c.cell;
    ref.length = _c.length;
    ref.width = _c.width;
    ref.nx = static_cast<int>(std::round(_c.nx * _c.length / _c.fe_length));
    ref.ny = _c.ny;
    ref.nz = _c.nz;
    ref.material = _sm;
    ref.quiet = true;
    ref.periods = 3.0;
    const auto fe_only = demo::run_cantilever(ref);
    _f_ref = fe_only["first_frequency_hz"].get<double>();
  }

  double shape(double xx) const
  {
    return _axial ? std::sin(0.5 * std::numbers::pi * xx / _c.length)
                  : shell::analytic::cantilever_mode_shape(xx, _c.length);
  }
  double slope(double xx) const { return shell::analytic::cantilever_mode_slope(xx, _c.length); }

  /// Clamp at x = 0; initial velocity: the cantilever mode shape of the
  /// whole bar times the all-shell model's circular frequency, so the tip
  /// swings to about `amplitude` (a smooth velocity field, which excites
  /// the particles' own high modes far less than an imposed displacement
  /// field would).
  void clamp_and_start()
  {
    shell::FEModel& fe = *_fe;
    const auto x = fe.node_coordinates();
    const int bs = fe.block_size();
    std::vector<int> all(bs);
    std::iota(all.begin(), all.end(), 0);
    const double length = _c.length;
    const auto clamp = shell::node_dofs(
        shell::select_nodes(x, [&](const auto& q) { return q[0] < 1e-9 * length; }, "clamped end x = 0"),
        bs, all);
    _s->fe().add_motion({"clamp", clamp, shell::MotionKind::fixed, {}});
    const double vmax = 2.0 * std::numbers::pi * _f_ref * _c.amplitude;
    std::vector<double> u(fe.num_dofs(), 0.0), v(fe.num_dofs(), 0.0);
    for (std::size_t k = 0; k < fe.num_nodes(); ++k)
    {
      if (_axial)
        v[bs * k] = vmax * shape(x[3 * k]);
      else
      {
        v[bs * k + 2] = vmax * shape(x[3 * k]);
        if (_solid)
          v[bs * k] = -vmax * slope(x[3 * k]) * x[3 * k + 2];
        else
          v[bs * k + 4] = -vmax * slope(x[3 * k]);
      }
    }
    for (std::size_t i = 0; i < _p.size(); ++i)
    {
      const double xi = _p.x[3 * i], zi = _p.x[3 * i + 2];
      if (_axial)
        _p.v[3 * i] = vmax * shape(xi);
      else
      {
        _p.v[3 * i + 2] = vmax * shape(xi);
        _p.v[3 * i] = -vmax * slope(xi) * zi;
        _p.w[3 * i + 1] = -vmax * slope(xi);
      }
    }
    _s->start(u, v);
    // the tip: the spheres within 2 mean radii of the free end, but those
    // whose links leave them free to turn (they drift, without a force)
    for (std::size_t i = 0; i < _p.size(); ++i)
      if (_p.x0[3 * i] > _c.length - 2.0 * _c.mean_radius
          && !std::binary_search(_floppy.begin(), _floppy.end(), static_cast<std::int32_t>(i)))
        _tip.push_back(static_cast<std::int32_t>(i));
  }

  void open_output()
  {
    if (_c.output.empty())
      return;
    const std::filesystem::path dir(_c.output);
    std::filesystem::create_directories(dir);
    _shell_out = std::make_unique<shell::XdmfWriter>(*_fe, dir / "shell.xdmf");
    _part_out = std::make_unique<dem::ParticleWriter>(dir / "particles.xdmf", _links, _p.size(), false);
    _csv.open(dir / "history.csv");
    _csv << "t_s,tip_m,fe_kinetic_j,fe_strain_j,de_kinetic_j,de_elastic_j,total_j,imbalance_j,residual\n";
  }

  /// Continues from the checkpoint: both sides and the coupling, the tip
  /// history, the output files up to the checkpoint.
  void resume()
  {
    const auto file = _ckpt->open_restart();
    const auto root = file.root();
    _s->load(root.group("coupled"));
    const auto run = root.group("run");
    run.read("t", _ts);
    run.read("tip", _tips);
    std::vector<double> tracked;
    run.read("tracked", tracked);
    if (tracked.size() != 3 || _ts.empty() || _ts.size() != _tips.size())
      run.fail("tracked", "not the history of this run (file damaged?)");
    _e0 = tracked[0];
    _worst = tracked[1];
    _drift = tracked[2];
    _restarted_from = _s->fe().steps();
    if (_c.output.empty())
      return;
    const std::filesystem::path dir(_c.output);
    _shell_out = std::make_unique<shell::XdmfWriter>(*_fe, dir / "shell.xdmf", root.group("shell_xdmf"));
    _part_out = std::make_unique<dem::ParticleWriter>(dir / "particles.xdmf", _links, _p.size(), false,
                                                      root.group("particles_xdmf"));
    demo::reopen_text(_csv, dir / "history.csv", run.read_int("csv_bytes"));
  }

  /// The checkpoint: the coupled state, the tip history, the output files' extent.
  void save(const checkpoint::Group& root)
  {
    _s->save(root.group("coupled"));
    const auto run = root.group("run");
    run.write("t", _ts);
    run.write("tip", _tips);
    run.write("tracked", std::vector<double>{_e0, _worst, _drift});
    if (_shell_out)
    {
      _shell_out->save(root.group("shell_xdmf"));
      _part_out->save(root.group("particles_xdmf"));
    }
    if (_csv.is_open())
      run.write_int("csv_bytes", demo::flushed_size(_csv, std::filesystem::path(_c.output) / "history.csv"));
  }

  // ---- run ------------------------------------------------------------------
  double tip_value() const
  {
    const int comp = _axial ? 0 : 2;
    double t = 0.0;
    for (auto i : _tip)
      t += _p.x[3 * i + comp] - _p.x0[3 * i + comp];
    return t / _tip.size();
  }

  void write_frame(std::int64_t k, double r)
  {
    const auto e = _s->energy();
    _drift = std::max(_drift, std::abs(e.total() - _e0) / _e0);
    if (_csv.is_open())
      _csv << _ts.back() << ',' << _tips.back() << ',' << e.fe.kinetic << ',' << e.fe.strain << ','
           << e.de.kinetic << ',' << e.de.elastic << ',' << e.total() << ',' << e.imbalance() << ',' << r
           << '\n' << std::flush; // whole rows if the run is killed
    if (_shell_out)
    {
      _shell_out->write(_ts.back(), _s->fe().u(), _s->fe().v());
      _part_out->write(_ts.back(), _p, _links);
    }
    if (k % (_every * std::max<std::int64_t>(1, _c.frames / 10)) == 0 || k == _nsteps)
      std::printf("%10.4e %12.4e %13.5e %14.3e %16.3e\n", _ts.back(), _tips.back(), e.total(), e.imbalance(), r);
  }

  void march()
  {
    _nsteps = static_cast<std::int64_t>(std::ceil(_c.periods / _f_ref / _s->dt()));
    _every = std::max<std::int64_t>(1, _nsteps / std::max(1, _c.frames));
    std::cout << "     t [s]      tip [m]   total E [J]  imbalance [J]   residual [m/s]\n";
    if (_ts.empty()) // a new run (a restarted one has its history)
    {
      _ts = {0.0};
      _tips = {tip_value()};
      _e0 = _s->energy().total();
      write_frame(0, 0.0); // the initial state, a frame at t = 0
    }
    // the shared time loop (time_loop.h): a frame and a CSV row every
    // _every steps and at the end
    const demo::LoopPlan plan{
        .done = _s->fe().steps(), .last = _nsteps, .rows = {}, .frames = {_every}, .prints = {}, .checkpoints = _ckpt.get()};
    double r = 0.0; // the step's multiplier residual [m/s]
    demo::LoopHooks h;
    h.step = [&](std::int64_t k)
    {
      r = _s->step();
      _worst = std::max(_worst, r);
      _ts.push_back(k * _s->dt());
      _tips.push_back(tip_value());
    };
    h.time = [this] { return _ts.back(); };
    h.frame = [&](std::int64_t k, bool) { write_frame(k, r); };
    h.save = [this](const checkpoint::Group& g) { save(g); };
    demo::run_time_loop(plan, h);
  }

  // ---- summary --------------------------------------------------------------
  nlohmann::json summary() const
  {
    const auto& s = *_s;
    const double f = demo::crossing_frequency(_ts, _tips);
    nlohmann::json out{{"load", _c.load},
            {"fe", _c.fe_kind},
            {"particles", _p.size()},
            {"floppy_spheres", _floppy.size()},
            {"shell_nodes", _fe->num_nodes()},
            {"constrained_particles", s.constrained()},
            {"placed_by_nearest_rule", s.coupling().outside()},
            {"max_constraint_residual", _worst},
            {"energy_drift", _drift},
            {"first_frequency_hz", f},
            {"fe_only_frequency_hz", _f_ref},
            {"relative_to_fe_only", f / _f_ref - 1.0},
            {"dt_s", s.dt()},
            {"dt_coupled_s", s.dt_coupled()},
            {"dt_de_s", s.dt_de()},
            {"dt_fe_s", s.dt_fe()},
            {"steps", _nsteps},
            {"wall_s", _clock.seconds()}};
    if (_restarted_from >= 0)
      out["restarted_from_step"] = _restarted_from;
    return out;
  }

  // ---- state ----------------------------------------------------------------
  CoupledCantileverConfig _c;
  demo::Stopwatch _clock;
  bool _solid = false, _axial = true;
  dem::MaterialFile _mf;
  dem::Material _mat;
  shell::Material _sm;
  std::unique_ptr<shell::FEModel> _fe;
  dem::Particles _p;
  dem::Links _links;
  std::unique_ptr<bridge::CoupledSolver> _s; // after what it holds
  double _f_ref = 0.0;
  std::vector<std::int32_t> _tip, _floppy;
  std::unique_ptr<shell::XdmfWriter> _shell_out;
  std::unique_ptr<dem::ParticleWriter> _part_out;
  std::ofstream _csv;
  std::int64_t _nsteps = 0, _every = 1;
  std::vector<double> _ts, _tips;
  double _e0 = 0.0, _worst = 0.0, _drift = 0.0;
  std::unique_ptr<demo::Checkpointer> _ckpt;
  std::int64_t _restarted_from = -1;
};
} // namespace

int main(int argc, char** argv)
{
  CoupledCantileverConfig c;
  c.material_file = demo::shipped_file("materials/default.json", DEMBRIDGE_SOURCE_DIR "/demos/calibrate/materials/default.json");
  CLI::App app{"Coupled shell / DE cantilever in free vibration", "coupled_cantilever"};
  using demo::Allowed;
  demo::add_choice(app, "--load", c.load, "first cantilever mode shape", "axial | bending");
  demo::add_choice(app, "--fe", c.fe_kind, "the FE side", "shell | solid");
  demo::add_choice(app, "--cell", c.cell,
                   "triangle | quadrilateral (shell); hexahedron | tetrahedron (solid); auto = quadrilateral "
                   "or hexahedron", "auto | triangle | quadrilateral | hexahedron | tetrahedron");
  demo::add_integer(app, "--nz", c.nz, "solid divisions through the thickness", Allowed::closed(1, 10000));
  demo::add_number(app, "--length", c.length, "bar length [m]", Allowed::positive(100.0));
  demo::add_number(app, "--width", c.width, "side of the square section = shell thickness [m]", Allowed::positive(10.0));
  demo::add_number(app, "--fe-length", c.fe_length, "shell region: x in [0, fe-length] [m]", Allowed::positive(100.0));
  demo::add_number(app, "--de-start", c.de_start, "DE region: x in [de-start, length] [m]", Allowed::positive(100.0));
  demo::add_integer(app, "--nx", c.nx, "shell divisions along x (over fe-length)", Allowed::closed(1, 10000));
  demo::add_integer(app, "--ny", c.ny, "shell divisions across", Allowed::closed(1, 10000));
  demo::add_number(app, "--mean-radius", c.mean_radius, "mean sphere radius [m]", Allowed::positive(1.0));
  demo::add_integer(app, "--seed", c.seed, "packing seed", Allowed::closed(0, 4294967295.0));
  demo::add_input_file(app, "--material", c.material_file, "DE parameter file (from calibrate)")->capture_default_str();
  demo::add_number(app, "--amplitude", c.amplitude, "tip amplitude of the initial mode-shape velocity (tip speed = 2 pi f amplitude) [m]", Allowed::positive(1.0));
  demo::add_number(app, "--periods", c.periods, "run length in periods of the all-shell model", Allowed::positive(1e4));
  demo::add_number(app, "--safety-factor", c.safety, "fraction of the coupled critical time step (a power-iteration estimate, from below)", Allowed::above(0.0, 0.95));
  demo::add_integer(app, "--frames", c.frames, "output frames", Allowed::closed(1, 100000));
  demo::add_run_options(app, c.output, "output folder; empty = none", c.summary, c.restart);
  if (const int rc = demo::parse_run_options(app, argc, argv, c.restart); rc >= 0)
    return rc;

  return demo::run_guarded(argc, argv, [&]
  {
    demo::echo_options(app);
    const nlohmann::json out = CoupledCantileverRun(c).run();
    std::cout << out.dump(2) << std::endl;
    if (!c.summary.empty())
      demo::write_summary(c.summary, out);
  }, c.summary, demo::petsc_runtime());
}
