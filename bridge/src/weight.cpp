#include "dembridge/bridge/weight.h"

#include "dembridge/core/text.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace dembridge::bridge
{

void PlanarOverlap::validate() const
{
  const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  if (std::abs(n - 1.0) > 1e-12)
    throw std::runtime_error("overlap axis has length " + std::to_string(n)
                             + ": must be a unit vector");
  if (!(std::abs(s_fe - s_de) > 0.0))
    throw std::runtime_error("overlap planes coincide (s_de = s_fe = " + std::to_string(s_de)
                             + " m): the overlap needs a width");
}

double PlanarOverlap::weight(const std::array<double, 3>& x) const
{
  const double s = axis[0] * x[0] + axis[1] * x[1] + axis[2] * x[2];
  return std::clamp((s - s_de) / (s_fe - s_de), 0.0, 1.0);
}

bool PlanarOverlap::contains(const std::array<double, 3>& x) const
{
  const double s = axis[0] * x[0] + axis[1] * x[1] + axis[2] * x[2];
  return s >= std::min(s_de, s_fe) && s <= std::max(s_de, s_fe);
}

namespace
{
using core::number_text;

/// The two in-plane axes of a slab whose normal is axis `normal`.
std::array<int, 2> in_plane(int normal)
{
  if (normal == 0)
    return {1, 2};
  if (normal == 1)
    return {0, 2};
  return {0, 1};
}

std::string bad_normal(int normal)
{
  return normal < 0 || normal > 2 ? "normal axis " + std::to_string(normal) + ": allowed are 0, 1, 2 (x, y, z)" : "";
}
} // namespace

Overlap::Overlap(const PlanarOverlap& p)
    : _d([p](const std::array<double, 3>& x)
         {
           const double s = p.axis[0] * x[0] + p.axis[1] * x[1] + p.axis[2] * x[2];
           return p.s_fe > p.s_de ? s - p.s_de : p.s_de - s;
         }),
      _w(std::abs(p.s_fe - p.s_de)), _what("a planar overlap from " + number_text(p.s_de) + " m (DE side) to " + number_text(p.s_fe)
                                         + " m (FE side) along (" + number_text(p.axis[0]) + ", " + number_text(p.axis[1]) + ", "
                                         + number_text(p.axis[2]) + ")"),
      _planar(p)
{
}

Overlap::Overlap(CoreDistance d, double width, std::string what) : _d(std::move(d)), _w(width), _what(std::move(what))
{
  if (!_d)
    _invalid = _what + ": no distance function";
}

Overlap Overlap::box(std::array<double, 2> centre, std::array<double, 2> half, double width, int normal)
{
  const auto [a, b] = in_plane(std::clamp(normal, 0, 2));
  // the rectangle's signed distance: outside, the distance to its nearest
  // point; inside, minus the distance to its nearest side
  Overlap o([=](const std::array<double, 3>& x)
            {
              const double qx = std::abs(x[a] - centre[0]) - half[0], qy = std::abs(x[b] - centre[1]) - half[1];
              const double ox = std::max(qx, 0.0), oy = std::max(qy, 0.0);
              return std::sqrt(ox * ox + oy * oy) + std::min(std::max(qx, qy), 0.0);
            },
            width,
            "a box core, half sizes " + number_text(half[0]) + " x " + number_text(half[1]) + " m about (" + number_text(centre[0]) + ", "
                + number_text(centre[1]) + ") m, band " + number_text(width) + " m");
  o._invalid = bad_normal(normal);
  if (!(half[0] > 0.0 && half[1] > 0.0) || !std::isfinite(half[0]) || !std::isfinite(half[1]))
    o._invalid = "box core half sizes " + number_text(half[0]) + " x " + number_text(half[1]) + " m: both must be > 0";
  return o;
}

Overlap Overlap::cylinder(std::array<double, 2> centre, double radius, double width, int normal)
{
  const auto [a, b] = in_plane(std::clamp(normal, 0, 2));
  Overlap o([=](const std::array<double, 3>& x)
            { return std::hypot(x[a] - centre[0], x[b] - centre[1]) - radius; },
            width,
            "a cylinder core of radius " + number_text(radius) + " m about (" + number_text(centre[0]) + ", " + number_text(centre[1])
                + ") m, band " + number_text(width) + " m");
  o._invalid = bad_normal(normal);
  if (!(radius > 0.0) || !std::isfinite(radius))
    o._invalid = "cylinder core radius " + number_text(radius) + " m: must be > 0";
  return o;
}

void Overlap::validate() const
{
  if (_planar)
    return _planar->validate();
  if (!_invalid.empty())
    throw std::runtime_error(_invalid);
  if (!(_w > 0.0) || !std::isfinite(_w))
    throw std::runtime_error("overlap band width " + number_text(_w) + " m (" + _what + "): must be > 0");
}

double Overlap::weight(const std::array<double, 3>& x) const
{
  return _planar ? _planar->weight(x) : std::clamp(_d(x) / _w, 0.0, 1.0);
}

bool Overlap::contains(const std::array<double, 3>& x) const
{
  if (_planar)
    return _planar->contains(x);
  const double d = _d(x);
  return d >= 0.0 && d <= _w;
}

bool Overlap::beyond(const std::array<double, 3>& x) const { return !contains(x) && weight(x) == 1.0; }

double floored(double eta, double floor)
{
  if (!(floor > 0.0 && floor < 1.0))
    throw std::runtime_error("weight floor " + std::to_string(floor) + ": must be in (0, 1)");
  if (!(eta >= 0.0 && eta <= 1.0))
    throw std::runtime_error("weight " + std::to_string(eta) + ": must be in [0, 1]");
  return std::max(eta, floor);
}

} // namespace dembridge::bridge
