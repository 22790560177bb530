// dem_sample: a discrete element sample of concrete (cylinder or square
// prism) in quasi-static uniaxial tension or compression, or a prism in
// triaxial compression (docs/method.md sections 1.1-1.14). A dense polydisperse packing is generated (or read), bonded with
// cohesive links within lambda (R_a + R_b), and loaded by the platens at a
// constant strain rate with velocity-proportional damping. It reports the
// macroscopic Young's modulus (initial tangent), Poisson's ratio, peak stress
// and the links broken in tension and in shear, and prints the energy budget.
//
// Sample runs:
//   build/bin/dem_sample --test tension --output out/tension --summary out/tension.json
//   build/bin/dem_sample --test compression --shape prism --mean-radius 0.003
//   build/bin/dem_sample --test triaxial --shape prism --confinement 50e6
//   build/bin/dem_sample --packing my_spheres.txt --lambda 1.4
// Output: DIR/particles.xdmf (+ .h5: positions, radius, displacement,
// velocity, damage, and the broken links as line cells), DIR/stress_strain.csv.
#include "sample.h"
#include "options.h"
#include "support.h"
#include "dembridge/dem/material_file.h"

#include <CLI/CLI.hpp>
#include <iostream>

namespace
{
/// The concrete law's options (docs/method.md 1.1-1.7d), each overriding
/// the --material file's value (defined after --material: CLI11 assigns
/// options in the order they are defined).
void add_law_options(CLI::App& app, dembridge::dem::Material& m)
{
  using dembridge::demo::Allowed;
  namespace demo = dembridge::demo;
  const Allowed angle{0.0, 90.0, false, true, {}, {}};
  demo::add_number(app, "--youngs-modulus", m.youngs_modulus, "E in equation [1] [Pa]", Allowed::positive(1e13));
  demo::add_number(app, "--poisson-ratio", m.poisson_ratio, "nu in equation [1] [-]", Allowed::open(-1.0, 0.5));
  demo::add_number(app, "--density", m.density, "bulk density of the concrete [kg/m^3]", Allowed::positive(1e5));
  demo::add_number(app, "--alpha", m.micro.alpha, "alpha of equation [1] [-]", Allowed::closed(-1e3, 1e3));
  demo::add_number(app, "--beta", m.micro.beta, "beta of equation [1] [-]", Allowed::closed(-1e3, 1e3));
  demo::add_number(app, "--gamma", m.micro.gamma, "gamma of equation [1] [-]", Allowed::closed(-1e3, 1e3));
  demo::add_number(app, "--tensile-strength", m.tensile, "local tensile strength T [Pa]", Allowed::non_negative(1e12));
  demo::add_number(app, "--cohesion", m.cohesion, "cohesion C0 [Pa]", Allowed::non_negative(1e12));
  demo::add_number(app, "--softening", m.zeta, "softening factor zeta [-]", Allowed::non_negative(1e6));
  demo::add_number(app, "--phi-i", m.phi_i_deg, "internal friction angle [degree]", angle);
  demo::add_number(app, "--phi-c", m.phi_c_deg, "contact friction angle [degree]", angle);
  demo::add_number(app, "--contact-shear-limit", m.contact_shear_limit,
                   "Tresca limit of the contacts' friction, beside F_c tan(phi_c) [Pa]",
                   Allowed::positive(1e12).or_value(0.0, "none"));
  demo::add_number(app, "--crack-closure", m.crack_closure,
                   "crack closure: the share of a broken link's gap at rest, D_init - (R_a + R_b), at which its "
                   "spheres meet again, with the link's stiffnesses [-]; 1 = at D_init",
                   Allowed::above(0.0, 1.0).or_value(0.0, "off"));
  demo::add_number(app, "--rolling-friction", m.rolling_friction,
                   "rolling resistance of the contacts: mu_r of the cap |M| <= mu_r R* F_c [-]",
                   Allowed::positive(10.0).or_value(0.0, "none"));
  demo::add_number(app, "--rate-fc", m.rate_fc,
                   "strain-rate effect on the links' T and C0: the Malvar-Ross law's compressive strength f_c [Pa]",
                   Allowed::positive(1e10).or_value(0.0, "no rate effect"));
  app.add_flag("--rate-mean-tension", m.rate_mean_tension,
               "strain-rate effect: a link's factor grows only while its spheres' links are, on the whole, stretched");
  app.add_flag("--rate-current", m.rate_current,
               "strain-rate effect: a link's factor follows its current rate, not the largest so far (never below "
               "what the link holds)");
  demo::add_number(app, "--rate-filter", m.rate_filter,
                   "strain-rate effect: time constant of the low-pass filter on each link's rate [s]",
                   Allowed::positive(1.0).or_value(0.0, "no filter"));
}
} // namespace

