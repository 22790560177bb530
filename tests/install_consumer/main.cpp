// Uses the installed dembridge as a user's program would: PETSc (and MPI)
// initialised first, as the shell module's models need it; a shell model
// and its critical time step, a beam reference, a link stiffness from dem, a
// weight from bridge, and a form compiled here.
#include "my_shell.h"
#include <dembridge/bridge/weight.h>
#include <dembridge/dem/stiffness.h>
#include <dembridge/shell/analytic.h>
#include <dembridge/shell/mesh.h>
#include <dembridge/shell/model.h>
#include <cmath>
#include <cstdio>
#include <mpi.h>
#include <petscsys.h>

int main(int argc, char** argv)
{
  using namespace dembridge;
  PetscInitialize(&argc, &argv, nullptr, nullptr); // also initialises MPI
  int ok = 0;
  {
    shell::Material m; // E 30 GPa, nu 0.2, rho 2400 kg/m^3
    m.thickness = 0.25;
    const auto mesh = shell::create_shell_rectangle(MPI_COMM_WORLD, 0.85, 0.25, 17, 5, shell::Cell::quadrilateral);
    const shell::FEModel model(mesh, m);
    const double dt = model.critical_time_step(model.lumped_mass());
    const double f = shell::analytic::timoshenko_cantilever_frequency(30e9, 0.2, 2400, {0.25, 0.25}, 0.85, 5.0 / 6);
    const auto k = dem::link_stiffness(30e9, 0.2, dem::interaction_surface(1e-3, 1e-3), 2e-3, {0, 1, 1});
    const double eta = bridge::PlanarOverlap{{1, 0, 0}, 0.0, 1.0}.weight({0.5, 0, 0});
    std::printf("shell model: %zu nodes, critical step %.3e s; f = %.2f Hz, kn = %.3e N/m, eta = %.2f, form rank %d\n",
                model.num_nodes(), dt, f, k.kn, eta, form_my_shell_a->rank);
    ok = dt > 0.0 && std::abs(f - 186.10) < 0.01 && eta == 0.5 && form_my_shell_a->rank == 2;
  }
  PetscFinalize();
  return ok ? 0 : 1;
}
