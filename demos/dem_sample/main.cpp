// dem_sample: a discrete element sample of concrete (cylinder or square
// prism) in quasi-static uniaxial tension or compression (docs/method.md
// sections 1.1-1.14). A dense polydisperse packing is generated (or read), bonded with
// cohesive links within lambda (R_a + R_b), and loaded by the platens at a
// constant strain rate with velocity-proportional damping. It reports the
// macroscopic Young's modulus (initial tangent), Poisson's ratio, peak stress
// and the links broken in tension and in shear, and prints the energy budget.
//
// Sample runs:
//   build/bin/dem_sample --test tension --output out/tension --summary out/tension.json
//   build/bin/dem_sample --test compression --shape prism --mean-radius 0.003
//   build/bin/dem_sample --packing my_spheres.txt --lambda 1.4
// Output: DIR/particles.xdmf (+ .h5: positions, radius, displacement,
// velocity, damage, and the broken links as line cells), DIR/stress_strain.csv.
#include "sample.h"
#include "support.h"
#include "dembridge/dem/material_file.h"

#include <CLI/CLI.hpp>
#include <iostream>

int main(int argc, char** argv)
{
  using namespace dembridge;
  demo::SampleConfig c;
  std::string summary;
  auto& m = c.material;
  CLI::App app{"DE sample in quasi-static uniaxial tension or compression", "dem_sample"};
  app.add_option("--test", c.test, "tension | compression")->capture_default_str();
  app.add_option("--shape", c.shape, "cylinder | prism")->capture_default_str();
  app.add_option("--diameter", c.diameter, "cylinder diameter or prism side [m]")->capture_default_str();
  app.add_option("--height", c.height, "sample height [m]")->capture_default_str();
  app.add_option("--mean-radius", c.mean_radius, "mean sphere radius [m]")->capture_default_str();
  app.add_option("--radius-ratio", c.radius_ratio, "Rmax / Rmin, in [1, 3]")->capture_default_str();
  app.add_option("--seed", c.seed, "packing random seed")->capture_default_str();
  app.add_option("--packing", c.packing_file, "read the packing from an 'x y z r' file [m]");
  app.add_option("--lambda", c.lambda, "interaction range factor (>= 1); 0 = from --links-per-sphere")
      ->capture_default_str();
  app.add_option("--links-per-sphere", c.links_per_sphere, "target mean number of links per sphere")
      ->capture_default_str();
  std::string material_file;
  app.add_option("--material", material_file,
                 "DE parameter file (JSON, from calibrate); options given after it override it");
  app.add_option("--youngs-modulus", m.youngs_modulus, "E in equation [1] [Pa]")->capture_default_str();
  app.add_option("--poisson-ratio", m.poisson_ratio, "nu in equation [1] [-]")->capture_default_str();
  app.add_option("--density", m.density, "bulk density of the concrete [kg/m^3]")->capture_default_str();
  app.add_option("--alpha", m.micro.alpha, "alpha of equation [1] [-]")->capture_default_str();
  app.add_option("--beta", m.micro.beta, "beta of equation [1] [-]")->capture_default_str();
  app.add_option("--gamma", m.micro.gamma, "gamma of equation [1] [-]")->capture_default_str();
  app.add_option("--tensile-strength", m.tensile, "local tensile strength T [Pa]")->capture_default_str();
  app.add_option("--cohesion", m.cohesion, "cohesion C0 [Pa]")->capture_default_str();
  app.add_option("--softening", m.zeta, "softening factor zeta [-]")->capture_default_str();
  app.add_option("--phi-i", m.phi_i_deg, "internal friction angle [degree]")->capture_default_str();
  app.add_option("--phi-c", m.phi_c_deg, "contact friction angle [degree]")->capture_default_str();
  app.add_option("--ligament", c.ligament,
                 "notch at mid-height: the ligament's share of the cross-section, in (0, 1]; 1 = no notch "
                 "(stresses and fracture energy are then per ligament area)")->capture_default_str();
  app.add_option("--strain-rate", c.strain_rate, "platen strain rate [1/s]")->capture_default_str();
  app.add_option("--max-strain", c.max_strain, "stop at this strain [-]; 0 = 5e-4 tension, 5e-3 compression")
      ->capture_default_str();
  app.add_option("--stop-ratio", c.stop_ratio, "stop when the stress falls below this x peak [-]")
      ->capture_default_str();
  app.add_flag("--to-separation", c.to_separation,
               "tension until separated: the force through the crack below 1 % of the peak (fracture energy; "
               "--max-strain 0 then means 5e-3)");
  app.add_option("--damping", c.damping, "velocity-proportional damping [1/s]; < 0 = automatic")
      ->capture_default_str();
  app.add_option("--dt", c.dt, "time step [s]; 0 = safety factor x critical")->capture_default_str();
  app.add_option("--safety-factor", c.safety, "fraction of the critical time step")->capture_default_str();
  app.add_option("--frames", c.frames, "XDMF frames if the run goes to --max-strain")->capture_default_str();
  app.add_option("--output", c.output_dir, "output folder (XDMF, CSV); empty = none");
  app.add_option("--summary", summary, "write key results as JSON to this file");
  // --material first, so that explicit options override the file
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--material")
      try
      {
        const auto f = dem::read_material(argv[i + 1]);
        m = f.material;
        c.links_per_sphere = f.links_per_sphere;
      }
      catch (const std::exception& e)
      {
        std::cerr << "error: " << e.what() << std::endl;
        return 1;
      }
  CLI11_PARSE(app, argc, argv);

  return demo::run_guarded(argc, argv, [&]
  {
    demo::echo_options(app);
    const auto r = demo::run_sample(c);
    std::cout << r.dump(2) << std::endl;
    if (!summary.empty())
      demo::write_json(summary, r);
  });
}