int main(int argc, char** argv)
{
  using namespace dembridge;
  demo::SampleConfig c;
  std::string summary;
  auto& m = c.material;
  CLI::App app{"DE sample in quasi-static uniaxial tension or compression, or triaxial compression", "dem_sample"};
  using demo::Allowed;
  demo::add_choice(app, "--test", c.test, "the test", "tension | compression | triaxial");
  demo::add_choice(app, "--shape", c.shape, "the sample's shape", "cylinder | prism");
  demo::add_number(app, "--confinement", c.confinement,
                   "triaxial test: the side plates' lateral pressure, reached hydrostatically, then held [Pa]",
                   Allowed::positive(1e10).or_value(0.0, "none: tension or compression"));
  demo::add_number(app, "--diameter", c.diameter, "cylinder diameter or prism side [m]", Allowed::positive(10.0));
  demo::add_number(app, "--height", c.height, "sample height [m]", Allowed::positive(10.0));
  demo::add_number(app, "--mean-radius", c.mean_radius, "mean sphere radius [m]", Allowed::positive(1.0));
  demo::add_number(app, "--radius-ratio", c.radius_ratio, "Rmax / Rmin [-]", Allowed::closed(1.0, 3.0));
  demo::add_integer(app, "--seed", c.seed, "packing random seed", Allowed::closed(0, 4294967295.0));
  demo::add_input_file(app, "--packing", c.packing_file, "read the packing from an 'x y z r' file [m]");
  demo::add_number(app, "--lambda", c.lambda, "interaction range factor [-]",
                   Allowed::closed(1.0, 10.0).or_value(0.0, "from --links-per-sphere"));
  // The file's values are set when --material is read, before the options
  // below it (CLI11 assigns options in the order they are defined): any of
  // them given on the command line overrides the file, wherever it stands.
  // the default concrete: the shipped, calibrated default.json (E 30 GPa,
  // nu 0.2, sigma_t 3 MPa, sigma_c 16.5 MPa on calibrate's default sample)
  std::string material_file = demo::shipped_file("materials/default.json", DEMBRIDGE_SOURCE_DIR "/demos/calibrate/materials/default.json");
  try
  {
    const auto f = dem::read_material(material_file);
    m = f.material;
    c.links_per_sphere = f.links_per_sphere;
  }
  catch (const std::exception& e)
  {
    std::cerr << "error: the default material: " << e.what() << std::endl;
    return 1;
  }
  demo::add_input_file(app, "--material", material_file,
                       "DE parameter file (JSON, from calibrate); the material options given override it")
      ->capture_default_str()
      ->each([&](const std::string& file)
             {
               try
               {
                 const auto f = dem::read_material(file);
                 m = f.material;
                 c.links_per_sphere = f.links_per_sphere;
               }
               catch (const std::exception& e)
               {
                 throw CLI::ValidationError(e.what());
               }
             });
  demo::add_number(app, "--links-per-sphere", c.links_per_sphere, "target mean number of links per sphere in the bulk",
                   Allowed::positive(100.0));
  add_law_options(app, m);
  demo::add_number(app, "--ligament", c.ligament,
                   "notch at mid-height: the ligament's share of the cross-section; 1 = no notch "
                   "(stresses and fracture energy are then per ligament area)", Allowed::above(0.0, 1.0));
  demo::add_number(app, "--strain-rate", c.strain_rate, "platen strain rate [1/s]", Allowed::positive(1e6));
  app.add_flag("--uniform-start", c.uniform_start,
               "dynamic tests: every sphere starts at the affine velocity strain-rate x z, the platens at full "
               "speed (no ramp, no wave from the platens); damping then defaults to 0");
  demo::add_number(app, "--max-strain", c.max_strain, "stop at this strain [-]",
                   Allowed::positive(1.0).or_value(0.0, "5e-4 tension, 5e-3 compression, 3e-2 triaxial"));
  demo::add_number(app, "--stop-ratio", c.stop_ratio, "stop when the stress (triaxial: the deviator) falls below this x peak [-]",
                   Allowed{0.0, 1.0, false, true, {}, {}});
  app.add_flag("--to-separation", c.to_separation,
               "tension until separated: the force through the crack below 1 % of the peak (fracture energy; "
               "--max-strain 0 then means 5e-3)");
  demo::add_number(app, "--damping", c.damping, "velocity-proportional damping [1/s]",
                   Allowed::non_negative(1e9).or_value(-1.0, "the sample's first axial circular frequency"));
  demo::add_number(app, "--dt", c.dt, "time step [s]", Allowed::positive(1.0).or_value(0.0, "safety factor x critical"));
  demo::add_number(app, "--safety-factor", c.safety, "fraction of the critical time step [-]", Allowed::above(0.0, 1.0));
  demo::add_integer(app, "--frames", c.frames, "XDMF frames if the run goes to --max-strain", Allowed::closed(1, 100000));
  demo::RestartOptions restart;
  demo::add_run_options(app, c.output_dir, "output folder (XDMF, CSV); empty = none", summary, restart);
  if (const int rc = demo::parse_run_options(app, argc, argv, restart); rc >= 0)
    return rc;
  c.restart = &restart;

  return demo::run_guarded(argc, argv, [&]
  {
    demo::echo_options(app);
    const auto r = demo::run_sample(c);
    std::cout << r.dump(2) << std::endl;
    if (!summary.empty())
      demo::write_summary(summary, r);
  }, summary);
}
