// The section theory of a reinforced beam in three-point bending
// (beam.h: beam_theory, BeamTheory::deflection) and the change of slope of
// a measured curve (change_of_slope), which the rc_beam demo compares with.
#include "beam.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace dembridge::demo
{

namespace
{
double steel_area(const BeamConfig& c) { return c.bars * std::numbers::pi * c.bar_diameter * c.bar_diameter / 4.0; }
} // namespace

BeamTheory beam_theory(const BeamConfig& c)
{
  BeamTheory t;
  const double b = c.width, h = c.height, E = c.concrete_modulus, As = steel_area(c);
  t.n = c.steel.youngs_modulus / E;
  t.d = h - c.cover;
  // uncracked: the bars as (n - 1) A_s in place of concrete
  const double A = b * h + (t.n - 1.0) * As;
  t.y_uncracked = (b * h * h / 2.0 + (t.n - 1.0) * As * t.d) / A;
  t.i_uncracked = b * h * h * h / 12.0 + b * h * std::pow(h / 2.0 - t.y_uncracked, 2)
                  + (t.n - 1.0) * As * std::pow(t.d - t.y_uncracked, 2);
  // the flexural tensile strength of fib MC2010 (eq. 5.1-8, as MC90),
  // f_ct,fl = f_ct (1 + 0.06 h^0.7) / (0.06 h^0.7), h in mm: a bending
  // crack starts at a higher stress than a tensile one, the more so the
  // shallower the beam. Eurocode 2's max(1.6 - h / 1 m, 1) f_ct, lower by
  // 10 % at h = 0.1 m, is reported beside it.
  const double hb = std::pow(1e3 * h, 0.7);
  t.f_ct_fl = (1.0 + 0.06 * hb) / (0.06 * hb) * c.tensile_strength;
  t.f_ct_fl_ec2 = std::max(1.6 - h, 1.0) * c.tensile_strength;
  t.m_cracking = t.f_ct_fl * t.i_uncracked / (h - t.y_uncracked);
  // cracked: b c^2 / 2 = n A_s (d - c)
  const double nA = t.n * As;
  t.c_cracked = (-nA + std::sqrt(nA * nA + 2.0 * b * nA * t.d)) / b;
  t.i_cracked = b * std::pow(t.c_cracked, 3) / 3.0 + nA * std::pow(t.d - t.c_cracked, 2);
  t.m_yield = As * c.steel.yield * (t.d - t.c_cracked / 3.0);
  t.p_cracking = 4.0 * t.m_cracking / c.span;
  t.p_yield = 4.0 * t.m_yield / c.span;
  return t;
}

double BeamTheory::deflection(const BeamConfig& c, double P, bool tension_stiffening) const
{
  // delta = 2 int_0^{L/2} M m / (E I) dx, M = P x / 2, m = x / 2; cracked
  // where P x / 2 > M_cr, that is beyond x_cr = 2 M_cr / P
  const double E = c.concrete_modulus, half = c.span / 2.0;
  const double xc = P > 0.0 ? std::min(half, 2.0 * m_cracking / P) : half;
  double bending = P / (2.0 * E)
                   * (xc * xc * xc / (3.0 * i_uncracked) + (half * half * half - xc * xc * xc) / (3.0 * i_cracked));
  // tension stiffening takes (M_t^2 / M) (1 / (E I_cr) - 1 / (E I)) off the
  // cracked part's curvature; with m = x / 2 that is (M_t^2 / P) (...) at
  // every x beyond x_cr
  // (Eurocode 2, 7.1(2): tension stiffening with f_ctm, so zeta's M_cr is
  // the moment at sigma_t, while the cracked zone starts at f_ct,fl's)
  if (tension_stiffening && P > 0.0)
  {
    const double m_ts = m_cracking * c.tensile_strength / f_ct_fl;
    bending -= 2.0 * m_ts * m_ts / P * (1.0 / i_cracked - 1.0 / i_uncracked) / E * (half - xc);
  }
  const double G = E / (2.0 * (1.0 + c.concrete_poisson));
  return bending + P * c.span / (4.0 * 5.0 / 6.0 * G * c.width * c.height);
}

/// (beam.h)
std::array<double, 2> change_of_slope(std::span<const double> x, std::span<const double> y, double x_end)
{
  std::size_t n = 0;
  for (std::size_t k = 0; k < x.size(); ++k)
    n += x[k] > 0.0 && x[k] <= x_end;
  if (n < 4)
    return {0.0, 0.0};
  double best = std::numeric_limits<double>::infinity();
  std::array<double, 2> kink{0.0, 0.0};
  for (int step = 0; step <= 340; ++step)
  {
    // normal equations of y = a u + b v, u = min(x, xb), v = max(x - xb, 0)
    const double xb = (0.05 + 0.0025 * step) * x_end;
    double suu = 0, suv = 0, svv = 0, suy = 0, svy = 0, syy = 0;
    for (std::size_t k = 0; k < x.size(); ++k)
      if (x[k] > 0.0 && x[k] <= x_end)
      {
        const double u = std::min(x[k], xb), v = std::max(x[k] - xb, 0.0);
        suu += u * u, suv += u * v, svv += v * v, suy += u * y[k], svy += v * y[k], syy += y[k] * y[k];
      }
    const double det = suu * svv - suv * suv;
    if (!(det > 1e-12 * suu * svv))
      continue;
    const double a = (suy * svv - svy * suv) / det, b = (svy * suu - suy * suv) / det;
    const double sse = syy - a * suy - b * svy; // at the least-squares solution
    if (sse < best)
    {
      best = sse;
      kink = {xb, a * xb};
    }
  }
  return kink;
}

/// Least-squares slope of y against x over the points with lo <= y <= hi
/// before y first exceeds hi (the loading branch, not the points where the
/// load falls back into the window after a crack).
double slope(const std::vector<double>& x, const std::vector<double>& y, double lo, double hi)
{
  LineFit fit;
  for (std::size_t k = 0; k < x.size() && y[k] <= hi; ++k)
    if (y[k] >= lo)
      fit.add(x[k], y[k]);
  return fit.n < 3 ? 0.0 : fit.slope();
}

} // namespace dembridge::demo
