// The packing round the bars (bars.h): the distance to a bar's element, the
// spheres that lie on bars, the region less the bars (a grid of the
// elements sorted by distance), room made in a packing, and the concrete's
// fraction.
#include "dembridge/dem/bars.h"

#include "bar_grid.h"
#include "errors.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace dembridge::dem
{
using namespace impl; // the bars' element grid (bar_grid.h), dot and errors.h

std::array<double, 2> distance_to_element(const Bars& bars, std::size_t e, const double* x)
{
  const double* pa = &bars.x[3 * bars.a[e]];
  const double* pb = &bars.x[3 * bars.b[e]];
  const double d[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
  const double r[3] = {x[0] - pa[0], x[1] - pa[1], x[2] - pa[2]};
  const double xi = std::clamp(dot(r, d) / dot(d, d), 0.0, 1.0);
  const double q[3] = {r[0] - xi * d[0], r[1] - xi * d[1], r[2] - xi * d[2]};
  return {std::sqrt(dot(q, q)), xi};
}


std::vector<std::uint8_t> spheres_on_bars(const Bars& bars, std::span<const double> centres,
                                          std::span<const double> radii, double tolerance)
{
  std::vector<std::uint8_t> on(radii.size(), 0);
  double reach = 0.0;
  for (double r : radii)
    reach = std::max(reach, r);
  reach += max_bar_radius(bars);
  const ElementGrid grid = element_grid(bars, reach);
  for (std::size_t i = 0; i < radii.size(); ++i)
    on[i] = std::get<0>(nearest_element(bars, grid, &centres[3 * i], [&](std::size_t e)
                                        { return radii[i] + bar_radius(bars, e) - tolerance; }))
            >= 0;
  return on;
}


namespace
{
/// The bars' elements near each cell of an ElementGrid, sorted by a lower
/// bound of their surface's distance from any point of the cell: the
/// distance between the cell's box and the element's axis' box, less its
/// bar radius (a point's distance to a segment is at least that to the
/// segment's box). A query scans its cell's list in that order and stops
/// at the first bound past what it has found, so that it evaluates the few
/// nearest elements of a cell, not every element within the grid's reach.
struct SortedElements
{
  ElementGrid grid;
  std::vector<double> bound; ///< per item of grid.items, ascending in each cell
  /// per element: its first node a, its axis d = b - a, d.d and its bar
  /// radius, for surface_distance
  std::vector<double> seg;

  /// The distance from x to element e's surface: distance_to_element's
  /// axis distance, computed in the same operations from the same values
  /// (so the same bits), less the bar radius.
  double surface_distance(std::int32_t e, const double* x) const
  {
    const double* s = &seg[8 * e];
    const double r[3] = {x[0] - s[0], x[1] - s[1], x[2] - s[2]};
    const double xi = std::clamp((r[0] * s[3] + r[1] * s[4] + r[2] * s[5]) / s[6], 0.0, 1.0);
    const double q[3] = {r[0] - xi * s[3], r[1] - xi * s[4], r[2] - xi * s[5]};
    return std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]) - s[7];
  }

  SortedElements(const Bars& bars, double reach) : grid(element_grid(bars, reach))
  {
    seg.resize(8 * bars.elements());
    for (std::size_t e = 0; e < bars.elements(); ++e)
    {
      const double* pa = &bars.x[3 * bars.a[e]];
      const double* pb = &bars.x[3 * bars.b[e]];
      double* s = &seg[8 * e];
      for (int k = 0; k < 3; ++k)
      {
        s[k] = pa[k];
        s[3 + k] = pb[k] - pa[k];
      }
      s[6] = s[3] * s[3] + s[4] * s[4] + s[5] * s[5];
      s[7] = bar_radius(bars, e);
    }
    bound.resize(grid.items.size());
    const std::size_t cells = grid.start.size() - 1;
    // a margin below the bound: the computed distances may fall below the
    // exact ones by rounding, and no element may be skipped for it
    const double margin = 1e-9 * (grid.cell + reach);
    std::vector<std::pair<double, std::int32_t>> list;
    for (std::size_t id = 0; id < cells; ++id)
    {
      const std::size_t i0 = grid.start[id], i1 = grid.start[id + 1];
      if (i0 == i1)
        continue;
      const std::size_t c[3] = {id / (std::size_t(grid.n[1]) * grid.n[2]), id / grid.n[2] % grid.n[1],
                                id % grid.n[2]};
      list.clear();
      for (std::size_t i = i0; i < i1; ++i)
      {
        const std::int32_t e = grid.items[i];
        double gap2 = 0.0;
        for (int k = 0; k < 3; ++k)
        {
          const double lo = grid.lo[k] + c[k] * grid.cell, hi = lo + grid.cell;
          const double a = bars.x[3 * bars.a[e] + k], b = bars.x[3 * bars.b[e] + k];
          const double gap = std::max({0.0, std::min(a, b) - hi, lo - std::max(a, b)});
          gap2 += gap * gap;
        }
        list.emplace_back(std::sqrt(gap2) - bar_radius(bars, e) - margin, e);
      }
      std::sort(list.begin(), list.end());
      for (std::size_t i = i0; i < i1; ++i)
      {
        bound[i] = list[i - i0].first;
        grid.items[i] = list[i - i0].second;
      }
    }
  }
};
} // namespace

