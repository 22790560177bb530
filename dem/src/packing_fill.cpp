// The boundary fill of a packing (fill_uncovered, fill_boundary) and the
// Morton order of its spheres.
#include "packing_internal.h"

#include "dembridge/dem/neighbours.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace dembridge::dem
{
namespace impl
{

Point gradient(const Region& g, const Point& x, double h)
{
  Point d;
  for (int k = 0; k < 3; ++k)
  {
    Point a = x, b = x;
    a[k] += h;
    b[k] -= h;
    d[k] = (g.sdf(a) - g.sdf(b)) / (2.0 * h);
  }
  const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (n > 0.0)
    for (auto& c : d)
      c /= n;
  return d;
}

namespace
{
struct Candidate
{
  Point c;
  double r;
  std::size_t cell;
};

double dot(const Point& a, const Point& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/// The largest radius <= rmax of a sphere tangent to the boundary at q
/// (inward normal `in`) that overlaps no sphere of p and stays in the
/// region; 0 if none of at least rmin.
double largest_tangent(const Packing& p, const CellGrid& grid, const Region& g, const Point& q, const Point& in,
                       double rmin, double rmax)
{
  double rho = rmax;
  grid.for_each_near(q.data(),
                     [&](std::int32_t j)
                     {
                       const Point d{q[0] - p.x[3 * j], q[1] - p.x[3 * j + 1], q[2] - p.x[3 * j + 2]};
                       const double den = p.r[j] - dot(d, in);
                       if (den > 0.0)
                         rho = std::min(rho, (dot(d, d) - p.r[j] * p.r[j]) / (2.0 * den));
                     });
  auto inside = [&](double r)
  { return g.sdf({q[0] + r * in[0], q[1] + r * in[1], q[2] + r * in[2]}) + r <= 1e-4 * rmin; };
  if (rho < rmin || !inside(rmin))
    return 0.0;
  if (!inside(rho)) // near an edge: bisect down to the largest that fits
  {
    double a = rmin, b = rho;
    for (int it = 0; it < 30; ++it)
      (inside(0.5 * (a + b)) ? a : b) = 0.5 * (a + b);
    rho = a;
  }
  return rho;
}

/// The boundary fill's grid: cells of side L = 2 Rmax over the bounding box.
struct FillGrid
{
  double L;
  int m[3];
  std::size_t cells() const { return std::size_t(m[0]) * m[1] * m[2]; }
};

/// The candidates of one cell of the grid that the boundary crosses: its
/// boundary points sampled every Rmin / 2 on the tangent plane at the
/// point nearest its centre (projected onto a curved boundary), those
/// farther than 0.75 Rmax from every sphere surface, each with its largest
/// tangent sphere.
void scan_cell(const Packing& p, const CellGrid& grid, const Region& g, const FillGrid& fg, std::size_t id,
               double rmin, double rmax, double h, std::vector<Candidate>& found)
{
  const double L = fg.L, hs = 0.5 * rmin, flat = 1e-9 * L;
  const int ci[3] = {int(id / (std::size_t(fg.m[1]) * fg.m[2])), int(id / fg.m[2] % fg.m[1]), int(id % fg.m[2])};
  Point lo, c;
  for (int k = 0; k < 3; ++k)
  {
    lo[k] = g.lo[k] + ci[k] * L;
    c[k] = lo[k] + 0.5 * L;
  }
  const double sc = g.sdf(c);
  if (std::abs(sc) > 0.87 * L)
    return;
  const Point gc = gradient(g, c, h);
  const Point q0{c[0] - sc * gc[0], c[1] - sc * gc[1], c[2] - sc * gc[2]};
  const Point n = gradient(g, q0, h);
  // two tangents
  const int a = std::abs(n[0]) < 0.6 ? 0 : (std::abs(n[1]) < 0.6 ? 1 : 2);
  Point t1{0.0, 0.0, 0.0};
  t1[a] = 1.0;
  const double tn = dot(t1, n);
  for (int k = 0; k < 3; ++k)
    t1[k] -= tn * n[k];
  const double l1 = std::sqrt(dot(t1, t1));
  for (auto& v : t1)
    v /= l1;
  const Point t2{n[1] * t1[2] - n[2] * t1[1], n[2] * t1[0] - n[0] * t1[2], n[0] * t1[1] - n[1] * t1[0]};
  const int steps = static_cast<int>(std::ceil(0.87 * L / hs));
  for (int u = -steps; u <= steps; ++u)
    for (int w = -steps; w <= steps; ++w)
    {
      Point q;
      for (int k = 0; k < 3; ++k)
        q[k] = q0[k] + u * hs * t1[k] + w * hs * t2[k];
      Point nq = n;
      double sq = g.sdf(q);
      for (int it = 0; it < 3 && std::abs(sq) > flat; ++it) // project onto a curved boundary
      {
        nq = gradient(g, q, h);
        for (int k = 0; k < 3; ++k)
          q[k] -= sq * nq[k];
        sq = g.sdf(q);
      }
      bool mine = std::abs(sq) <= 1e-6 * L;
      for (int k = 0; k < 3; ++k)
        mine = mine && q[k] >= lo[k] && q[k] < lo[k] + L;
      if (!mine)
        continue;
      double gap = 2.0 * rmax;
      grid.for_each_near(q.data(),
                         [&](std::int32_t j)
                         {
                           const double dx = q[0] - p.x[3 * j], dy = q[1] - p.x[3 * j + 1], dz = q[2] - p.x[3 * j + 2];
                           gap = std::min(gap, std::sqrt(dx * dx + dy * dy + dz * dz) - p.r[j]);
                         });
      if (gap <= 0.75 * rmax)
        continue;
      const Point in{-nq[0], -nq[1], -nq[2]};
      const double rho = largest_tangent(p, grid, g, q, in, rmin, rmax);
      if (rho >= rmin)
        found.push_back({{q[0] + rho * in[0], q[1] + rho * in[1], q[2] + rho * in[2]}, rho, id});
    }
}

/// The candidates, the largest first, each kept if it misses those already kept.
std::vector<Candidate> disjoint(const std::vector<std::vector<Candidate>>& found)
{
  std::vector<Candidate> all;
  for (auto& f : found)
    all.insert(all.end(), f.begin(), f.end());
  std::stable_sort(all.begin(), all.end(), [](const auto& x, const auto& y) { return x.r > y.r; });
  std::vector<Candidate> added;
  for (const auto& cand : all)
  {
    bool free = true;
    for (const auto& o : added)
    {
      const double dx = cand.c[0] - o.c[0], dy = cand.c[1] - o.c[1], dz = cand.c[2] - o.c[2];
      free = free && dx * dx + dy * dy + dz * dz >= (cand.r + o.r) * (cand.r + o.r);
    }
    if (free)
      added.push_back(cand);
  }
  return added;
}
} // namespace

/// Where the boundary is left uncovered (a point of it farther than 0.75
/// Rmax from every sphere surface), inserts the largest sphere of at most
/// Rmax tangent to the boundary there that overlaps nothing, if it is at
/// least Rmin. Boundary points are sampled every Rmin / 2 on tangent planes
/// of cells of 2 Rmax along the boundary; since the gap varies by at most
/// the sampling distance, what is left is below 0.75 Rmax + Rmin / (2 sqrt 2)
/// < Rmax wherever such a sphere fits (always, for Rmax/Rmin >= 2, on flat
/// faces: a tangent sphere of radius gap / 2 always fits). Returns the number
/// of spheres added (appended to p).
std::size_t fill_uncovered(Packing& p, const Region& g, double rmin, double rmax, double h)
{
  FillGrid fg{2.0 * rmax, {}};
  for (int k = 0; k < 3; ++k)
    fg.m[k] = std::max(1, static_cast<int>(std::ceil((g.hi[k] - g.lo[k]) / fg.L)));
  const CellGrid grid(p.x, 3.0 * rmax);
  std::vector<std::vector<Candidate>> found(fg.cells());
#pragma omp parallel for schedule(dynamic, 64)
  for (std::size_t id = 0; id < fg.cells(); ++id)
    scan_cell(p, grid, g, fg, id, rmin, rmax, h, found[id]);
  const std::vector<Candidate> added = disjoint(found);
  for (const auto& a : added)
  {
    p.x.insert(p.x.end(), a.c.begin(), a.c.end());
    p.r.push_back(a.r);
  }
  return added.size();
}

namespace
{
std::uint64_t spread(std::uint64_t v)
{
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}
} // namespace

/// Renumbers the spheres along a Morton (z-order) curve.
void morton_sort(Packing& p, const Region& g)
{
  const std::size_t n = p.size();
  double ext = 0.0;
  for (int k = 0; k < 3; ++k)
    ext = std::max(ext, g.hi[k] - g.lo[k]);
  const double scale = ((1 << 21) - 1) / std::max(ext, 1e-300);
  std::vector<std::uint64_t> key(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    std::uint64_t c[3];
    for (int k = 0; k < 3; ++k)
      c[k] = static_cast<std::uint64_t>(std::clamp((p.x[3 * i + k] - g.lo[k]) * scale, 0.0,
                                                   double((1 << 21) - 1)));
    key[i] = spread(c[0]) | spread(c[1]) << 1 | spread(c[2]) << 2;
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](auto a, auto b) { return key[a] < key[b]; });
  std::vector<double> x(3 * n), r(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    r[i] = p.r[order[i]];
    for (int k = 0; k < 3; ++k)
      x[3 * i + k] = p.x[3 * order[i] + k];
  }
  p.x = std::move(x);
  p.r = std::move(r);
}
} // namespace impl

std::size_t fill_boundary(Packing& p, const Region& region, double rmin, double rmax)
{
  if (!(rmin > 0.0 && rmax >= rmin))
    throw std::runtime_error("fill_boundary: radii " + std::to_string(rmin) + ", " + std::to_string(rmax)
                             + " m: need 0 < rmin <= rmax");
  const Region& g = region;
  const double h = 1e-7 * (g.hi[0] - g.lo[0] + g.hi[1] - g.lo[1]);
  const std::size_t added = impl::fill_uncovered(p, region, rmin, rmax, h);
  p.filled += added;
  impl::morton_sort(p, region);
  return added;
}

} // namespace dembridge::dem
