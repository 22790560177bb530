#pragma once
/// @file weight.h
/// Energy weight eta(x) of the bridging-domain method (paper's equation [3]):
/// 1 in the FE-only region, 0 in the DE-only region, linear across the
/// overlap (docs/method.md section 3.1).

#include <array>

namespace dembridge::bridge
{

/// Overlap between two parallel planes normal to `axis`: eta = 0 where
/// axis . x <= s_de, eta = 1 where axis . x >= s_fe, linear between.
/// s_fe may be smaller than s_de (then the FE side lies on the low side).
struct PlanarOverlap
{
  std::array<double, 3> axis{1.0, 0.0, 0.0}; ///< unit vector [-]
  double s_de = 0.0;                         ///< [m]
  double s_fe = 1.0;                         ///< [m]
  /// @throws std::runtime_error if the axis is not a unit vector or the planes coincide.
  void validate() const;
  /// eta(x) in [0, 1].
  double weight(const std::array<double, 3>& x) const;
  /// True if x lies in the overlap (strictly between the planes, planes included).
  bool contains(const std::array<double, 3>& x) const;
};

/// Weight floor: max(eta, floor), so that no weighted mass vanishes.
/// @throws std::runtime_error if floor is not in (0, 1).
double floored(double eta, double floor);

} // namespace dembridge::bridge