Region region_without_bars(const Region& region, const Bars& bars, double rmax)
{
  // within `reach` of a bar the distance is exact; beyond, the bars' part
  // is at least reach - rb, past what the packing looks
  const double rb = max_bar_radius(bars), reach = 6.0 * rmax + 2.0 * rb;
  auto near = std::make_shared<const SortedElements>(bars, reach);
  const double far = reach - rb; // no element within this of a cell's point it does not list
  auto base = region.sdf;
  auto sdf = [base, near, far](const Point& x)
  {
    // max(base, -bars_part), bars_part = min(far, min over the elements of
    // their surface's distance); an element whose bound is past both what
    // was found and -base cannot change the result (a nearer bar surface
    // than -base is the only way the bars' part wins), so the sorted scan
    // stops there and the result is the full minimum's, bit for bit
    const double b = base(x);
    double bars_part = far;
    const std::int64_t id = near->grid.index(x);
    if (id >= 0)
      for (std::int64_t i = near->grid.start[id]; i < near->grid.start[id + 1]; ++i)
      {
        if (near->bound[i] >= std::min(bars_part, -b))
          break;
        bars_part = std::min(bars_part, near->surface_distance(near->grid.items[i], x.data()));
      }
    return std::max(b, -bars_part);
  };
  return sdf_region(region.name + " less the bars", sdf, region.lo, region.hi);
}

std::array<std::size_t, 2> make_room_for_bars(Packing& packing, const Region& region, const Bars& bars)
{
  if (packing.size() == 0)
    return {0, 0};
  const auto on = spheres_on_bars(bars, packing.x, packing.r);
  Packing kept;
  for (std::size_t i = 0; i < packing.size(); ++i)
    if (!on[i])
    {
      kept.x.insert(kept.x.end(), &packing.x[3 * i], &packing.x[3 * i + 3]);
      kept.r.push_back(packing.r[i]);
    }
  const double rmin = *std::min_element(packing.r.begin(), packing.r.end());
  const double rmax = *std::max_element(packing.r.begin(), packing.r.end());
  const std::size_t removed = packing.size() - kept.size();
  const std::size_t added = fill_boundary(kept, region_without_bars(region, bars, rmax), rmin, rmax);
  packing = std::move(kept);
  return {removed, added};
}

ConcretePacking pack_around_bars(const Region& region, const Bars& bars, const PackingOptions& options)
{
  if (!(options.mean_radius > 0.0))
    impl::out_of_range("pack_around_bars: mean radius", options.mean_radius, "> 0 m (the packing is sized by it, not by a count)");
  // a bound of the packing's largest radius: the reach of region_without_bars
  const double rmax = options.mean_radius * std::max(1.0, options.radius_ratio);
  ConcretePacking c;
  c.packing = generate_packing(region_without_bars(region, bars, rmax), options);
  const auto room = make_room_for_bars(c.packing, region, bars);
  c.removed = room[0];
  c.added = room[1];
  c.solid_fraction = concrete_fraction(c.packing, region, bars);
  return c;
}

double concrete_fraction(const Packing& packing, const Region& region, const Bars& bars)
{
  double solid = 0.0, bars_volume = 0.0;
  for (double r : packing.r)
    solid += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  for (std::size_t e = 0; e < bars.elements(); ++e)
  {
    const double* a = &bars.x[3 * bars.a[e]];
    const double* b = &bars.x[3 * bars.b[e]];
    const Point mid{0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
    if (region.sdf(mid) < 0.0)
      bars_volume += bars.area[e] * bars.l0[e];
  }
  return solid / (region.volume - bars_volume);
}
} // namespace dembridge::dem
