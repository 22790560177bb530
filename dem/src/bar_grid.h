#pragma once
// The bars' elements on a grid of cells, for the queries of spheres near
// them (bars.cpp: the packing's room and the bonds; bar_contacts.cpp).
#include "dembridge/dem/bars.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <span>
#include <tuple>
#include <vector>

namespace dembridge::dem::impl
{
/// a . b of two 3-vectors
inline double dot(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/// The bars' elements by cells of a uniform grid: each element listed in
/// every cell its box, grown by `reach`, touches; a query looks in its own
/// cell only, and finds every element within `reach` of it (a point
/// outside the grid has none). The lists are compressed rows: cell id's
/// elements are items[start[id]] to items[start[id + 1]] (one offset per
/// cell, so that a query over many points stays in cache).
struct ElementGrid
{
  Point lo{};
  double cell = 1.0;
  int n[3] = {1, 1, 1};
  std::vector<std::int32_t> start{0, 0}, items;
  std::int64_t index(const Point& x) const
  {
    std::int64_t id = 0;
    for (int k = 0; k < 3; ++k)
    {
      const double f = (x[k] - lo[k]) / cell;
      if (!(f >= 0.0 && f < n[k]))
        return -1;
      id = id * n[k] + static_cast<std::int64_t>(f);
    }
    return id;
  }
  std::span<const std::int32_t> near(const double* x) const
  {
    const std::int64_t id = index({x[0], x[1], x[2]});
    if (id < 0)
      return {};
    return std::span<const std::int32_t>(items.data() + start[id], items.data() + start[id + 1]);
  }
};

/// The squared distance from x to the axis of element e (clamped to the
/// segment) and the place of the nearest point, xi in [0, 1]: the inline
/// form of distance_to_element for the loops over many spheres.
inline std::array<double, 2> distance2_to_element(const Bars& bars, std::size_t e, const double* x)
{
  const double* pa = &bars.x[3 * bars.a[e]];
  const double* pb = &bars.x[3 * bars.b[e]];
  const double d[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
  const double r[3] = {x[0] - pa[0], x[1] - pa[1], x[2] - pa[2]};
  const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  const double xi = std::clamp((r[0] * d[0] + r[1] * d[1] + r[2] * d[2]) / dd, 0.0, 1.0);
  const double q[3] = {r[0] - xi * d[0], r[1] - xi * d[1], r[2] - xi * d[2]};
  return {q[0] * q[0] + q[1] * q[1] + q[2] * q[2], xi};
}

/// The grid of the elements for queries within `reach` of them, cells of
/// max(longest element, reach / 4) over the bars' box grown by reach.
inline ElementGrid element_grid(const Bars& bars, double reach)
{
  ElementGrid grid;
  if (bars.elements() == 0)
    return grid;
  Point lo{bars.x[0], bars.x[1], bars.x[2]}, hi = lo;
  double lmax = 0.0;
  for (std::size_t q = 0; q < bars.nodes(); ++q)
    for (int k = 0; k < 3; ++k)
    {
      lo[k] = std::min(lo[k], bars.x[3 * q + k]);
      hi[k] = std::max(hi[k], bars.x[3 * q + k]);
    }
  for (double l : bars.l0)
    lmax = std::max(lmax, l);
  grid.cell = std::max(lmax, 0.25 * reach);
  for (int k = 0; k < 3; ++k)
  {
    grid.lo[k] = lo[k] - reach;
    grid.n[k] = static_cast<int>(std::ceil((hi[k] - lo[k] + 2.0 * reach) / grid.cell)) + 1;
  }
  const std::size_t cells = std::size_t(grid.n[0]) * grid.n[1] * grid.n[2];
  // two passes over the elements' cells: count, then fill
  auto each_cell = [&](std::size_t e, auto&& f)
  {
    int c0[3], c1[3];
    for (int k = 0; k < 3; ++k)
    {
      const double a = bars.x[3 * bars.a[e] + k], b = bars.x[3 * bars.b[e] + k];
      c0[k] = std::max(0, static_cast<int>(std::floor((std::min(a, b) - reach - grid.lo[k]) / grid.cell)));
      c1[k] = std::min(grid.n[k] - 1, static_cast<int>(std::floor((std::max(a, b) + reach - grid.lo[k]) / grid.cell)));
    }
    for (int i = c0[0]; i <= c1[0]; ++i)
      for (int j = c0[1]; j <= c1[1]; ++j)
        for (int k = c0[2]; k <= c1[2]; ++k)
          f((std::size_t(i) * grid.n[1] + j) * grid.n[2] + k);
  };
  grid.start.assign(cells + 1, 0);
  for (std::size_t e = 0; e < bars.elements(); ++e)
    each_cell(e, [&](std::size_t id) { ++grid.start[id + 1]; });
  for (std::size_t id = 0; id < cells; ++id)
    grid.start[id + 1] += grid.start[id];
  grid.items.resize(grid.start[cells]);
  std::vector<std::int32_t> fill(grid.start.begin(), grid.start.end() - 1);
  for (std::size_t e = 0; e < bars.elements(); ++e)
    each_cell(e, [&](std::size_t id) { grid.items[fill[id]++] = static_cast<std::int32_t>(e); });
  return grid;
}

/// The nearest element to x within `limit(e)` (<= the grid's reach) of its
/// axis: {element, xi, distance}, element -1 if none.
template <typename Limit>
std::tuple<std::int64_t, double, double> nearest_element(const Bars& bars, const ElementGrid& grid, const double* x,
                                                         Limit&& limit)
{
  std::int64_t best = -1;
  double bxi = 0.0, bd = std::numeric_limits<double>::infinity();
  for (const std::int32_t e : grid.near(x))
  {
    const auto [d, xi] = distance_to_element(bars, e, x);
    if (d < limit(e) && d < bd)
    {
      best = e;
      bd = d;
      bxi = xi;
    }
  }
  return {best, bxi, bd};
}
inline double bar_radius(const Bars& bars, std::size_t e) { return std::sqrt(bars.area[e] / std::numbers::pi); }
inline double max_bar_radius(const Bars& bars)
{
  double rb = 0.0;
  for (std::size_t e = 0; e < bars.elements(); ++e)
    rb = std::max(rb, bar_radius(bars, e));
  return rb;
}
} // namespace dembridge::dem::impl
