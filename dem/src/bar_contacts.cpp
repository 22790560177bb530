// The contacts of spheres with the bars beyond their bonds (bars.h,
// BarContacts): candidate pairs refreshed when spheres and nodes may have
// closed a gap of 2 skin, a frictionless penalty on the overlap with the nearest element of each bar.
#include "dembridge/dem/bars.h"

#include "bar_grid.h"

#include <algorithm>
#include <cmath>
#include <omp.h>

namespace dembridge::dem
{
/// The grid of the elements, built for queries within `reach` + `margin`
/// of them from the nodes at `x`: it finds every element within `reach` of
/// a point while no node has moved more than `margin` from `x`.
struct BarGridCache
{
  impl::ElementGrid grid;
  std::vector<double> x;
  double reach = 0.0, margin = 0.0;
};

namespace
{
bool is_gone(std::span<const std::uint8_t> gone, std::int32_t i) { return !gone.empty() && gone[i]; }

/// The largest distance between the points x and their places x0 (3 per
/// point), those flagged in `gone` left out.
double largest_move(std::span<const double> x0, std::span<const double> x, std::span<const std::uint8_t> gone)
{
  double m2 = 0.0;
  for (std::size_t i = 0; i < x.size() / 3; ++i)
  {
    if (is_gone(gone, static_cast<std::int32_t>(i)))
      continue;
    const double d0 = x[3 * i] - x0[3 * i], d1 = x[3 * i + 1] - x0[3 * i + 1], d2 = x[3 * i + 2] - x0[3 * i + 2];
    m2 = std::max(m2, d0 * d0 + d1 * d1 + d2 * d2);
  }
  return std::sqrt(m2);
}

/// The cached grid if it still serves queries within `reach`, else a new one.
std::shared_ptr<const BarGridCache> bar_grid(const Bars& bars, std::shared_ptr<const BarGridCache> cache,
                                             double reach, double margin)
{
  if (cache && cache->reach >= reach && cache->x.size() == bars.x.size()
      && largest_move(cache->x, bars.x, {}) <= cache->margin)
    return cache;
  auto g = std::make_shared<BarGridCache>();
  g->grid = impl::element_grid(bars, reach + margin);
  g->x = bars.x;
  g->reach = reach;
  g->margin = margin;
  return g;
}

/// For each sphere, 1 + the bar (line) it has an intact bond to, or 0.
void mark_bonded(const Bars& bars, std::vector<std::int32_t>& flags, std::size_t spheres)
{
  flags.assign(spheres, 0);
  for (std::size_t k = 0; k < bars.bonds(); ++k)
    if (!bars.open[k])
      flags[bars.sphere[k]] = 1 + bars.line[bars.element[k]];
}

/// One contact: sphere i on element e at xi, overlap delta, unit normal n
/// from the axis to the sphere's centre.
struct Touch
{
  std::int32_t sphere, element;
  double xi, delta;
  double n[3];
};

/// Calls visit(Touch) for every sphere on the nearest unbroken element of
/// each bar it overlaps and has no intact bond to (flags).
template <typename Visit>
void for_each_touch(const Bars& bars, const Particles& p, const BarContacts& c, const std::vector<std::int32_t>& flags,
                    std::span<const std::uint8_t> gone, Visit&& visit)
{
  std::size_t q = 0;
  while (q < c.sphere.size())
  {
    const std::int32_t i = c.sphere[q];
    std::size_t end = q;
    while (end < c.sphere.size() && c.sphere[end] == i)
      ++end;
    if (is_gone(gone, i))
    {
      q = end;
      continue;
    }
    // the candidates of one sphere, by element: a bar's elements are
    // consecutive, so its nearest element is found in one pass of its run
    const double* x = &p.x[3 * i];
    while (q < end)
    {
      const std::int32_t line = bars.line[c.element[q]];
      Touch best{i, -1, 0.0, 0.0, {0.0, 0.0, 0.0}};
      double rho2_best = 0.0;
      for (; q < end && bars.line[c.element[q]] == line; ++q)
      {
        const std::int32_t e = c.element[q];
        if (bars.broken[e])
          continue;
        const auto [rho2, xi] = impl::distance2_to_element(bars, e, x);
        if (best.element < 0 || rho2 < rho2_best)
        {
          best.element = e;
          best.xi = xi;
          rho2_best = rho2;
        }
      }
      if (best.element < 0 || flags[i] == 1 + line)
        continue;
      const double rho_best = std::sqrt(rho2_best);
      best.delta = p.r[i] + impl::bar_radius(bars, best.element) - rho_best;
      if (!(best.delta > 0.0) || !(rho_best > 0.0))
        continue; // apart, or the centre on the axis (no normal; a sphere never gets there)
      const double* pa = &bars.x[3 * bars.a[best.element]];
      const double* pb = &bars.x[3 * bars.b[best.element]];
      for (int k = 0; k < 3; ++k)
        best.n[k] = (x[k] - (pa[k] + best.xi * (pb[k] - pa[k]))) / rho_best;
      visit(best);
    }
  }
}
} // namespace

void refresh_bar_contacts(const Bars& bars, const Particles& p, BarContacts& c, const NeighbourList& nl,
                          std::span<const std::uint8_t> gone)
{
  // a pair left out at the refresh had a gap of at least 2 skin: it can
  // close only once the largest move of a sphere plus that of a node since
  // then reach it
  const double skin = nl.skin();
  if (c.refreshed && c.x_refresh.size() == bars.x.size() && c.x_spheres.size() == p.x.size()
      && largest_move(c.x_spheres, p.x, gone) + largest_move(c.x_refresh, bars.x, {}) < 2.0 * skin)
    return;
  c.sphere.clear();
  c.element.clear();
  c.x_refresh = bars.x;
  c.x_spheres = p.x;
  c.refreshed = true;
  if (bars.elements() == 0 || p.size() == 0 || !bars.sphere_contacts)
    return;
  const double rmax = *std::max_element(p.r.begin(), p.r.end());
  c.grid = bar_grid(bars, c.grid, rmax + impl::max_bar_radius(bars) + 2.0 * skin, 2.0 * skin);
  const impl::ElementGrid& grid = c.grid->grid;
  // each thread scans a contiguous range of spheres; the ranges joined in
  // order give the same pairs, by sphere then element, on any thread count
  std::vector<std::vector<std::int32_t>> spheres(omp_get_max_threads()), elements(spheres.size());
#pragma omp parallel
  {
    const std::size_t t = omp_get_thread_num(), nt = omp_get_num_threads();
    std::vector<std::int32_t>& ps = spheres[t];
    std::vector<std::int32_t>& pe = elements[t];
    for (std::size_t i = p.size() * t / nt; i < p.size() * (t + 1) / nt; ++i)
    {
      if (is_gone(gone, static_cast<std::int32_t>(i)))
        continue;
      // the grid lists each cell's elements in increasing order
      for (const std::int32_t e : grid.near(&p.x[3 * i]))
      {
        const double reach = p.r[i] + impl::bar_radius(bars, e) + 2.0 * skin;
        if (impl::distance2_to_element(bars, e, &p.x[3 * i])[0] < reach * reach)
        {
          ps.push_back(static_cast<std::int32_t>(i));
          pe.push_back(e);
        }
      }
    }
  }
  for (std::size_t t = 0; t < spheres.size(); ++t)
  {
    c.sphere.insert(c.sphere.end(), spheres[t].begin(), spheres[t].end());
    c.element.insert(c.element.end(), elements[t].begin(), elements[t].end());
  }
}

void bar_contact_forces(Bars& bars, Particles& p, BarContacts& c, const Material& m,
                        std::span<const std::uint8_t> gone)
{
  if (!bars.sphere_contacts)
    return;
  mark_bonded(bars, c.bonded, p.size());
  for_each_touch(bars, p, c, c.bonded, gone, [&](const Touch& t)
                 {
                   const double F = body_contact_stiffness(m, p.r[t.sphere]) * t.delta;
                   double* fa = &bars.f[3 * bars.a[t.element]];
                   double* fb = &bars.f[3 * bars.b[t.element]];
                   for (int k = 0; k < 3; ++k)
                   {
                     p.f[3 * t.sphere + k] += F * t.n[k];
                     fa[k] -= (1.0 - t.xi) * F * t.n[k];
                     fb[k] -= t.xi * F * t.n[k];
                   }
                 });
}

double bar_contact_energy(const Bars& bars, const Particles& p, const BarContacts& c, const Material& m,
                          std::span<const std::uint8_t> gone)
{
  if (!bars.sphere_contacts)
    return 0.0;
  std::vector<std::int32_t> flags;
  mark_bonded(bars, flags, p.size());
  double e = 0.0;
  for_each_touch(bars, p, c, flags, gone, [&](const Touch& t)
                 { e += 0.5 * body_contact_stiffness(m, p.r[t.sphere]) * t.delta * t.delta; });
  return e;
}

} // namespace dembridge::dem
