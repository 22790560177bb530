// Uses the installed dembridge: a beam reference from the shell library, a
// link stiffness from dem, a weight from bridge, and a form compiled here.
#include "my_shell.h"
#include <dembridge/bridge/weight.h>
#include <dembridge/dem/stiffness.h>
#include <dembridge/shell/analytic.h>
#include <cmath>
#include <cstdio>

int main()
{
  using namespace dembridge;
  const double f = shell::analytic::timoshenko_cantilever_frequency(30e9, 0.2, 2400, {0.25, 0.25}, 0.85, 5.0 / 6);
  const auto k = dem::link_stiffness(30e9, 0.2, dem::interaction_surface(1e-3, 1e-3), 2e-3, {0, 1, 1});
  const double eta = bridge::PlanarOverlap{{1, 0, 0}, 0.0, 1.0}.weight({0.5, 0, 0});
  std::printf("f = %.2f Hz, kn = %.3e N/m, eta = %.2f, form rank %d\n", f, k.kn, eta,
              form_my_shell_a->rank);
  return (std::abs(f - 186.10) < 0.01 && eta == 0.5 && form_my_shell_a->rank == 2) ? 0 : 1;
}
