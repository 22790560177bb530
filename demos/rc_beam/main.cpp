// rc_beam: a reinforced-concrete beam of DE concrete with steel bars in
// quasi-static three-point bending (docs/validation.md section 2.10): the
// load against the midspan deflection, the cracking load, the cracked
// stiffness and the load at the bars' first yield, beside reinforced-concrete
// section theory (transformed sections).
//
// Sample runs:
//   build/bin/rc_beam --output out/rc_beam --summary out/rc_beam.json
//   build/bin/rc_beam --bars 3 --bar-diameter 0.005 --mean-radius 0.004
// Output: DIR/particles.xdmf (the spheres and the cracks), DIR/bars.xdmf
// (axial force, plastic strain, slip), DIR/load_deflection.csv,
// DIR/theory_curve.csv, DIR/summary.json and DIR/load_deflection.png.
#include "beam.h"
#include "options.h"
#include "support.h"
#include "dembridge/dem/material_file.h"

#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>

int main(int argc, char** argv)
{
  using namespace dembridge;
  demo::BeamConfig c;
  std::string summary;
  CLI::App app{"RC beam of DE concrete with steel bars in quasi-static three-point bending", "rc_beam"};
  using demo::Allowed;
  // the 48 MPa concrete of the impact scenarios (its macroscopic E and
  // sigma_t feed the section theory)
  std::string material_file = demo::shipped_file("scenarios/concrete-48.json",
                                                 DEMBRIDGE_SOURCE_DIR "/demos/impact/scenarios/concrete-48.json");
  auto read = [&](const std::string& file)
  {
    const auto f = dem::read_material(file);
    c.material = f.material;
    c.links_per_sphere = f.links_per_sphere;
    c.concrete_modulus = f.macroscopic.value("youngs_modulus_pa", f.material.youngs_modulus);
    c.concrete_poisson = f.macroscopic.value("poisson_ratio", f.material.poisson_ratio);
    c.tensile_strength = f.macroscopic.value("tensile_strength_pa", 0.0);
    if (!(c.tensile_strength > 0.0))
      throw std::runtime_error("material file '" + file + "': no macroscopic.tensile_strength_pa (the section "
                               "theory's sigma_t): use a file of calibrate");
  };
  try
  {
    read(material_file);
  }
  catch (const std::exception& e)
  {
    std::cerr << "error: the default material: " << e.what() << std::endl;
    return 1;
  }
  demo::add_input_file(app, "--material", material_file,
                       "DE parameter file (JSON, from calibrate, with its macroscopic E and sigma_t)")
      ->capture_default_str()
      ->each([&](const std::string& file)
             {
               try
               {
                 read(file);
               }
               catch (const std::exception& e)
               {
                 throw CLI::ValidationError(e.what());
               }
             });
  demo::add_number(app, "--span", c.span, "distance between the supports [m]", Allowed::positive(100.0));
  demo::add_number(app, "--overhang", c.overhang, "beam beyond each support [m]", Allowed::positive(10.0));
  demo::add_number(app, "--height", c.height, "beam height [m]", Allowed::positive(10.0));
  demo::add_number(app, "--width", c.width, "beam width [m]", Allowed::positive(10.0));
  demo::add_integer(app, "--bars", c.bars, "number of bars at the bottom", Allowed::closed(1, 100));
  demo::add_number(app, "--bar-diameter", c.bar_diameter, "bar diameter [m]", Allowed::positive(1.0));
  demo::add_number(app, "--cover", c.cover, "bottom face to the bars' axes [m]", Allowed::positive(10.0));
  std::string skin = c.skin_compensation ? "true" : "false";
  demo::add_choice(app, "--skin-compensation", skin,
                   "stiffen the links of the spheres within 2 Rmax of a face by their bulk's links per sphere over "
                   "their own",
                   "true | false")
      ->each([&](const std::string& s) { c.skin_compensation = s == "true"; });
  std::string supports = "hinged";
  demo::add_choice(app, "--supports", supports,
                   "the supports' spheres: hinged (the band turns about its line, as on a roller bearing) or held "
                   "(at rest: the band clamps the beam's rotation over its width)",
                   "hinged | held")
      ->each([&](const std::string& s) { c.hinged_supports = s == "hinged"; });
  demo::add_number(app, "--steel-yield", c.steel.yield, "steel yield strength f_y [Pa]", Allowed::positive(1e11));
  demo::add_number(app, "--steel-hardening", c.steel.hardening, "steel hardening modulus H [Pa]",
                   Allowed::non_negative(1e13));
  demo::add_number(app, "--bond-tau-max", c.bond.tau_max, "peak bond stress (fib MC2010) [Pa]", Allowed::positive(1e10));
  demo::add_number(app, "--mean-radius", c.mean_radius, "mean sphere radius [m]", Allowed::positive(1.0));
  demo::add_integer(app, "--seed", c.seed, "packing random seed", Allowed::closed(0, 4294967295.0));
  demo::add_number(app, "--deflection", c.deflection, "stop at this midspan deflection [m]",
                   Allowed::positive(1.0).or_value(0.0, "2 x the theory's at first yield"));
  demo::add_number(app, "--speed", c.speed, "loading plate speed [m/s]", Allowed::positive(100.0));
  demo::add_number(app, "--ramp-time", c.ramp_time, "time over which the plate reaches its speed [s]",
                   Allowed::positive(10.0).or_value(0.0, "4 periods of the first bending mode"));
  demo::add_number(app, "--damping", c.damping, "velocity-proportional damping [1/s]",
                   Allowed::positive(1e9).or_value(0.0, "0.1 x the first bending mode's circular frequency"));
  demo::add_number(app, "--safety-factor", c.safety, "fraction of the critical time step [-]", Allowed::above(0.0, 1.0));
  demo::add_integer(app, "--frames", c.frames, "XDMF frames", Allowed::closed(1, 100000));
  demo::add_output_dir(app, "--output", c.output_dir, "output folder (XDMF, CSV); empty = none");
  demo::add_output_file(app, "--summary", summary, "write key results as JSON to this file");
  int plot = 1;
  demo::add_integer(app, "--plot", plot, "1: write DIR/load_deflection.png with matplotlib, 0: no",
                    Allowed::closed(0, 1));
  if (const int rc = demo::parse_options(app, argc, argv); rc >= 0)
    return rc;
  return demo::run_guarded(argc, argv, [&]
  {
    demo::echo_options(app);
    const auto r = demo::run_beam(c);
    std::cout << r.dump(2) << std::endl;
    if (!summary.empty())
      demo::write_summary(summary, r);
    if (c.output_dir.empty())
      return;
    const std::filesystem::path dir = c.output_dir;
    demo::write_summary(dir / "summary.json", r);
    if (plot == 1)
    {
      if (demo::run_plot_script("plot_rc_beam.py", c.output_dir, "load_deflection.csv is"))
        std::cout << "plot: " << (dir / "load_deflection.png").string() << "\n";
    }
  }, summary);
}
