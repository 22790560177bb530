#include <array>
#include "dembridge/dem/assembly.h"
#include "dembridge/dem/neighbours.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "errors.h"

namespace dembridge::dem
{
namespace
{
double max_radius(std::span<const double> r)
{
  return r.empty() ? 0.0 : *std::max_element(r.begin(), r.end());
}
} // namespace

void Material::validate() const
{
  if (!(youngs_modulus > 0.0) || !std::isfinite(youngs_modulus))
    impl::out_of_range("Young's modulus E", youngs_modulus, "> 0 Pa");
  if (!(poisson_ratio > -1.0 && poisson_ratio < 0.5))
    impl::out_of_range("Poisson's ratio nu", poisson_ratio, "in (-1, 0.5)");
  if (!(density > 0.0) || !std::isfinite(density))
    impl::out_of_range("density", density, "> 0 kg/m^3");
  if (!(tensile >= 0.0) || !std::isfinite(tensile))
    impl::out_of_range("tensile strength T", tensile, ">= 0 Pa");
  if (!(cohesion >= 0.0) || !std::isfinite(cohesion))
    impl::out_of_range("cohesion C0", cohesion, ">= 0 Pa");
  if (!(zeta >= 0.0) || !std::isfinite(zeta))
    impl::out_of_range("softening factor zeta", zeta, ">= 0");
  if (!(phi_i_deg >= 0.0 && phi_i_deg < 90.0))
    impl::out_of_range("internal friction angle phi_i", phi_i_deg, "in [0, 90) degrees");
  if (!(phi_c_deg >= 0.0 && phi_c_deg < 90.0))
    impl::out_of_range("contact friction angle phi_c", phi_c_deg, "in [0, 90) degrees");
  if (!(rate_fc >= 0.0) || !std::isfinite(rate_fc))
    impl::out_of_range("strain-rate law's compressive strength f_c", rate_fc, ">= 0 Pa (0 = no rate effect)");
  if (!(contact_shear_limit >= 0.0) || !std::isfinite(contact_shear_limit))
    impl::out_of_range("contacts' shear limit", contact_shear_limit, ">= 0 Pa (0 = none)");
  if (!(crack_closure >= 0.0 && crack_closure <= 1.0))
    impl::out_of_range("crack closure", crack_closure, "in [0, 1] (0 = off, 1 = at the links' initial distance)");
  if (!(rolling_friction >= 0.0) || !std::isfinite(rolling_friction))
    impl::out_of_range("contacts' rolling friction mu_r", rolling_friction, ">= 0 (0 = none)");
  if (!(rate_filter >= 0.0 && rate_filter <= 1.0))
    impl::out_of_range("strain-rate filter's time constant", rate_filter, "in [0, 1] s (0 = none)");
  if (!(rate_max >= 0.0) || !std::isfinite(rate_max))
    impl::out_of_range("strain-rate cap", rate_max, ">= 0 1/s (0 = none)");
  const CompactionLaw& c = compaction;
  if (!(c.onset >= 0.0 && c.onset < 1.0))
    impl::out_of_range("compaction onset strain", c.onset, "in [0, 1) (0 = no compaction)");
  if (c.on())
  {
    if (!(c.stiffness > 0.0 && c.stiffness <= 1.0))
      impl::out_of_range("compaction stiffness ratio", c.stiffness, "in (0, 1]");
    if (!(c.lock > c.onset && c.lock < 1.0))
      impl::out_of_range("compaction lock strain", c.lock, "above the onset strain and below 1");
    if (!(c.pressure >= 0.0) || !std::isfinite(c.pressure))
      impl::out_of_range("compaction pressure gate", c.pressure, ">= 0 Pa (0 = none)");
  }
  // eq. [1] must give positive stiffnesses
  (void)link_stiffness(youngs_modulus, poisson_ratio, 1.0, 1.0, micro);
}

LinkLaw Material::law(double ra, double rb, double d_init) const
{
  const double s = interaction_surface(ra, rb);
  const auto k = link_stiffness(youngs_modulus, poisson_ratio, s, d_init, micro);
  const double deg = std::numbers::pi / 180.0;
  // zeta = 0 would make the softening slope infinite: a brittle link
  return {k.kn, k.ks, s, tensile, cohesion, std::tan(phi_i_deg * deg), std::tan(phi_c_deg * deg),
          std::max(zeta, 1e-12), contact_shear_limit};
}

double position_quantum(std::span<const double> x)
{
  double m = 0.0;
  for (double c : x)
    m = std::max(m, std::abs(c));
  if (!(m > 0.0) || !std::isfinite(m))
    return 0.0;
  return std::ldexp(1.0, std::ilogb(m) + 1 - 52);
}

Particles make_particles(std::span<const double> x, std::span<const double> r, double rho_bulk,
                         double packing_fraction)
{
  if (x.size() != 3 * r.size())
    throw std::runtime_error("make_particles: positions must be (n, 3) for n radii");
  if (!(rho_bulk > 0.0))
    impl::out_of_range("density", rho_bulk, "> 0 kg/m^3");
  if (!(packing_fraction > 0.0 && packing_fraction <= 1.0))
    impl::out_of_range("packing fraction", packing_fraction, "in (0, 1]");
  const double rho_s = rho_bulk / packing_fraction;
  Particles p;
  const std::size_t n = r.size();
  p.x.assign(x.begin(), x.end());
  p.quantum = position_quantum(x);
  if (p.quantum > 0.0)
    for (double& c : p.x)
      c = std::nearbyint(c / p.quantum) * p.quantum; // exact: q is a power of 2
  p.x0 = p.x;
  p.v.assign(3 * n, 0.0);
  p.w.assign(3 * n, 0.0);
  p.f.assign(3 * n, 0.0);
  p.t.assign(3 * n, 0.0);
  p.r.assign(r.begin(), r.end());
  p.m.resize(n);
  p.inertia.resize(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    if (!(r[i] > 0.0) || !std::isfinite(r[i]))
      impl::out_of_range("radius of sphere " + std::to_string(i), r[i], "> 0 m");
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(x[3 * i + k]))
        impl::out_of_range("coordinate of sphere " + std::to_string(i), x[3 * i + k], "finite");
    p.m[i] = rho_s * 4.0 / 3.0 * std::numbers::pi * r[i] * r[i] * r[i];
    p.inertia[i] = 0.4 * p.m[i] * r[i] * r[i];
  }
  return p;
}

