#include "dembridge/shell/analytic.h"

#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace dembridge::shell::analytic
{
namespace
{
constexpr double beta1 = 1.8751040687119611; // first root of cos b cosh b = -1

/// det of the free-end conditions for trial omega (see header).
double timoshenko_det(double omega, double E, double nu, double rho,
                      const BeamSection& s, double L, double k)
{
  const double G = E / (2.0 * (1.0 + nu));
  const double EI = E * s.second_moment(), kGA = k * G * s.area();
  const double rA = rho * s.area(), rI = rho * s.second_moment();
  const double w2 = omega * omega;
  // y = (w, w', psi, psi')
  auto rhs = [&](const std::array<double, 4>& y)
  {
    const double wpp = y[3] - rA * w2 * y[0] / kGA;
    const double psipp = (-kGA * (y[1] - y[2]) - rI * w2 * y[2]) / EI;
    return std::array<double, 4>{y[1], wpp, y[3], psipp};
  };
  auto shoot = [&](std::array<double, 4> y)
  {
    const int n = 2000;
    const double hstep = L / n;
    for (int i = 0; i < n; ++i)
    {
      auto k1 = rhs(y);
      std::array<double, 4> t;
      for (int j = 0; j < 4; ++j) t[j] = y[j] + 0.5 * hstep * k1[j];
      auto k2 = rhs(t);
      for (int j = 0; j < 4; ++j) t[j] = y[j] + 0.5 * hstep * k2[j];
      auto k3 = rhs(t);
      for (int j = 0; j < 4; ++j) t[j] = y[j] + hstep * k3[j];
      auto k4 = rhs(t);
      for (int j = 0; j < 4; ++j)
        y[j] += hstep / 6.0 * (k1[j] + 2 * k2[j] + 2 * k3[j] + k4[j]);
    }
    return y;
  };
  const auto a = shoot({0.0, 1.0, 0.0, 0.0});
  const auto b = shoot({0.0, 0.0, 0.0, 1.0});
  // moment ~ psi', shear ~ w' - psi (scaled to comparable magnitude)
  const double ma = a[3] * L, mb = b[3] * L;
  const double va = a[1] - a[2], vb = b[1] - b[2];
  return ma * vb - mb * va;
}
} // namespace

double axial_clamped_free_frequency(double E, double rho, double L)
{
  return std::sqrt(E / rho) / (4.0 * L);
}

double euler_bernoulli_tip_deflection(double P, double E, const BeamSection& s,
                                      double L)
{
  return P * L * L * L / (3.0 * E * s.second_moment());
}

double timoshenko_tip_deflection(double P, double E, double nu,
                                 const BeamSection& s, double L, double k)
{
  const double G = E / (2.0 * (1.0 + nu));
  return euler_bernoulli_tip_deflection(P, E, s, L) + P * L / (k * G * s.area());
}

double euler_bernoulli_cantilever_frequency(double E, double rho,
                                            const BeamSection& s, double L)
{
  return beta1 * beta1 / (2.0 * std::numbers::pi * L * L)
         * std::sqrt(E * s.second_moment() / (rho * s.area()));
}

double timoshenko_cantilever_frequency(double E, double nu, double rho,
                                       const BeamSection& s, double L, double k)
{
  // Shear and rotary inertia lower the frequency: the root lies below the
  // Euler-Bernoulli one. Scan upward from a low value to bracket it.
  const double w_eb
      = 2.0 * std::numbers::pi * euler_bernoulli_cantilever_frequency(E, rho, s, L);
  double lo = 0.05 * w_eb;
  double flo = timoshenko_det(lo, E, nu, rho, s, L, k);
  double hi = lo;
  for (int i = 0; i < 400; ++i)
  {
    hi = lo + 0.01 * w_eb;
    const double fhi = timoshenko_det(hi, E, nu, rho, s, L, k);
    if (std::signbit(fhi) != std::signbit(flo))
      break;
    lo = hi;
    flo = fhi;
    if (i == 399)
      throw std::runtime_error("timoshenko_cantilever_frequency: no root found");
  }
  for (int it = 0; it < 200 && (hi - lo) > 1e-13 * hi; ++it)
  {
    const double mid = 0.5 * (lo + hi);
    const double fm = timoshenko_det(mid, E, nu, rho, s, L, k);
    if (std::signbit(fm) == std::signbit(flo))
    {
      lo = mid;
      flo = fm;
    }
    else
      hi = mid;
  }
  return 0.5 * (lo + hi) / (2.0 * std::numbers::pi);
}

double cantilever_mode_shape(double x, double L)
{
  const double b = beta1 / L;
  const double sigma = (std::cosh(beta1) + std::cos(beta1))
                       / (std::sinh(beta1) + std::sin(beta1));
  auto phi = [&](double xx)
  {
    return std::cosh(b * xx) - std::cos(b * xx)
           - sigma * (std::sinh(b * xx) - std::sin(b * xx));
  };
  return phi(x) / phi(L);
}

double cantilever_mode_slope(double x, double L)
{
  const double b = beta1 / L;
  const double sigma = (std::cosh(beta1) + std::cos(beta1))
                       / (std::sinh(beta1) + std::sin(beta1));
  const double phiL = std::cosh(beta1) - std::cos(beta1)
                      - sigma * (std::sinh(beta1) - std::sin(beta1));
  return b * (std::sinh(b * x) + std::sin(b * x)
              - sigma * (std::cosh(b * x) - std::cos(b * x)))
         / phiL;
}

} // namespace dembridge::shell::analytic
