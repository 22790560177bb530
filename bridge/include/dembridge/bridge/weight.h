#pragma once
/// @file weight.h
/// Energy weight eta(x) of the bridging-domain method (paper's equation [3]):
/// 1 in the FE-only region, 0 in the DE-only region, linear across the
/// overlap (docs/method.md section 3.1).
///
/// An overlap is a band of width w round the DE-only region (the core): with
/// d(x) the signed distance to the core (< 0 inside it), eta = clamp(d / w,
/// 0, 1). Planes, boxes and cylinders through a slab's thickness are given;
/// any other core is a user function with the same interface.

#include <array>
#include <functional>
#include <optional>
#include <string>

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

/// Signed distance [m] from x to the DE-only core's surface: < 0 inside the
/// core, > 0 outside. Only its value within the band matters; it must grow
/// at unit rate across the band for the weight to be linear in distance.
using CoreDistance = std::function<double(const std::array<double, 3>&)>;

/// An overlap of any shape: the band 0 <= d(x) <= width round the core.
class Overlap
{
public:
  /// The planar overlap (weights and membership exactly PlanarOverlap's).
  Overlap(const PlanarOverlap& p); // NOLINT: a planar overlap is an overlap
  /// A core given by its signed distance; `what` names it in messages.
  Overlap(CoreDistance d, double width, std::string what);
  /// A box core through a slab's thickness: the rectangle |x - cx| <= hx,
  /// |y - cy| <= hy in the plane normal to `normal` (0, 1 or 2; x, y the
  /// other two axes in order), any depth along the normal.
  static Overlap box(std::array<double, 2> centre, std::array<double, 2> half, double width, int normal = 2);
  /// A cylinder core through a slab's thickness: radius r about the line
  /// through `centre` along `normal`.
  static Overlap cylinder(std::array<double, 2> centre, double radius, double width, int normal = 2);

  /// @throws std::runtime_error naming the value: width not > 0, a planar
  ///   overlap's axis or planes, a box's or cylinder's sizes.
  void validate() const;
  double distance(const std::array<double, 3>& x) const { return _d(x); }
  double width() const { return _w; }
  /// eta(x) in [0, 1]: clamp(d / width, 0, 1).
  double weight(const std::array<double, 3>& x) const;
  /// True if 0 <= d(x) <= width (the band, its edges included).
  bool contains(const std::array<double, 3>& x) const;
  /// True beyond the band on the FE side (d > width: eta = 1, the shells'
  /// alone).
  bool beyond(const std::array<double, 3>& x) const;
  /// "a box core, half sizes 0.1 x 0.1 m at (0, 0) m, band 0.05 m", ...
  const std::string& what() const { return _what; }

private:
  CoreDistance _d;
  double _w = 0.0;
  std::string _what;
  std::optional<PlanarOverlap> _planar;
  std::string _invalid; // set by box() or cylinder() on bad sizes
};

/// Weight floor: max(eta, floor), so that no weighted mass vanishes.
/// @throws std::runtime_error if floor is not in (0, 1).
double floored(double eta, double floor);

} // namespace dembridge::bridge
