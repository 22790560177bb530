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
#include "support.h"

#include "dembridge/bridge/coupled.h"
#include "dembridge/dem/material_file.h"
#include "dembridge/dem/output.h"
#include "dembridge/dem/packing.h"
#include "dembridge/shell/analytic.h"
#include "dembridge/shell/mesh.h"
#include "dembridge/shell/output.h"

#include <CLI/CLI.hpp>
#include <cmath>
#include <fstream>
#include <iostream>
#include <numbers>
#include <numeric>

int main(int argc, char** argv)
{
  using namespace dembridge;
  std::string load = "axial", fe_kind = "shell", cell = "quadrilateral", material_file, output, summary;
  double length = 0.2, width = 0.05, fe_length = 0.12, de_start = 0.08, mean_radius = 3e-3;
  double amplitude = 1e-6, periods = 2.0, safety = 0.8;
  int nx = 12, ny = 5, frames = 20;
  unsigned seed = 1;
  material_file = DEMBRIDGE_SOURCE_DIR "/demos/calibrate/materials/default.json";
  CLI::App app{"Coupled shell / DE cantilever in free vibration", "coupled_cantilever"};
  app.add_option("--load", load, "axial | bending (first cantilever mode shape)")->capture_default_str();
  app.add_option("--fe", fe_kind, "shell | solid")->capture_default_str();
  app.add_option("--cell", cell, "triangle | quadrilateral (shell); hexahedron | tetrahedron (solid)")
      ->capture_default_str();
  int nz = 5;
  app.add_option("--nz", nz, "solid divisions through the thickness")->capture_default_str();
  app.add_option("--length", length, "bar length [m]")->capture_default_str();
  app.add_option("--width", width, "side of the square section = shell thickness [m]")->capture_default_str();
  app.add_option("--fe-length", fe_length, "shell region: x in [0, fe-length] [m]")->capture_default_str();
  app.add_option("--de-start", de_start, "DE region: x in [de-start, length] [m]")->capture_default_str();
  app.add_option("--nx", nx, "shell divisions along x (over fe-length)")->capture_default_str();
  app.add_option("--ny", ny, "shell divisions across")->capture_default_str();
  app.add_option("--mean-radius", mean_radius, "mean sphere radius [m]")->capture_default_str();
  app.add_option("--seed", seed, "packing seed")->capture_default_str();
  app.add_option("--material", material_file, "DE parameter file (from calibrate)")->capture_default_str();
  app.add_option("--amplitude", amplitude, "tip amplitude of the initial mode-shape velocity (tip speed = 2 pi f amplitude) [m]")->capture_default_str();
  app.add_option("--periods", periods, "run length in periods of the all-shell model")->capture_default_str();
  app.add_option("--safety-factor", safety, "fraction of the coupled critical time step, in (0, 1]")->capture_default_str();
  app.add_option("--frames", frames, "output frames")->capture_default_str();
  app.add_option("--output", output, "output folder; empty = none");
  app.add_option("--summary", summary, "write key results as JSON to this file");
  CLI11_PARSE(app, argc, argv);

  return demo::run_guarded(argc, argv, [&]
  {
    demo::echo_options(app);
    demo::Stopwatch clock;
    if (fe_kind != "shell" && fe_kind != "solid")
      throw std::runtime_error("--fe " + fe_kind + ": allowed are shell, solid");
    const bool solid = fe_kind == "solid";
    if (solid && (cell == "quadrilateral" || cell == "triangle"))
      cell = "hexahedron";
    if (load != "axial" && load != "bending")
      throw std::runtime_error("load '" + load + "': allowed are axial, bending");
    if (!(de_start < fe_length && fe_length < length && de_start > 0.0))
      throw std::runtime_error("need 0 < de-start < fe-length < length (the overlap is [de-start, fe-length])");
    // DE side: material as identified; the shell takes the same E, nu, density
    auto mf = dem::read_material(material_file);
    dem::Material mat = mf.material;
    mat.tensile = mat.cohesion = 1e12; // elastic vibration
    shell::Material sm;
    sm.youngs_modulus = mf.macroscopic.value("youngs_modulus_pa", mat.youngs_modulus);
    sm.poisson_ratio = mf.macroscopic.value("poisson_ratio", mat.poisson_ratio);
    sm.density = mat.density;
    sm.thickness = width;
    std::cout << "# shell material: E " << sm.youngs_modulus << " Pa, nu " << sm.poisson_ratio
              << ", rho " << sm.density << " kg/m^3 (measured on the DE sample)\n";

    auto mesh = solid ? shell::create_solid_box(MPI_COMM_WORLD, {fe_length, width, width},
                                                {nx, ny, nz}, shell::parse_cell(cell),
                                                shell::Placement::rotation_about(
                                                    {1, 0, 0}, 0.0, {0.0, 0.0, -0.5 * width}))
                      : shell::create_shell_rectangle(MPI_COMM_WORLD, fe_length, width, nx, ny,
                                                      shell::parse_cell(cell));
    shell::FEModel fe(mesh, sm);
    dem::PackingOptions po;
    po.mean_radius = mean_radius;
    po.seed = seed;
    const double h = width;
    const auto region = dem::box_region({de_start, 0.0, -0.5 * h}, {length, width, 0.5 * h});
    const auto pk = dem::generate_packing(region, po);
    double solid_volume = 0.0;
    for (double r : pk.r)
      solid_volume += 4.0 / 3.0 * std::numbers::pi * r * r * r;
    auto p = dem::make_particles(pk.x, pk.r, mat.density, solid_volume / region.volume);
    auto links = dem::create_links(p, dem::lambda_for_bulk_links(region, p.x, p.r, mf.links_per_sphere), mat);

    bridge::CouplingOptions o;
    o.overlap = {{1.0, 0.0, 0.0}, fe_length, de_start};
    o.safety = safety;
    bridge::CoupledSolver s(fe, p, links, mat, o);
    std::cout << p.size() << " spheres, " << links.size() << " links, " << fe.num_nodes()
              << " shell nodes, " << s.constrained() << " constrained spheres ("
              << s.coupling().outside() << " placed by the nearest-element rule); dt " << s.dt()
              << " s = safety x coupled critical " << s.dt_coupled() << " s (alone: FE " << s.dt_fe() << " s, DE " << s.dt_de() << " s)\n";

    // reference: the all-shell cantilever of the same bar
    demo::CantileverConfig ref;
    ref.load = load;
    ref.cell = cell;
    ref.length = length;
    ref.width = width;
    ref.nx = static_cast<int>(std::round(nx * length / fe_length));
    ref.ny = ny;
    ref.nz = nz;
    ref.material = sm;
    ref.quiet = true;
    ref.periods = 3.0;
    const auto fe_only = demo::run_cantilever(ref);
    const double f_ref = fe_only["first_frequency_hz"].get<double>();
    // clamp, initial shape (cantilever mode of the whole bar)
    const auto x = fe.node_coordinates();
    const int bs = fe.block_size();
    std::vector<int> all(bs);
    std::iota(all.begin(), all.end(), 0);
    const auto clamp = shell::node_dofs(
        shell::select_nodes(x, [&](const auto& q) { return q[0] < 1e-9 * length; }, "clamped end x = 0"),
        bs, all);
    s.fe().add_motion({"clamp", clamp, shell::MotionKind::fixed, {}});
    const bool axial = load == "axial";
    auto shape = [&](double xx) {
      return axial ? std::sin(0.5 * std::numbers::pi * xx / length)
                   : shell::analytic::cantilever_mode_shape(xx, length);
    };
    auto slope = [&](double xx) { return shell::analytic::cantilever_mode_slope(xx, length); };
    // initial velocity: the mode shape times the all-shell model's circular
    // frequency, so the tip swings to about `amplitude` (a smooth velocity
    // field, which excites the particles' own high modes far less than an
    // imposed displacement field would)
    const double vmax = 2.0 * std::numbers::pi * f_ref * amplitude;
    std::vector<double> u(fe.num_dofs(), 0.0), v(fe.num_dofs(), 0.0);
    for (std::size_t k = 0; k < fe.num_nodes(); ++k)
    {
      if (axial)
        v[bs * k] = vmax * shape(x[3 * k]);
      else
      {
        v[bs * k + 2] = vmax * shape(x[3 * k]);
        if (solid)
          v[bs * k] = -vmax * slope(x[3 * k]) * x[3 * k + 2];
        else
          v[bs * k + 4] = -vmax * slope(x[3 * k]);
      }
    }
    for (std::size_t i = 0; i < p.size(); ++i)
    {
      const double xi = p.x[3 * i], zi = p.x[3 * i + 2];
      if (axial)
        p.v[3 * i] = vmax * shape(xi);
      else
      {
        p.v[3 * i + 2] = vmax * shape(xi);
        p.v[3 * i] = -vmax * slope(xi) * zi;
        p.w[3 * i + 1] = -vmax * slope(xi);
      }
    }
    s.start(u, v);

    const auto nsteps = static_cast<std::int64_t>(std::ceil(periods / f_ref / s.dt()));

    std::vector<std::int32_t> tip;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (p.x0[3 * i] > length - 2.0 * mean_radius)
        tip.push_back(static_cast<std::int32_t>(i));
    const int comp = axial ? 0 : 2;
    auto tip_value = [&] {
      double t = 0.0;
      for (auto i : tip)
        t += p.x[3 * i + comp] - p.x0[3 * i + comp];
      return t / tip.size();
    };
    std::unique_ptr<shell::XdmfWriter> shell_out;
    std::unique_ptr<dem::ParticleWriter> part_out;
    std::ofstream csv;
    if (!output.empty())
    {
      std::filesystem::create_directories(output);
      shell_out = std::make_unique<shell::XdmfWriter>(fe, std::filesystem::path(output) / "shell.xdmf");
      part_out = std::make_unique<dem::ParticleWriter>(std::filesystem::path(output) / "particles.xdmf",
                                                       links, p.size(), false);
      csv.open(std::filesystem::path(output) / "history.csv");
      csv << "t_s,tip_m,fe_kinetic_j,fe_strain_j,de_kinetic_j,de_elastic_j,total_j,imbalance_j,residual\n";
    }
    const std::int64_t every = std::max<std::int64_t>(1, nsteps / std::max(1, frames));
    std::vector<double> ts{0.0}, tips{tip_value()};
    const double e0 = s.energy().total();
    double worst = 0.0, drift = 0.0;
    std::cout << "     t [s]      tip [m]   total E [J]  imbalance [J]   residual [m/s]\n";
    for (std::int64_t k = 1; k <= nsteps; ++k)
    {
      const double r = s.step();
      worst = std::max(worst, r);
      ts.push_back(k * s.dt());
      tips.push_back(tip_value());
      if (k % every == 0 || k == nsteps)
      {
        const auto e = s.energy();
        drift = std::max(drift, std::abs(e.total() - e0) / e0);
        if (csv.is_open())
          csv << ts.back() << ',' << tips.back() << ',' << e.fe.kinetic << ',' << e.fe.strain << ','
              << e.de.kinetic << ',' << e.de.elastic << ',' << e.total() << ',' << e.imbalance()
              << ',' << r << '\n';
        if (shell_out)
        {
          shell_out->write(ts.back(), s.fe().u(), s.fe().v());
          part_out->write(ts.back(), p, links);
        }
        if (k % (every * std::max<std::int64_t>(1, frames / 10)) == 0 || k == nsteps)
          std::printf("%10.4e %12.4e %13.5e %14.3e %16.3e\n", ts.back(), tips.back(), e.total(),
                      e.imbalance(), r);
      }
    }
    const double f = demo::crossing_frequency(ts, tips);
    nlohmann::json out = {{"load", load},
                          {"fe", fe_kind},
                          {"particles", p.size()},
                          {"shell_nodes", fe.num_nodes()},
                          {"constrained_particles", s.constrained()},
                          {"placed_by_nearest_rule", s.coupling().outside()},
                          {"max_constraint_residual", worst},
                          {"energy_drift", drift},
                          {"first_frequency_hz", f},
                          {"fe_only_frequency_hz", f_ref},
                          {"relative_to_fe_only", f / f_ref - 1.0},
                          {"dt_s", s.dt()},
                          {"dt_coupled_s", s.dt_coupled()},
                          {"dt_de_s", s.dt_de()},
                          {"dt_fe_s", s.dt_fe()},
                          {"steps", nsteps},
                          {"wall_s", clock.seconds()}};
    std::cout << out.dump(2) << std::endl;
    if (!summary.empty())
      demo::write_json(summary, out);
  });
}
