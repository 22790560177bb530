#pragma once
/// @file stepping.h
/// What the explicit steppers of every module share (docs/architecture.md,
/// "The stepping contract"): the action of a linear operator on plain
/// arrays, and the critical time step by power iteration. dem/ and shell/
/// compute their own and the coupled critical steps with it.

#include <cstdint>
#include <functional>
#include <span>
#include <string>

namespace dembridge::core
{

/// A scalar history of time: value(t) in SI units (what a prescribed
/// motion or a load follows).
using History = std::function<double(double)>;

/// How a prescribed motion drives its set (a shell's dofs, a set of
/// spheres): held, at a velocity value(t), or at a displacement value(t)
/// from where it started.
enum class MotionKind
{
  fixed,
  velocity,
  displacement
};

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

/// The energy guard of an explicit run: on the steps it is due (every
/// `every` steps), the energy not accounted for by the initial energy and
/// the work done (the budget's imbalance) must stay within `margin` times
/// the energy scale (initial + |work| + the stored energies): an unstable
/// integration creates energy from nothing, and the run stops with a
/// message naming the time, the step and the energies. Margin 0 turns it
/// off. The DE, shell and coupled steppers each guard their own budget.
class EnergyGuard
{
public:
  /// @throws std::runtime_error unless margin >= 0 (finite) and every >= 1
  void set(double margin, std::int64_t every = 100);
  double margin() const { return _margin; }
  bool on() const { return _margin > 0.0; }
  /// The full check is due after `step`.
  bool due(std::int64_t step) const { return on() && step % _every == 0; }

  /// What a check reads of a budget: the time and step, the energy stored
  /// (kinetic and elastic) with its name in the message, the initial
  /// energy, the work done, the imbalance and the energy scale [J].
  struct Budget
  {
    double t;
    std::int64_t step;
    const char* system;  ///< "the energy", "the coupled system's energy"
    const char* stored_name; ///< "kinetic + elastic", ...
    double stored, initial, work, imbalance, scale;
  };
  /// @throws std::runtime_error when the imbalance exceeds margin x scale
  void check(const Budget& b) const;

private:
  double _margin = 0.5;
  std::int64_t _every = 100;
};

} // namespace dembridge::core