std::size_t Links::count(LinkState s) const
{
  return static_cast<std::size_t>(std::count(state.begin(), state.end(), s));
}

namespace
{
/// Calls fn(i, j, D) for each pair i < j with D <= lambda (R_i + R_j).
template <typename Fn>
void for_pairs_within(std::span<const double> x, std::span<const double> r, double lambda, Fn&& fn)
{
  const double rmax = max_radius(r);
  CellGrid grid(x, 2.0 * lambda * rmax);
  const std::size_t n = r.size();
  std::vector<std::pair<std::int32_t, double>> found;
  for (std::size_t i = 0; i < n; ++i)
  {
    found.clear();
    grid.for_each_later_near(x, i,
                             [&](std::int32_t j, double d2)
                             {
                               const double lim = lambda * (r[i] + r[j]);
                               if (d2 <= lim * lim)
                                 found.emplace_back(j, std::sqrt(d2));
                             });
    std::sort(found.begin(), found.end());
    for (auto [j, d] : found)
      fn(static_cast<std::int32_t>(i), j, d);
  }
}
} // namespace

std::vector<std::int32_t> floppy_spheres(const Particles& p, const Links& l, double tol)
{
  // each sphere's contact points, relative to its centre
  const std::size_t n = p.size();
  std::vector<std::vector<std::array<double, 3>>> pts(n);
  for (std::size_t k = 0; k < l.size(); ++k)
  {
    if (l.state[k] != LinkState::intact)
      continue;
    const std::int32_t a = l.a[k], b = l.b[k];
    double d[3];
    for (int c = 0; c < 3; ++c)
      d[c] = p.x[3 * b + c] - p.x[3 * a + c];
    const double ra = p.r[a] / (p.r[a] + p.r[b]), rb = p.r[b] / (p.r[a] + p.r[b]);
    pts[a].push_back({ra * d[0], ra * d[1], ra * d[2]});
    pts[b].push_back({-rb * d[0], -rb * d[1], -rb * d[2]});
  }
  std::vector<std::int32_t> out;
  for (std::size_t i = 0; i < n; ++i)
  {
    const auto& q = pts[i];
    bool line = true; // all points on the line through q[0] and the farthest from it
    if (q.size() >= 3)
    {
      std::size_t far = 1;
      double dmax = 0.0;
      for (std::size_t j = 1; j < q.size(); ++j)
      {
        double s2 = 0.0;
        for (int c = 0; c < 3; ++c)
          s2 += (q[j][c] - q[0][c]) * (q[j][c] - q[0][c]);
        if (s2 > dmax)
          dmax = s2, far = j;
      }
      const double e[3] = {q[far][0] - q[0][0], q[far][1] - q[0][1], q[far][2] - q[0][2]};
      for (std::size_t j = 1; j < q.size() && line; ++j)
      {
        const double w[3] = {q[j][0] - q[0][0], q[j][1] - q[0][1], q[j][2] - q[0][2]};
        const double cx = e[1] * w[2] - e[2] * w[1], cy = e[2] * w[0] - e[0] * w[2], cz = e[0] * w[1] - e[1] * w[0];
        // |e x w| / |e| is w's distance from the line
        line = cx * cx + cy * cy + cz * cz <= tol * tol * dmax * dmax;
      }
    }
    if (line)
      out.push_back(static_cast<std::int32_t>(i));
  }
  return out;
}

