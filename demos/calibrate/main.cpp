// calibrate: identifies the DE parameters (alpha, beta, gamma, T, C0) that
// reproduce a concrete's E, nu, tensile and compressive strengths on a DE
// sample, by simulated quasi-static tension and compression tests (section
// 2.2 of the paper; the method is in identify.h). zeta, phi_i, phi_c are kept
// as given. Writes the parameter file that the other demos read with
// --material FILE, the final stress-strain curves (CSV) and their plots (PNG,
// like the paper's Figures 3 and 4).
//
// Sample runs:
//   build/bin/calibrate --output out/calibration --summary out/calibration.json
//   build/bin/calibrate --tensile-strength 4e6 --compressive-strength 28e6 --mean-radius 0.003
//   build/bin/calibrate --elastic-only --poisson-ratio 0.18
#include "identify.h"
#include "support.h"

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <iostream>

int main(int argc, char** argv)
{
  using namespace dembridge;
  demo::IdentifyConfig c;
  auto& t = c.target;
  auto& s = c.sample;
  std::string output, summary, plot = "1";
  CLI::App app{"Identification of the DE parameters from macroscopic concrete properties", "calibrate"};
  app.add_option("--youngs-modulus", t.youngs_modulus, "target Young's modulus E [Pa]")->capture_default_str();
  app.add_option("--poisson-ratio", t.poisson_ratio, "target Poisson's ratio [-]")->capture_default_str();
  app.add_option("--tensile-strength", t.tensile_strength, "target tensile strength sigma_t [Pa]")
      ->capture_default_str();
  app.add_option("--compressive-strength", t.compressive_strength,
                 "target compressive strength sigma_c [Pa]")->capture_default_str();
  app.add_option("--density", t.density, "bulk density [kg/m^3]")->capture_default_str();
  app.add_option("--fracture-energy", t.fracture_energy,
                 "target fracture energy G_f [J/m^2] of the notched tension test; 0 = none (zeta kept)")
      ->capture_default_str();
  app.add_option("--softening", c.fixed.zeta, "softening factor zeta (kept; with --fracture-energy the start) [-]")
      ->capture_default_str();
  app.add_option("--softening-min", c.zeta_min, "with --fracture-energy: smallest zeta tried [-]")
      ->capture_default_str();
  app.add_option("--softening-max", c.zeta_max,
                 "with --fracture-energy: largest zeta tried [-] (above ~20 G_f stops growing)")
      ->capture_default_str();
  app.add_option("--ligament", c.ligament,
                 "fracture test: share of the section the mid-height notch keeps, in (0, 1]")
      ->capture_default_str();
  app.add_option("--phi-i", c.fixed.phi_i_deg, "internal friction angle (kept) [degree]")->capture_default_str();
  app.add_option("--phi-c", c.fixed.phi_c_deg, "contact friction angle (kept) [degree]")->capture_default_str();
  app.add_option("--shape", s.shape, "sample: cylinder | prism")->capture_default_str();
  app.add_option("--diameter", s.diameter, "sample diameter or side [m]")->capture_default_str();
  app.add_option("--height", s.height, "sample height [m]")->capture_default_str();
  app.add_option("--mean-radius", s.mean_radius, "mean sphere radius [m]")->capture_default_str();
  app.add_option("--radius-ratio", s.radius_ratio, "Rmax / Rmin")->capture_default_str();
  app.add_option("--seed", s.seed, "packing seed")->capture_default_str();
  app.add_option("--packing", s.packing_file, "use this 'x y z r' packing [m]");
  app.add_option("--packings", c.packings,
                 "identify the strengths and G_f on the mean over this many packings (seeds seed, "
                 "seed + 1, ...); 0 = 2 with --fracture-energy, else 1")
      ->capture_default_str();
  app.add_option("--links-per-sphere", s.links_per_sphere, "mean links per sphere (sets lambda)")
      ->capture_default_str();
  app.add_option("--strain-rate", s.strain_rate, "platen strain rate [1/s]")->capture_default_str();
  app.add_option("--tolerance-elastic", c.tol_elastic, "tolerance on E (relative) and nu (absolute)")
      ->capture_default_str();
  app.add_option("--tolerance-strength", c.tol_strength, "relative tolerance on sigma_c/sigma_t")
      ->capture_default_str();
  app.add_option("--tolerance-fracture", c.tol_fracture, "relative tolerance on G_f / sigma_t^2")
      ->capture_default_str();
  app.add_flag("--elastic-only", c.elastic_only, "identify alpha, beta, gamma only");
  app.add_flag("--checks", c.checks,
               "then measure again at half the strain rate (< 1 % asked), on a packing not used (seed + packings) "
               "and on a sample of twice the volume (E 2 %, nu 0.02, strengths 5 %)");
  double local_t = 0.0, local_c0 = 0.0;
  auto* opt_t = app.add_option("--local-tensile", local_t,
                               "give the local tensile strength T [Pa] instead of identifying it "
                               "(with --local-cohesion; the paper's concrete: 3.3e6)");
  auto* opt_c = app.add_option("--local-cohesion", local_c0,
                               "give the local cohesion C0 [Pa] (with --local-tensile; the "
                               "paper's concrete: 4.4e6); sigma_t and sigma_c are then measured");
  opt_t->needs(opt_c);
  opt_c->needs(opt_t);
  opt_t->excludes("--elastic-only");
  app.add_option("--plot", plot, "1: write PNG plots with matplotlib, 0: no")->capture_default_str();
  app.add_option("--output", output, "output folder (material.json, curves, plots)");
  app.add_option("--summary", summary, "write target, achieved and parameters as JSON");
  CLI11_PARSE(app, argc, argv);

  return demo::run_guarded(argc, argv, [&]
  {
    demo::echo_options(app);
    if (*opt_t)
    {
      c.given_local_strengths = true;
      c.fixed.tensile = local_t;
      c.fixed.cohesion = local_c0;
    }
    demo::Stopwatch clock;
    c.output_dir = output;
    std::cout << "simulated tests:" << std::endl;
    const auto r = demo::identify(c);
    const auto& m = r.file.material;
    nlohmann::json out;
    out["target"] = {{"youngs_modulus_pa", t.youngs_modulus}, {"poisson_ratio", t.poisson_ratio}};
    if (!c.elastic_only && !c.given_local_strengths)
    {
      out["target"]["tensile_strength_pa"] = t.tensile_strength;
      out["target"]["compressive_strength_pa"] = t.compressive_strength;
      if (t.fracture_energy > 0.0)
        out["target"]["fracture_energy_j_m2"] = t.fracture_energy;
    }
    out["achieved"] = r.achieved;
    out["parameters"] = {{"alpha", m.micro.alpha}, {"beta", m.micro.beta}, {"gamma", m.micro.gamma},
                         {"tensile_strength_pa", m.tensile}, {"cohesion_pa", m.cohesion},
                         {"softening", m.zeta}, {"phi_i_deg", m.phi_i_deg},
                         {"phi_c_deg", m.phi_c_deg}, {"lambda", r.file.lambda}};
    if (c.checks)
      out["checks"] = r.checks;
    out["simulated_tests"] = r.history.size();
    out["particles"] = r.compression["particles"];
    out["wall_s"] = clock.seconds();
    std::cout << out.dump(2) << std::endl;
    if (!output.empty())
    {
      dem::write_material(std::filesystem::path(output) / "material.json", r.file);
      demo::write_json(std::filesystem::path(output) / "history.json", r.history);
      std::cout << "parameter file: " << (std::filesystem::path(output) / "material.json") << std::endl;
      if (plot == "1")
      {
        const std::string cmd = "/usr/bin/python3 " DEMBRIDGE_SOURCE_DIR
                                "/scripts/plot_stress_strain.py " + output;
        if (std::system(cmd.c_str()) != 0)
          std::cerr << "warning: the plots could not be made (python3-matplotlib missing?)\n";
      }
    }
    if (!summary.empty())
      demo::write_json(summary, out);
  });
}
