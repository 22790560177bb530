// shell_cantilever: the concrete bar of the paper (0.85 m x 0.25 m, 0.25 m
// thick) as a cantilever of Reissner-Mindlin shells (or 3D solids), clamped at
// x = 0. It checks the shell module against beam theory:
//   --load axial       free axial vibration from the first mode shape;
//                      first frequency vs c / (4 L)
//   --load bending     free out-of-plane bending vibration from the first
//                      cantilever mode; first frequency vs the Timoshenko
//                      cantilever (k = 5/6, rotary inertia)
//   --load static-tip  tip load P (100 kN); damped explicit run and direct
//                      solve; tip deflection vs Timoshenko P L^3/(3EI) + P L/(kGA)
// Explicit central differences, lumped mass with rotary inertia rho h^3/12,
// internal forces K u (K assembled once). The energy budget is printed.
//
// Sample runs:
//   build/bin/shell_cantilever --load bending
//   build/bin/shell_cantilever --load axial --cell triangle --nx 34 --ny 10
//   build/bin/shell_cantilever --load static-tip --output out/tip --summary out/tip.json
//   build/bin/shell_cantilever --load bending --cell hexahedron --nx 34 --ny 10 --nz 10
// Output (with --output DIR): DIR/cantilever.xdmf (+ .h5) for ParaView,
// DIR/history.csv (tip displacement and energy budget over time).
#include "cantilever.h"
#include "options.h"
#include "fe_runtime.h"
#include "support.h"

#include <CLI/CLI.hpp>
#include <iostream>

int main(int argc, char** argv)
{
  using namespace dembridge;
  demo::CantileverConfig c;
  c.cell = "auto"; // from --mesh, else quadrilateral
  std::string summary;
  std::array<double, 3> axis{0.0, 0.0, 1.0}, shift{0.0, 0.0, 0.0};
  double angle_deg = 0.0;
  auto& m = c.material;

  CLI::App app{"Shell (or solid) cantilever checked against beam theory", "shell_cantilever"};
  using demo::Allowed;
  demo::add_choice(app, "--load", c.load, "what the bar does", "axial | bending | static-tip");
  demo::add_choice(app, "--cell", c.cell,
                   "cells: triangle | quadrilateral (shell); hexahedron | tetrahedron (solid); auto = "
                   "those of --mesh, else quadrilateral",
                   "auto | triangle | quadrilateral | hexahedron | tetrahedron");
  demo::add_integer(app, "--nx", c.nx, "divisions along the length", Allowed::closed(1, 10000));
  demo::add_integer(app, "--ny", c.ny, "divisions across the width", Allowed::closed(1, 10000));
  demo::add_integer(app, "--nz", c.nz, "divisions through the thickness (solids)", Allowed::closed(1, 10000));
  demo::add_input_file(app, "--mesh", c.mesh_file, "XDMF mesh file instead of the structured mesh "
                                                   "(bar along local x from 0 to --length; its cells pick shell or solid)");
  demo::add_number(app, "--length", c.length, "bar length L [m]", Allowed::positive(100.0));
  demo::add_number(app, "--width", c.width, "bar width b [m]", Allowed::positive(100.0));
  demo::add_number(app, "--thickness", m.thickness, "shell thickness / bar depth h [m]", Allowed::positive(10.0));
  demo::add_number(app, "--youngs-modulus", m.youngs_modulus, "Young's modulus E [Pa]", Allowed::positive(1e13));
  demo::add_number(app, "--poisson-ratio", m.poisson_ratio, "Poisson's ratio nu [-]", Allowed::open(-1.0, 0.5));
  demo::add_number(app, "--density", m.density, "density rho [kg/m^3]", Allowed::positive(1e5));
  demo::add_number(app, "--shear-factor", m.shear_factor, "transverse shear factor k [-]", Allowed::positive(10.0));
  demo::add_number(app, "--drilling", m.drilling, "drilling penalty, fraction of G h [-]", Allowed::positive(1e3));
  demo::add_number(app, "--tip-load", c.tip_load, "static tip load P along local z [N]", Allowed::closed(-1e10, 1e10));
  demo::add_number(app, "--amplitude", c.amplitude, "initial modal tip amplitude [m]", Allowed::positive(1.0));
  demo::add_choice(app, "--initial", c.initial,
                   "initial shape (dynamic): mode (FE first mode by inverse iteration) | "
                   "analytic (beam mode shape) | static (tip-load shape)", "mode | analytic | static");
  demo::add_number(app, "--periods", c.periods, "run length in reference periods (dynamic, if --end-time 0)", Allowed::positive(1e4));
  demo::add_number(app, "--end-time", c.end_time, "end time [s]", Allowed::positive(100.0).or_value(0.0, "automatic"));
  demo::add_number(app, "--dt", c.dt, "time step [s]", Allowed::positive(1.0).or_value(0.0, "safety factor x critical"));
  demo::add_number(app, "--safety-factor", c.safety, "fraction of the critical time step (a power-iteration estimate, from below) [-]", Allowed::above(0.0, 0.95));
  demo::add_number(app, "--damping", c.damping, "mass-proportional damping c [1/s]",
                   Allowed::non_negative(1e9).or_value(-1.0, "automatic (0 dynamic, 2 omega_1 static)"));
  demo::add_choice(app, "--solver", c.solver, "static-tip", "explicit | direct | both");
  demo::add_choice(app, "--internal-force", c.force_method, "matmult (K u, K assembled once) | residual", "matmult | residual");
  demo::add_vector(app, "--rotate-axis", axis, "placement: rotation axis [-]", Allowed::closed(-1e6, 1e6));
  demo::add_number(app, "--rotate-angle", angle_deg, "placement: rotation angle [degree]", Allowed::closed(-360.0, 360.0));
  demo::add_vector(app, "--translate", shift, "placement: translation [m]", Allowed::closed(-1e6, 1e6));
  demo::add_integer(app, "--frames", c.frames, "XDMF frames over the run", Allowed::closed(1, 100000));
  demo::RestartOptions restart;
  demo::add_run_options(app, c.output_dir, "output folder (XDMF, CSV); empty = none", summary, restart);
  if (const int rc = demo::parse_run_options(app, argc, argv, restart); rc >= 0)
    return rc;
  c.restart = &restart;

  return demo::run_guarded(argc, argv, [&]
  {
    demo::echo_options(app);
    c.placement = shell::Placement::rotation_about(axis, angle_deg * M_PI / 180.0, shift);
    const auto result = demo::run_cantilever(c);
    std::cout << result.dump(2) << std::endl;
    if (!summary.empty())
      demo::write_summary(summary, result);
  }, summary, demo::petsc_runtime());
}