Links create_links(const Particles& p, double lambda, const Material& mat)
{
  if (!(lambda >= 1.0) || !std::isfinite(lambda))
    impl::out_of_range("interaction range lambda", lambda, ">= 1");
  mat.validate();
  Links l;
  for_pairs_within(p.x, p.r, lambda,
                   [&](std::int32_t i, std::int32_t j, double d)
                   {
                     const LinkLaw law = mat.law(p.r[i], p.r[j], d);
                     l.a.push_back(i);
                     l.b.push_back(j);
                     l.d0.push_back(d);
                     l.kn.push_back(law.kn);
                     l.ks.push_back(law.ks);
                     // as the force loop computes it (times 1 / D): the
                     // same bits, so a link at rest sees no change of its
                     // normal, hence no shear from round-off
                     const double inv = 1.0 / d;
                     for (int k = 0; k < 3; ++k)
                       l.n.push_back((p.x[3 * j + k] - p.x[3 * i + k]) * inv);
                   });
  l.fs.assign(3 * l.size(), 0.0);
  l.delta_max.assign(l.size(), 0.0);
  l.state.assign(l.size(), LinkState::intact);
  return l;
}

std::vector<std::size_t> count_pairs(std::span<const double> x, std::span<const double> r,
                                     std::span<const double> lambdas)
{
  const double lmax = lambdas.empty() ? 1.0 : *std::max_element(lambdas.begin(), lambdas.end());
  std::vector<std::size_t> c(lambdas.size(), 0);
  for_pairs_within(x, r, lmax,
                   [&](std::int32_t i, std::int32_t j, double d)
                   {
                     const double q = d / (r[i] + r[j]);
                     for (std::size_t k = 0; k < lambdas.size(); ++k)
                       if (q <= lambdas[k])
                         ++c[k];
                   });
  return c;
}

double lambda_for_mean_links(std::span<const double> x, std::span<const double> r, double target,
                             std::span<const std::uint8_t> counted)
{
  if (!(target > 0.0))
    impl::out_of_range("target mean links per sphere", target, "> 0");
  if (!counted.empty() && counted.size() != r.size())
    throw std::runtime_error("lambda_for_mean_links: " + std::to_string(counted.size()) + " flags for "
                             + std::to_string(r.size()) + " spheres");
  const std::size_t n = counted.empty() ? r.size()
                                        : static_cast<std::size_t>(std::count(counted.begin(), counted.end(), 1));
  if (n == 0 && counted.empty())
    return 1.0; // no sphere, no link
  if (n == 0)
    throw std::runtime_error("lambda_for_mean_links: no sphere flagged to count links on (is the sample "
                             "too small for its bulk?)");
  // ratios q = D / (Ra + Rb) of all pairs up to 2, each weighing the number
  // of its spheres counted (2 for every pair when all are)
  std::vector<double> q;
  std::vector<std::uint8_t> w;
  for_pairs_within(x, r, 2.0, [&](std::int32_t i, std::int32_t j, double d) {
    const int k = counted.empty() ? 2 : counted[i] + counted[j];
    if (k == 0)
      return;
    q.push_back(d / (r[i] + r[j]));
    if (!counted.empty())
      w.push_back(static_cast<std::uint8_t>(k));
  });
  const auto need = static_cast<std::size_t>(std::ceil(target * n)); // in link ends
  const std::size_t total = counted.empty() ? 2 * q.size() : std::accumulate(w.begin(), w.end(), std::size_t{0});
  if (need == 0)
    return 1.0;
  if (need > total)
  {
    std::ostringstream s;
    s << "a mean of " << target << " links per sphere needs lambda > 2 on this packing (at "
      << "lambda = 2 the mean is " << static_cast<double>(total) / n << ")";
    throw std::runtime_error(s.str());
  }
  if (counted.empty())
  {
    // equal weights: the ceil(need / 2)-th smallest ratio, without a sort
    const std::size_t k = (need + 1) / 2 - 1;
    std::nth_element(q.begin(), q.begin() + k, q.end());
    return std::max(1.0, q[k] * (1.0 + 1e-12));
  }
  std::vector<std::size_t> order(q.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) { return q[i] < q[j]; });
  std::size_t acc = 0;
  for (auto i : order)
    if ((acc += w[i]) >= need)
      return std::max(1.0, q[i] * (1.0 + 1e-12));
  return std::max(1.0, q[order.back()] * (1.0 + 1e-12));
}

} // namespace dembridge::dem
