#include "dembridge/bridge/weight.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

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

double floored(double eta, double floor)
{
  if (!(floor > 0.0 && floor < 1.0))
    throw std::runtime_error("weight floor " + std::to_string(floor) + ": must be in (0, 1)");
  if (!(eta >= 0.0 && eta <= 1.0))
    throw std::runtime_error("weight " + std::to_string(eta) + ": must be in [0, 1]");
  return std::max(eta, floor);
}

} // namespace dembridge::bridge
