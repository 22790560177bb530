#pragma once
/// @file multipliers.h
/// The Lagrange-multiplier velocity correction of the explicit bridging-
/// domain coupling (docs/method.md section 3.6): for trial velocities
/// v*_DE (constrained particles) and v*_FE (shell dofs),
///   A lambda = G_DE v*_DE - G_FE v*_FE,
///   A = dt (G_DE m~^-1 G_DE^T + G_FE M~^-1 G_FE^T)   (SPD, 3 x 3 blocks),
///   v_DE = v*_DE - dt m~^-1 G_DE^T lambda,  v_FE = v*_FE + dt M~^-1 G_FE^T lambda.
/// G_DE selects the constrained particles; G_FE is the CouplingOperator. A is
/// never formed: by the Woodbury identity only K = M~_FE + G_FE^T m~_DE G_FE,
/// over the FE dofs the overlap touches, is assembled and factorised (sparse
/// LDL^T), once (it is constant while the geometry is linearised), and a
/// correction is v_FE += s, v_DE -= r - G_FE s with r = v*_DE - G_FE v*_FE,
/// s = K^-1 G_FE^T m~_DE r. After the correction the constraint holds to the
/// solver's precision; `correct` returns the residual.

#include "dembridge/bridge/fictive.h"

#include <memory>
#include <span>
#include <vector>

namespace dembridge::bridge
{

class MultiplierSolver
{
public:
  /// @param op G_FE for the constrained particles (in op's order)
  /// @param m_de weighted mass of each constrained particle [kg], > 0
  /// @param m_fe weighted lumped mass of each shell dof (nodes, 6) [kg, kg m^2], > 0
  /// @param dt time step [s]
  /// @throws std::runtime_error on a non-positive mass or if A is not SPD.
  MultiplierSolver(const CouplingOperator& op, std::span<const double> m_de,
                   std::span<const double> m_fe, double dt);
  ~MultiplierSolver();

  /// Corrects v_de (points, 3) and v_fe (nodes, 6) in place; returns the
  /// largest |G_DE v_DE - G_FE v_FE| component after the correction [m/s],
  /// or NaN when `residual` is false (one pass over the points saved).
  double correct(std::span<double> v_de, std::span<double> v_fe, bool residual = true);

  /// Multipliers of the last correction (points, 3) [N]: dt lambda is the
  /// impulse the constraint applies to each particle (with a minus sign).
  std::span<const double> multipliers() const { return _lambda; }

  /// Constraint residual G_DE v_DE - G_FE v_FE (points, 3) [m/s].
  std::vector<double> residual(std::span<const double> v_de, std::span<const double> v_fe) const;

private:
  /// zc = G^T f over the compact FE dofs (overwritten).
  void apply_transpose(std::span<const double> f, std::span<double> zc) const;
  struct Factor;
  const CouplingOperator& _op;
  std::vector<double> _m_de, _m_fe, _lambda, _rhs, _tmp;
  double _dt;
  std::unique_ptr<Factor> _factor;
};

} // namespace dembridge::bridge
