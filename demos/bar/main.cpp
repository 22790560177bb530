// bar: the paper's validation (section 4). A concrete bar 0.85 x 0.25 x
// 0.25 m fixed at x = 0 and loaded at x = 0.85, as shells (fe), coupled
// shells + discrete elements (coupled) or discrete elements (de); tension or
// bending; static (end force, damped to rest, against beam theory) or
// dynamic (end displacement ramped and released, free vibration; first
// frequency and amplitude at x = 0.75 and x = 0.4351). See bar.h for the
// loading. `--compare` runs all twelve cases and prints the paper's table.
//
// Sample runs:
//   build/bin/bar --model coupled --load tension --regime dynamic --output out/bar
//   build/bin/bar --model de --load bending --regime static --summary out/bar.json
//   build/bin/bar --compare --output out/bar_compare --summary out/bar_compare.json
//   build/bin/bar --compare --seeds 5 --output out/bar_seeds
#include "bar.h"
#include "options.h"
#include "fe_runtime.h"
#include "support.h"

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <vector>

int main(int argc, char** argv)
{
  using namespace dembridge;
  demo::BarConfig c;
  c.material = demo::shipped_file("materials/default.json", DEMBRIDGE_SOURCE_DIR "/demos/calibrate/materials/default.json");
  bool compare = false;
  int seeds = 1;
  std::string summary, python = "/usr/bin/python3";
  CLI::App app{"The paper's validation bar: FE, coupled and DE models, tension and bending, static and dynamic", "bar"};
  using demo::Allowed;
  demo::add_choice(app, "--model", c.model, "model", "fe | coupled | de");
  demo::add_choice(app, "--load", c.load, "load", "tension | bending");
  demo::add_choice(app, "--regime", c.regime, "regime", "static | dynamic");
  app.add_flag("--compare", compare, "run all twelve cases (3 models x 2 loads x 2 regimes) and write the paper's table");
  demo::add_integer(app, "--seeds", seeds, "with --compare: the twelve cases on this many packings (seed, seed + 1, ...), each in <output>/seed_<s> with its own measured E (unless --fe-youngs-modulus is given), and the models' scatter over them in seeds.md / seeds.json", Allowed::closed(1, 100));
  demo::add_number(app, "--length", c.length, "bar length [m]", Allowed::positive(100.0));
  demo::add_number(app, "--width", c.width, "side of the square section = shell thickness [m]", Allowed::positive(10.0));
  demo::add_number(app, "--fe-size", c.fe_size, "shell element size [m] (divides the FE region and the width)", Allowed::positive(10.0));
  demo::add_choice(app, "--cell", c.cell, "shell cells", "quadrilateral | triangle");
  demo::add_number(app, "--mean-radius", c.mean_radius, "DE mean radius [m]", Allowed::positive(1.0));
  demo::add_number(app, "--radius-ratio", c.radius_ratio, "DE Rmax / Rmin [-]", Allowed::closed(1.0, 3.0));
  demo::add_integer(app, "--seed", c.seed, "packing seed", Allowed::closed(0, 4294967295.0));
  demo::add_number(app, "--overlap-start", c.overlap_start, "coupled: DE region and overlap start here [m] (a multiple of fe-size)", Allowed::positive(100.0));
  demo::add_integer(app, "--overlap-layers", c.overlap_layers, "coupled: FE element layers in the overlap", Allowed::closed(1, 1000));
  demo::add_number(app, "--probe-de", c.probe_de, "probe in the DE zone [m]", Allowed::positive(100.0));
  demo::add_number(app, "--probe-overlap", c.probe_overlap, "probe in the overlap (de, coupled models) [m]", Allowed::positive(100.0));
  demo::add_number(app, "--probe-overlap-fe", c.probe_overlap_fe, "the same probe in the FE model [m]", Allowed::positive(100.0));
  demo::add_input_file(app, "--material", c.material, "DE parameter file from calibrate (the FE side takes its measured E, nu, density)")->capture_default_str();
  demo::add_number(app, "--fe-youngs-modulus", c.fe_youngs_modulus, "E of the FE side and of beam theory [Pa]", Allowed::positive(1e13).or_value(0.0, "measured on the DE bar in static tension (a DE run first)"));
  std::string skin = c.skin_compensation ? "true" : "false";
  demo::add_choice(app, "--skin-compensation", skin, "stiffen the links of the spheres within 2 Rmax of a face by their bulk's links per sphere over their own", "true | false");
  demo::add_number(app, "--static-force", c.static_force, "static end force [N]", Allowed::closed(-1e9, 1e9).or_value(0.0, "100 kN (tension), 20 kN (bending)"));
  demo::add_number(app, "--damping", c.damping, "static damping [1/s]", Allowed::non_negative(1e9).or_value(-1.0, "critical for the first mode (2 omega_1, beam theory)"));
  demo::add_number(app, "--end-displacement", c.end_displacement, "dynamic end displacement d0 [m]", Allowed::closed(-1.0, 1.0).or_value(0.0, "5e-5 (tension), 2e-4 (bending)"));
  demo::add_number(app, "--ramp-time", c.ramp_time, "dynamic: d0 (1 - cos(pi t / ramp)) / 2, then released [s]", Allowed::positive(10.0).or_value(0.0, "one first period (beam theory)"));
  demo::add_number(app, "--end-time", c.end_time, "physical time [s]", Allowed::positive(10.0).or_value(0.0, "3 first periods (static), ramp + 4 periods (dynamic)"));
  demo::add_number(app, "--safety-factor", c.safety, "fraction of the critical time step (a power-iteration estimate, from below)", Allowed::above(0.0, 0.95));
  demo::add_integer(app, "--frames", c.frames, "XDMF output frames", Allowed::closed(1, 100000));
  demo::add_program(app, "--python", python, "Python with matplotlib for the --compare plots");
  demo::RestartOptions restart;
  demo::add_run_options(app, c.output, "output folder (history.csv, shape.csv, shell.xdmf, particles.xdmf); empty = none",
                        summary, restart);
  if (const int rc = demo::parse_options(app, argc, argv); rc >= 0)
    return rc;
  c.skin_compensation = skin == "true";
  if (compare && (!restart.restart.empty() || restart.every > 0 || !restart.file.empty()))
  {
    std::cerr << "error: --restart, --checkpoint and --checkpoint-every apply to a single case, not to --compare"
              << std::endl;
    return 2;
  }
  if (const int rc = demo::record_setup(app, restart); rc >= 0)
    return rc;
  if (!compare)
    c.restart = &restart;

  return demo::run_guarded(argc, argv, [&]
  {
    demo::echo_options(app);
    demo::check_config(c);
    if (seeds > 1 && !compare)
      throw std::runtime_error("seeds " + std::to_string(seeds) + ": several seeds need --compare");
    // the E the identified parameters give on a bar's packing (each seed's own)
    auto with_modulus = [&](demo::BarConfig k)
    {
      if (k.fe_youngs_modulus == 0.0)
      {
        k.fe_youngs_modulus = demo::bar_modulus(k);
        std::cout << "# E measured on the DE bar (seed " << k.seed << ") in static tension: " << k.fe_youngs_modulus
                  << " Pa (FE side and beam theory)" << std::endl;
      }
      return k;
    };
    if (!compare)
    {
      const auto out = demo::run_bar(with_modulus(c));
      std::cout << out.dump(2) << std::endl;
      if (!summary.empty())
        demo::write_summary(summary, out);
      return;
    }
    const std::filesystem::path root = c.output.empty() ? std::filesystem::path("out/bar_compare") : std::filesystem::path(c.output);
    auto plot = [&](const std::filesystem::path& dir)
    {
      demo::run_plot_script("plot_bar.py", dir.string(), "the table and CSV files are", python);
    };
    if (seeds == 1)
    {
      const auto all = demo::compare_cases(with_modulus(c), root);
      if (!summary.empty())
        demo::write_summary(summary, all);
      plot(root);
      return;
    }
    // several packings: the twelve cases for each, then their scatter
    std::vector<unsigned> list;
    std::vector<nlohmann::json> tables;
    for (int k = 0; k < seeds; ++k)
    {
      demo::BarConfig s = c;
      s.seed = c.seed + static_cast<unsigned>(k);
      const auto dir = root / ("seed_" + std::to_string(s.seed));
      tables.push_back(demo::compare_cases(with_modulus(s), dir).at("table"));
      list.push_back(s.seed);
      plot(dir);
    }
    std::string md;
    const auto scatter = demo::seeds_table(list, tables, md);
    std::cout << "\n" << md << std::endl;
    demo::write_text(root / "seeds.md", md);
    demo::write_json(root / "seeds.json", scatter);
    if (!summary.empty())
      demo::write_summary(summary, scatter);
  }, summary, demo::petsc_runtime());
}
