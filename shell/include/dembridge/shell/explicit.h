#pragma once
/// @file explicit.h
/// Explicit central-difference time integration in velocity form for a
/// lumped-mass system M a = f_ext - f_int(u) - c M v, with boundary
/// conditions on dof sets. Works on plain arrays; no DOLFINx here, so the
/// same integrator serves any model that provides a mass vector and an
/// internal-force callback.

#include "dembridge/core/checkpoint.h"
#include "dembridge/core/stepping.h"

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace dembridge::shell
{

using core::History;

/// Internal-force callback: f = f_int(u). Spans of length num_dofs.
using InternalForceFn
    = std::function<void(std::span<const double> u, std::span<double> f)>;

/// How a set of dofs is driven (core/stepping.h): fixed, u = 0 and v = 0;
/// velocity, v(t) = value(t) [m/s or rad/s]; displacement, u(t) = value(t)
/// [m or rad].
using core::MotionKind;

/// A kinematic boundary condition on a set of dofs (all get the same value).
struct PrescribedMotion
{
  std::string name;
  std::vector<std::int32_t> dofs;
  MotionKind kind = MotionKind::fixed;
  History value; ///< unused for `fixed`
};

/// External nodal forces f_d = weights[d] * value(t) on the listed dofs.
struct NodalLoad
{
  std::string name;
  std::vector<std::int32_t> dofs;
  std::vector<double> weights; ///< [-] share of value(t) per dof
  History value;               ///< [N] or [N m]
};

/// Energy budget [J]. With no numerical dissipation,
/// kinetic + strain + damping = initial + external_work + prescribed_work.
struct EnergyBudget
{
  double initial = 0.0;         ///< kinetic + strain at the start
  double kinetic = 0.0;
  double strain = 0.0;
  double external_work = 0.0;   ///< work of NodalLoads
  double prescribed_work = 0.0; ///< work of reactions on prescribed dofs
  double damping = 0.0;         ///< dissipated by mass-proportional damping
  /// Energy created (> 0) or lost (< 0) by the integration.
  double imbalance() const
  {
    return kinetic + strain + damping - initial - external_work - prescribed_work;
  }
};

/// Selects nodes whose coordinates satisfy `pred`.
/// @param x node coordinates, shape (num_nodes, 3), row-major [m]
/// @throws std::runtime_error naming `what` if no node is selected.
std::vector<std::int32_t>
select_nodes(std::span<const double> x,
             const std::function<bool(const std::array<double, 3>&)>& pred,
             const std::string& what);

/// Dofs node * bs + c for each node and each component c in `components`.
std::vector<std::int32_t> node_dofs(std::span<const std::int32_t> nodes, int bs,
                                    std::span<const int> components);

/// Explicit integrator, velocity Verlet (= central differences):
///   v(n+1/2) = v(n) + dt/2 a(n),  u(n+1) = u(n) + dt v(n+1/2),
///   a(n+1) = M^-1 (f_ext(n+1) - f_int(u(n+1)) - c M v(n+1/2)),
///   v(n+1) = v(n+1/2) + dt/2 a(n+1).
/// Prescribed dofs follow their motion exactly; their reactions do work.
class ExplicitSolver
{
public:
  /// @param mass lumped mass per dof [kg or kg m^2], all > 0
  /// @param f_int internal force callback
  /// @param dt time step [s], > 0
  /// @param damping mass-proportional damping c [1/s], >= 0
  ExplicitSolver(std::vector<double> mass, InternalForceFn f_int, double dt,
                 double damping = 0.0);

  void add_motion(PrescribedMotion m);
  /// Releases the prescribed motion `name`: its dofs are free from now on
  /// (unless another motion holds them), starting from their current state.
  /// @throws std::runtime_error if no motion has that name.
  void remove_motion(const std::string& name);
  void add_load(NodalLoad l);

  /// Sets u and v at the current time (default zero) and evaluates a(0).
  void set_state(std::span<const double> u, std::span<const double> v);

  /// Advances one step (begin_step then end_step). Throws
  /// std::runtime_error naming the dof and time if a non-finite value appears.
  void step();
  /// First half of a step: v becomes the half-step velocity v(n+1/2) (the
  /// velocities that move the positions); a coupling may correct it through
  /// v_mut() before end_step().
  void begin_step();
  /// Second half: u(n+1) = u(n) + dt v(n+1/2), forces, v(n+1), bookkeeping.
  void end_step();
  /// Velocities, writable (between begin_step and end_step: v(n+1/2)).
  std::span<double> v_mut() { return _v; }

  double time() const { return _t; }
  std::int64_t steps() const { return _steps; }
  double dt() const { return _dt; }
  void set_damping(double c);
  double damping() const { return _c; } ///< [1/s]
  std::span<const double> u() const { return _u; }
  std::span<const double> v() const { return _v; }
  std::span<const double> mass() const { return _m; }
  /// Reaction forces on prescribed dofs at the last step (zero elsewhere).
  std::span<const double> reactions() const { return _r; }
  /// Energy budget at the current time (strain energy = u . f_int / 2,
  /// exact for linear internal forces).
  EnergyBudget energy() const;
  /// The energy guard: every `every` steps, the run stops (std::runtime_error
  /// naming the time, the step and the energies) when the energy not
  /// accounted for by the initial energy and the work done exceeds `margin`
  /// times the energy scale, initial + |work| + kinetic + strain: an
  /// unstable integration creates energy from nothing. A stable run keeps
  /// the share below 1e-3 here; margin 0 turns the guard off. Default 0.5,
  /// every 100 steps.
  void set_energy_guard(double margin, std::int64_t every = 100);

  /// Writes the state at the end of a step (u, v, a, forces, reactions,
  /// time, energies) into checkpoint group `g`.
  void save(const checkpoint::Group& g) const;
  /// Reads a state written by save() into a solver set up as the one that
  /// wrote it (same masses, motions, loads, time step; after set_state):
  /// the run then continues bit for bit. @throws std::runtime_error naming
  /// what differs.
  void load(const checkpoint::Group& g);

private:
  void external_forces(double t, std::span<double> f) const;
  void impose(double t, bool half);

  std::vector<double> _m, _u, _v, _a, _fint, _fext, _fext_new, _r, _v_old;
  bool _in_step = false;
  std::vector<char> _prescribed;
  InternalForceFn _f_int;
  std::vector<PrescribedMotion> _motions;
  std::vector<NodalLoad> _loads;
  double _dt, _c, _t = 0.0;
  std::int64_t _steps = 0;
  core::EnergyGuard _guard;
  EnergyBudget _e;
};

} // namespace dembridge::shell
