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
  c.material = DEMBRIDGE_SOURCE_DIR "/demos/calibrate/materials/default.json";
  bool compare = false;
  int seeds = 1;
  std::string summary, python = "/usr/bin/python3";
  CLI::App app{"The paper's validation bar: FE, coupled and DE models, tension and bending, static and dynamic", "bar"};
  app.add_option("--model", c.model, "fe | coupled | de")->capture_default_str();
  app.add_option("--load", c.load, "tension | bending")->capture_default_str();
  app.add_option("--regime", c.regime, "static | dynamic")->capture_default_str();
  app.add_flag("--compare", compare, "run all twelve cases (3 models x 2 loads x 2 regimes) and write the paper's table");
  app.add_option("--seeds", seeds, "with --compare: the twelve cases on this many packings (seed, seed + 1, ...), each in <output>/seed_<s> with its own measured E (unless --fe-youngs-modulus is given), and the models' scatter over them in seeds.md / seeds.json")->capture_default_str();
  app.add_option("--length", c.length, "bar length [m]")->capture_default_str();
  app.add_option("--width", c.width, "side of the square section = shell thickness [m]")->capture_default_str();
  app.add_option("--fe-size", c.fe_size, "shell element size [m] (divides the FE region and the width)")->capture_default_str();
  app.add_option("--cell", c.cell, "shell cells: quadrilateral | triangle")->capture_default_str();
  app.add_option("--mean-radius", c.mean_radius, "DE mean radius [m]")->capture_default_str();
  app.add_option("--radius-ratio", c.radius_ratio, "DE Rmax / Rmin [-]")->capture_default_str();
  app.add_option("--seed", c.seed, "packing seed")->capture_default_str();
  app.add_option("--overlap-start", c.overlap_start, "coupled: DE region and overlap start here [m] (a multiple of fe-size)")->capture_default_str();
  app.add_option("--overlap-layers", c.overlap_layers, "coupled: FE element layers in the overlap")->capture_default_str();
  app.add_option("--probe-de", c.probe_de, "probe in the DE zone [m]")->capture_default_str();
  app.add_option("--probe-overlap", c.probe_overlap, "probe in the overlap (de, coupled models) [m]")->capture_default_str();
  app.add_option("--probe-overlap-fe", c.probe_overlap_fe, "the same probe in the FE model [m]")->capture_default_str();
  app.add_option("--material", c.material, "DE parameter file from calibrate (the FE side takes its measured E, nu, density)")->capture_default_str();
  app.add_option("--fe-youngs-modulus", c.fe_youngs_modulus, "E of the FE side and of beam theory [Pa]; 0 = measured on the DE bar in static tension (a DE run first)")->capture_default_str();
  app.add_option("--skin-compensation", c.skin_compensation, "stiffen the links of the spheres within 2 Rmax of a face by their bulk's links per sphere over their own (true | false)")->capture_default_str();
  app.add_option("--static-force", c.static_force, "static end force [N]; 0 = 100 kN (tension), 20 kN (bending)")->capture_default_str();
  app.add_option("--damping", c.damping, "static damping [1/s]; < 0 = critical for the first mode (2 omega_1, beam theory)")->capture_default_str();
  app.add_option("--end-displacement", c.end_displacement, "dynamic end displacement d0 [m]; 0 = 5e-5 (tension), 2e-4 (bending)")->capture_default_str();
  app.add_option("--ramp-time", c.ramp_time, "dynamic: d0 (1 - cos(pi t / ramp)) / 2, then released [s]; 0 = one first period (beam theory)")->capture_default_str();
  app.add_option("--end-time", c.end_time, "physical time [s]; 0 = 3 first periods (static), ramp + 4 periods (dynamic)")->capture_default_str();
  app.add_option("--safety-factor", c.safety, "fraction of the critical time step, in (0, 1]")->capture_default_str();
  app.add_option("--frames", c.frames, "XDMF output frames")->capture_default_str();
  app.add_option("--python", python, "Python with matplotlib for the --compare plots")->capture_default_str();
  app.add_option("--output", c.output, "output folder (history.csv, shape.csv, shell.xdmf, particles.xdmf); empty = none");
  app.add_option("--summary", summary, "write key results as JSON to this file");
  CLI11_PARSE(app, argc, argv);

  return demo::run_guarded(argc, argv, [&]
  {
    demo::echo_options(app);
    demo::check_config(c);
    if (seeds < 1)
      throw std::runtime_error("seeds " + std::to_string(seeds) + ": allowed is at least 1");
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
        demo::write_json(summary, out);
      return;
    }
    const std::filesystem::path root = c.output.empty() ? std::filesystem::path("out/bar_compare") : std::filesystem::path(c.output);
    auto plot = [&](const std::filesystem::path& dir)
    {
      const std::string cmd = python + " " DEMBRIDGE_SOURCE_DIR "/scripts/plot_bar.py " + dir.string();
      if (std::system(cmd.c_str()) != 0)
        std::cerr << "warning: the plots were not made (" << cmd << " failed); the table and CSV files are written\n";
    };
    if (seeds == 1)
    {
      const auto all = demo::compare_cases(with_modulus(c), root);
      if (!summary.empty())
        demo::write_json(summary, all);
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
    std::ofstream(root / "seeds.md") << md;
    demo::write_json(root / "seeds.json", scatter);
    if (!summary.empty())
      demo::write_json(summary, scatter);
  });
}
