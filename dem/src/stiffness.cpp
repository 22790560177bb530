#include "dembridge/dem/stiffness.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "errors.h"

namespace dembridge::dem
{
namespace
{
} // namespace

double interaction_surface(double ra, double rb)
{
  if (!(ra > 0.0) || !std::isfinite(ra))
    impl::out_of_range("radius", ra, "> 0 m");
  if (!(rb > 0.0) || !std::isfinite(rb))
    impl::out_of_range("radius", rb, "> 0 m");
  const double r = std::min(ra, rb);
  return std::numbers::pi * r * r;
}

LinkStiffness link_stiffness(double E, double nu, double s_int, double d_init,
                             const MicroMacro& c)
{
  if (!(E > 0.0) || !std::isfinite(E))
    impl::out_of_range("Young's modulus E", E, "> 0 Pa");
  if (!(nu > -1.0 && nu < 0.5))
    impl::out_of_range("Poisson's ratio nu", nu, "in (-1, 0.5)");
  if (!(s_int > 0.0))
    impl::out_of_range("interaction surface", s_int, "> 0 m^2");
  if (!(d_init > 0.0))
    impl::out_of_range("initial distance", d_init, "> 0 m");
  const double den = c.beta * (1.0 + nu) + c.gamma * (1.0 - c.alpha * nu);
  if (!(den > 0.0))
    impl::out_of_range("beta (1 + nu) + gamma (1 - alpha nu)", den, "> 0 (check alpha, beta, gamma)");
  const double kn = E * s_int / d_init * (1.0 + c.alpha) / den;
  const double ks = kn * (1.0 - c.alpha * nu) / (1.0 + nu);
  if (!(kn > 0.0) || ks < 0.0)
    impl::out_of_range("stiffness K_n", kn, "> 0 with K_s >= 0 (check alpha)");
  return {kn, ks};
}

} // namespace dembridge::dem
