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
#include "options.h"
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
  using demo::Allowed;
  const Allowed angle{0.0, 90.0, false, true, {}, {}};
  demo::add_number(app, "--youngs-modulus", t.youngs_modulus, "target Young's modulus E [Pa]", Allowed::positive(1e12));
  demo::add_number(app, "--poisson-ratio", t.poisson_ratio, "target Poisson's ratio [-]", Allowed::open(0.0, 0.5));
  demo::add_number(app, "--tensile-strength", t.tensile_strength, "target tensile strength sigma_t [Pa]", Allowed::positive(1e9));
  demo::add_number(app, "--compressive-strength", t.compressive_strength, "target compressive strength sigma_c [Pa]", Allowed::positive(1e10));
  demo::add_number(app, "--density", t.density, "bulk density [kg/m^3]", Allowed::positive(1e5));
  demo::add_number(app, "--fracture-energy", t.fracture_energy, "target fracture energy G_f [J/m^2] of the notched tension test", Allowed::positive(1e6).or_value(0.0, "none (zeta kept)"));
  demo::add_number(app, "--softening", c.fixed.zeta, "softening factor zeta (kept; with --fracture-energy the start) [-]", Allowed::positive(1e3));
  demo::add_number(app, "--softening-min", c.zeta_min, "with --fracture-energy: smallest zeta tried [-]", Allowed::positive(1e3));
  demo::add_number(app, "--softening-max", c.zeta_max, "with --fracture-energy: largest zeta tried [-] (above ~20 G_f stops growing)", Allowed::positive(1e3));
  demo::add_number(app, "--ligament", c.ligament, "fracture test: share of the section the mid-height notch keeps [-]", Allowed::above(0.0, 1.0));
  demo::add_number(app, "--phi-i", c.fixed.phi_i_deg, "internal friction angle (kept) [degree]", angle);
  demo::add_number(app, "--phi-c", c.fixed.phi_c_deg, "contact friction angle (kept) [degree]", angle);
  demo::add_choice(app, "--shape", s.shape, "sample shape", "cylinder | prism");
  demo::add_number(app, "--diameter", s.diameter, "sample diameter or side [m]", Allowed::positive(10.0));
  demo::add_number(app, "--height", s.height, "sample height [m]", Allowed::positive(10.0));
  demo::add_number(app, "--mean-radius", s.mean_radius, "mean sphere radius [m]", Allowed::positive(1.0));
  demo::add_number(app, "--radius-ratio", s.radius_ratio, "Rmax / Rmin [-]", Allowed::closed(1.0, 3.0));
  demo::add_integer(app, "--seed", s.seed, "packing seed", Allowed::closed(0, 4294967295.0));
  demo::add_input_file(app, "--packing", s.packing_file, "use this 'x y z r' packing [m]");
  demo::add_integer(app, "--packings", c.packings, "identify the strengths and G_f on the mean over this many packings (seeds seed, seed + 1, ...)", Allowed::closed(1, 100).or_value(0, "2 with --fracture-energy, else 1"));
  demo::add_number(app, "--links-per-sphere", s.links_per_sphere, "mean links per sphere in the bulk (sets lambda)", Allowed::positive(100.0));
  demo::add_number(app, "--strain-rate", s.strain_rate, "platen strain rate [1/s]", Allowed::positive(1e6));
  demo::add_number(app, "--tolerance-elastic", c.tol_elastic, "tolerance on E (relative) and nu (absolute)", Allowed::positive(1.0));
  demo::add_number(app, "--tolerance-strength", c.tol_strength, "relative tolerance on sigma_c/sigma_t", Allowed::positive(1.0));
  demo::add_number(app, "--tolerance-fracture", c.tol_fracture, "relative tolerance on G_f / sigma_t^2", Allowed::positive(1.0));
  app.add_flag("--elastic-only", c.elastic_only, "identify alpha, beta, gamma only");
  app.add_flag("--checks", c.checks,
               "then measure again at half the strain rate (< 1 % asked), on a packing not used (seed + packings) "
               "and on a sample of twice the volume (E 2 %, nu 0.02, strengths 5 %)");
  double local_t = 0.0, local_c0 = 0.0;
  auto* opt_t = demo::add_number(app, "--local-tensile", local_t,
                                 "give the local tensile strength T [Pa] instead of identifying it "
                                 "(with --local-cohesion; the paper's concrete: 3.3e6)", Allowed::positive(1e10));
  auto* opt_c = demo::add_number(app, "--local-cohesion", local_c0,
                                 "give the local cohesion C0 [Pa] (with --local-tensile; the "
                                 "paper's concrete: 4.4e6); sigma_t and sigma_c are then measured", Allowed::positive(1e10));
  opt_t->needs(opt_c);
  opt_c->needs(opt_t);
  opt_t->excludes("--elastic-only");
  demo::add_choice(app, "--plot", plot, "1: write PNG plots with matplotlib, 0: no", "0 | 1");
  demo::add_output_dir(app, "--output", output, "output folder (material.json, curves, plots)");
  demo::add_output_file(app, "--summary", summary, "write target, achieved and parameters as JSON");
  if (const int rc = demo::parse_options(app, argc, argv); rc >= 0)
    return rc;

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
        demo::run_plot_script("plot_stress_strain.py", output, "material.json and history.json are");
    }
    if (!summary.empty())
      demo::write_summary(summary, out);
  }, summary);
}
