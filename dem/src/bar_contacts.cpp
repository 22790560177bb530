// The contacts of spheres with the bars beyond their bonds (bars.h,
// BarContacts): candidate pairs refreshed with the neighbour list, a
// frictionless penalty on the overlap with the nearest element of each bar.
#include "dembridge/dem/bars.h"

#include "bar_grid.h"

#include <algorithm>
#include <cmath>

namespace dembridge::dem
{
namespace
{
bool is_gone(std::span<const std::uint8_t> gone, std::int32_t i) { return !gone.empty() && gone[i]; }

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
      double rho_best = 0.0;
      for (; q < end && bars.line[c.element[q]] == line; ++q)
      {
        const std::int32_t e = c.element[q];
        if (bars.broken[e])
          continue;
        const auto [rho, xi] = distance_to_element(bars, e, x);
        if (best.element < 0 || rho < rho_best)
        {
          best.element = e;
          best.xi = xi;
          rho_best = rho;
        }
      }
      if (best.element < 0 || flags[i] == 1 + line)
        continue;
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
  const double skin = nl.skin();
  bool stale = !c.refreshed || c.version != nl.version() || c.x_refresh.size() != bars.x.size();
  for (std::size_t n = 0; !stale && n < bars.nodes(); ++n)
    stale = std::hypot(bars.x[3 * n] - c.x_refresh[3 * n], bars.x[3 * n + 1] - c.x_refresh[3 * n + 1],
                       bars.x[3 * n + 2] - c.x_refresh[3 * n + 2])
            > 0.5 * skin;
  if (!stale)
    return;
  c.sphere.clear();
  c.element.clear();
  c.x_refresh = bars.x;
  c.version = nl.version();
  c.refreshed = true;
  if (bars.elements() == 0 || p.size() == 0)
    return;
  const double rmax = *std::max_element(p.r.begin(), p.r.end());
  const impl::ElementGrid grid = impl::element_grid(bars, rmax + impl::max_bar_radius(bars) + 2.0 * skin);
  std::vector<std::int32_t> near;
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    if (is_gone(gone, static_cast<std::int32_t>(i)))
      continue;
    near.clear();
    for (const std::int32_t e : grid.near(&p.x[3 * i]))
      if (distance_to_element(bars, e, &p.x[3 * i])[0] < p.r[i] + impl::bar_radius(bars, e) + 2.0 * skin)
        near.push_back(e);
    std::sort(near.begin(), near.end());
    for (const std::int32_t e : near)
    {
      c.sphere.push_back(static_cast<std::int32_t>(i));
      c.element.push_back(e);
    }
  }
}

void bar_contact_forces(Bars& bars, Particles& p, BarContacts& c, const Material& m,
                        std::span<const std::uint8_t> gone)
{
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
  std::vector<std::int32_t> flags;
  mark_bonded(bars, flags, p.size());
  double e = 0.0;
  for_each_touch(bars, p, c, flags, gone, [&](const Touch& t)
                 { e += 0.5 * body_contact_stiffness(m, p.r[t.sphere]) * t.delta * t.delta; });
  return e;
}

} // namespace dembridge::dem
