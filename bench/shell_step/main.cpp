// shell_step: cost of one explicit step of the shell model, against one bare
// PETSc BAIJ MatMult on the same stiffness matrix.
//
// For each size (about 2k and 20k quadrilaterals by default) it builds a
// cantilever strip, times `--steps` explicit steps (internal forces K u,
// update, boundary conditions), the internal-force call alone, and MatMult
// alone, and prints microseconds per step and per dof.
//
// Sample run:
//   build/bin/shell_step --sizes 2000 20000 --steps 1000 --summary out/shell_step.json
#include "dembridge/shell/explicit.h"
#include "dembridge/shell/mesh.h"
#include "dembridge/shell/model.h"
#include "options.h"
#include "fe_runtime.h"
#include "support.h"

#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>
#include <petscmat.h>

int main(int argc, char** argv)
{
  using namespace dembridge;
  std::vector<int> sizes{2000, 20000};
  int steps = 1000;
  std::string cell = "quadrilateral", output, summary;
  CLI::App app{"Cost of an explicit shell step vs a bare MatMult", "shell_step"};
  using demo::Allowed;
  demo::add_integers(app, "--sizes", sizes, "approximate numbers of cells", Allowed::closed(1, 1e7));
  demo::add_integer(app, "--steps", steps, "timed steps per size", Allowed::closed(1, 1e7));
  demo::add_choice(app, "--cell", cell, "shell cells", "quadrilateral | triangle");
  demo::add_output_dir(app, "--output", output, "output folder (unused: nothing but the summary is written)");
  demo::add_output_file(app, "--summary", summary, "JSON file with the figures");
  if (const int rc = demo::parse_options(app, argc, argv); rc >= 0)
    return rc;

  return demo::run_guarded(argc, argv, [&]
  {
    demo::echo_options(app);
    if (steps < 1)
      throw std::runtime_error("--steps " + std::to_string(steps) + ": must be >= 1");
    nlohmann::json cases = nlohmann::json::array();
    const shell::Cell c = shell::parse_cell(cell);
    std::cout << "    cells       dofs  us/step  us/force  us/MatMult  ns/step/dof  force/MatMult\n";
    for (int n : sizes)
    {
      const double per = c == shell::Cell::triangle ? 2.0 : 1.0;
      const int ny = std::max(1, int(std::round(std::sqrt(n / per / 3.4))));
      const int nx = std::max(1, int(std::round(n / per / ny)));
      auto mesh = shell::create_shell_rectangle(MPI_COMM_WORLD, 0.85, 0.25, nx, ny, c);
      shell::FEModel model(mesh, shell::Material{});
      const auto mass = model.lumped_mass();
      const double dt = 0.9 * model.critical_time_step(mass);
      shell::ExplicitSolver solver(mass, model.internal_force_fn(), dt);
      const auto clamp = shell::select_nodes(model.node_coordinates(),
                                             [](const auto& x) { return x[0] < 1e-9; }, "clamp");
      std::vector<int> all{0, 1, 2, 3, 4, 5};
      solver.add_motion({"clamp", shell::node_dofs(clamp, 6, all), shell::MotionKind::fixed, {}});
      std::vector<double> u(model.num_dofs(), 0.0), v(model.num_dofs(), 0.0), f(model.num_dofs());
      for (std::size_t i = 0; i < u.size(); ++i)
        u[i] = 1e-6 * std::sin(0.001 * i);
      solver.set_state(u, v);

      demo::Stopwatch t1;
      for (int s = 0; s < steps; ++s)
        solver.step();
      const double us_step = 1e6 * t1.seconds() / steps;

      demo::Stopwatch t2;
      for (int s = 0; s < steps; ++s)
        model.internal_force(u, f);
      const double us_force = 1e6 * t2.seconds() / steps;

      Mat K = model.stiffness_matrix();
      Vec x, y;
      MatCreateVecs(K, &x, &y);
      VecSet(x, 1e-6);
      demo::Stopwatch t3;
      for (int s = 0; s < steps; ++s)
        MatMult(K, x, y);
      const double us_mm = 1e6 * t3.seconds() / steps;
      VecDestroy(&x);
      VecDestroy(&y);

      const auto dofs = model.num_dofs();
      std::printf("%9zu %10zu %8.1f %9.1f %11.1f %12.2f %14.2f\n", model.num_cells(), dofs,
                  us_step, us_force, us_mm, 1e3 * us_step / dofs, us_force / us_mm);
      cases.push_back({{"cells", model.num_cells()}, {"dofs", dofs}, {"us_per_step", us_step},
                       {"us_per_force", us_force}, {"us_per_step_matmult", us_mm},
                       {"ns_per_step_per_dof", 1e3 * us_step / dofs},
                       {"force_over_matmult", us_force / us_mm},
                       {"step_over_matmult", us_step / us_mm}, {"dt_s", dt}});
    }
    nlohmann::json out = cases.back();
    out["cases"] = cases;
    out["steps"] = steps;
    out["peak_rss_bytes"] = demo::peak_rss_bytes();
    if (!summary.empty())
      demo::write_summary(summary, out);
  }, summary, demo::petsc_runtime());
}
