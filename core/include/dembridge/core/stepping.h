#pragma once
/// @file stepping.h
/// What the explicit steppers of every module share (docs/architecture.md,
/// "The stepping contract"): the action of a linear operator on plain
/// arrays, and the critical time step by power iteration. dem/ and shell/
/// compute their own and the coupled critical steps with it.

#include <functional>
#include <span>

namespace dembridge::core
{

/// The action out = K z of a linear operator K on plain arrays (a stiffness:
/// internal forces of the displacements z).
using LinearAction = std::function<void(std::span<const double> z, std::span<double> out)>;

/// Largest eigenvalue of M^-1 K by power iteration on M^-1/2 K M^-1/2,
/// K given by its action `k` (linear), M diagonal (`mass`). Stops when the
/// Rayleigh quotient changes by less than `rtol` or after `max_iter`
/// iterations. Returns lambda_max [1/s^2]; the critical step of the central
/// differences is 2 / sqrt(lambda_max). With `project`, the iteration runs
/// on the motions it leaves unchanged: it must be the mass-orthogonal
/// projection onto them (a linear constraint on velocities, as the
/// coupling's multiplier correction), and the result is lambda_max of the
/// constrained system.
/// @throws std::runtime_error if the iterate vanishes (no free motion).
double max_eigenvalue(std::span<const double> mass, const LinearAction& k, double rtol = 1e-6,
                      int max_iter = 5000, const std::function<void(std::span<double>)>& project = {});

} // namespace dembridge::core
