#include "dembridge/dem/packing.h"
#include "dembridge/dem/assembly.h"
#include "dembridge/dem/neighbours.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <numeric>
#include <omp.h>
#include <random>
#include <sstream>
#include <stdexcept>

#include "errors.h"

namespace dembridge::dem
{
namespace
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

/// Full neighbour lists (both directions) in CSR form.
struct Csr
{
  std::vector<std::int32_t> start, items;
};

/// Sphere centre and radius together: what a neighbour read needs, in one
/// cache line.
struct Ball
{
  double x, y, z, r;
};

/// Full neighbour lists (both directions) in CSR form: every pair closer
/// than r_i + r_j + reach. The spheres are copied in the cell grid's order,
/// so the 27 cells around a sphere are read as 9 contiguous runs; each
/// thread fills a contiguous block of spheres.
Csr neighbours(const std::vector<double>& x, const std::vector<double>& r, double reach)
{
  const std::size_t n = r.size();
  const double rmax = *std::max_element(r.begin(), r.end());
  const CellGrid grid(x, 2.0 * rmax + reach);
  const std::vector<std::int32_t>& index = grid.items();
  std::vector<Ball> sorted(n);
  for (std::size_t k = 0; k < n; ++k)
    sorted[k] = {x[3 * index[k]], x[3 * index[k] + 1], x[3 * index[k] + 2], r[index[k]]};
  Csr c;
  c.start.assign(n + 1, 0);
  std::vector<std::vector<std::int32_t>> chunk;
#pragma omp parallel
  {
#pragma omp single
    chunk.resize(omp_get_num_threads());
    auto& buf = chunk[omp_get_thread_num()];
    std::size_t used = 0;
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < n; ++i)
    {
      const std::size_t first = used;
      const Ball bi{x[3 * i], x[3 * i + 1], x[3 * i + 2], r[i]};
      grid.for_each_run_near(
          &x[3 * i],
          [&](std::int32_t k0, std::int32_t k1)
          {
            if (buf.size() < used + (k1 - k0))
              buf.resize(2 * (used + (k1 - k0)));
            std::int32_t* out = buf.data() + used;
            std::size_t kept = 0;
            for (std::int32_t k = k0; k < k1; ++k) // branch-free: write, keep if near
            {
              const Ball& bj = sorted[k];
              const double dx = bj.x - bi.x, dy = bj.y - bi.y, dz = bj.z - bi.z;
              const double lim = bi.r + bj.r + reach;
              out[kept] = index[k];
              kept += (dx * dx + dy * dy + dz * dz < lim * lim)
                      & (index[k] != static_cast<std::int32_t>(i));
            }
            used += kept;
          });
      c.start[i + 1] = static_cast<std::int32_t>(used - first);
    }
    buf.resize(used);
  }
  for (std::size_t i = 0; i < n; ++i)
    c.start[i + 1] += c.start[i];
  c.items.clear();
  c.items.reserve(c.start[n]);
  for (auto& b2 : chunk) // static schedule: thread blocks are in sphere order
    c.items.insert(c.items.end(), b2.begin(), b2.end());
  return c;
}

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
  const double L = 2.0 * rmax, hs = 0.5 * rmin, flat = 1e-9 * L;
  CellGrid grid(p.x, 3.0 * rmax);
  int m[3];
  for (int k = 0; k < 3; ++k)
    m[k] = std::max(1, static_cast<int>(std::ceil((g.hi[k] - g.lo[k]) / L)));
  const std::size_t cells = std::size_t(m[0]) * m[1] * m[2];
  struct Candidate
  {
    Point c;
    double r;
    std::size_t cell;
  };
  auto dot = [](const Point& a, const Point& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  // largest radius <= rmax of a sphere tangent at q (inward normal in) that
  // overlaps no sphere of p and stays in the region; 0 if none
  auto largest = [&](const Point& q, const Point& in)
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
  };
  std::vector<std::vector<Candidate>> found(cells);
#pragma omp parallel for schedule(dynamic, 64)
  for (std::size_t id = 0; id < cells; ++id)
  {
    const int ci[3] = {int(id / (std::size_t(m[1]) * m[2])), int(id / m[2] % m[1]), int(id % m[2])};
    Point lo, c;
    for (int k = 0; k < 3; ++k)
    {
      lo[k] = g.lo[k] + ci[k] * L;
      c[k] = lo[k] + 0.5 * L;
    }
    const double sc = g.sdf(c);
    if (std::abs(sc) > 0.87 * L)
      continue;
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
                             const double dx = q[0] - p.x[3 * j], dy = q[1] - p.x[3 * j + 1],
                                          dz = q[2] - p.x[3 * j + 2];
                             gap = std::min(gap, std::sqrt(dx * dx + dy * dy + dz * dz) - p.r[j]);
                           });
        if (gap <= 0.75 * rmax)
          continue;
        const Point in{-nq[0], -nq[1], -nq[2]};
        const double rho = largest(q, in);
        if (rho >= rmin)
          found[id].push_back({{q[0] + rho * in[0], q[1] + rho * in[1], q[2] + rho * in[2]}, rho, id});
      }
  }
  // the largest first; each must miss those already added
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
  for (const auto& a : added)
  {
    p.x.insert(p.x.end(), a.c.begin(), a.c.end());
    p.r.push_back(a.r);
  }
  return added.size();
}

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
/// A size scale's value at x, checked to lie in (0, 1].
double checked_scale(const std::function<double(const Point&)>& scale, const Point& x)
{
  const double v = scale(x);
  if (!(v > 0.0 && v <= 1.0))
    impl::out_of_range("packing size scale at (" + std::to_string(x[0]) + ", " + std::to_string(x[1]) + ", "
                           + std::to_string(x[2]) + ") m",
                       v, "in (0, 1]");
  return v;
}

/// What a graded packing needs of its scale field: the region's volume
/// weighted by scale^-3, and the smallest scale in it.
struct Graded
{
  double weighted, smallest;
};

/// Graded for a region and a size scale, from the cell centres of a 128^3
/// grid over its bounding box (as the volume of sdf_region), in one serial
/// pass (the scale may throw: checked_scale).
Graded graded_volume(const Region& g, const std::function<double(const Point&)>& scale)
{
  constexpr int m = 128;
  double h[3];
  for (int k = 0; k < 3; ++k)
    h[k] = (g.hi[k] - g.lo[k]) / m;
  double sum = 0.0, smallest = 1.0;
  std::size_t count = 0;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j)
      for (int k = 0; k < m; ++k)
      {
        const Point x{g.lo[0] + (i + 0.5) * h[0], g.lo[1] + (j + 0.5) * h[1], g.lo[2] + (k + 0.5) * h[2]};
        if (g.sdf(x) >= 0.0)
          continue;
        const double v = checked_scale(scale, x);
        sum += 1.0 / (v * v * v);
        smallest = std::min(smallest, v);
        ++count;
      }
  if (count == 0)
    return {g.volume, 1.0};
  // the region's own volume times the mean of scale^-3 over its samples
  return {g.volume * sum / count, smallest};
}
} // namespace

std::size_t fill_boundary(Packing& p, const Region& region, double rmin, double rmax)
{
  if (!(rmin > 0.0 && rmax >= rmin))
    throw std::runtime_error("fill_boundary: radii " + std::to_string(rmin) + ", " + std::to_string(rmax)
                             + " m: need 0 < rmin <= rmax");
  const Region& g = region;
  const double h = 1e-7 * (g.hi[0] - g.lo[0] + g.hi[1] - g.lo[1]);
  const std::size_t added = fill_uncovered(p, region, rmin, rmax, h);
  p.filled += added;
  morton_sort(p, region);
  return added;
}

Region box_region(const Point& lo, const Point& hi)
{
  for (int k = 0; k < 3; ++k)
    if (!(hi[k] > lo[k]))
      impl::out_of_range("box size along axis " + std::to_string(k), hi[k] - lo[k], "> 0 m");
  Region g;
  g.name = "box";
  g.lo = lo;
  g.hi = hi;
  g.volume = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  g.sdf = [lo, hi](const Point& x)
  {
    double out = 0.0, in = -1e300;
    for (int k = 0; k < 3; ++k)
    {
      const double d = std::max(lo[k] - x[k], x[k] - hi[k]);
      out += d > 0.0 ? d * d : 0.0;
      in = std::max(in, d);
    }
    return out > 0.0 ? std::sqrt(out) : in;
  };
  return g;
}

Region cylinder_region(const Point& base, double radius, double height)
{
  if (!(radius > 0.0))
    impl::out_of_range("cylinder radius", radius, "> 0 m");
  if (!(height > 0.0))
    impl::out_of_range("cylinder height", height, "> 0 m");
  Region g;
  g.name = "cylinder";
  g.lo = {base[0] - radius, base[1] - radius, base[2]};
  g.hi = {base[0] + radius, base[1] + radius, base[2] + height};
  g.volume = std::numbers::pi * radius * radius * height;
  g.sdf = [base, radius, height](const Point& x)
  {
    const double dr = std::hypot(x[0] - base[0], x[1] - base[1]) - radius;
    const double dz = std::max(base[2] - x[2], x[2] - base[2] - height);
    const double out = std::hypot(std::max(dr, 0.0), std::max(dz, 0.0));
    return out > 0.0 ? out : std::max(dr, dz);
  };
  return g;
}

Region sdf_region(const std::string& name, std::function<double(const Point&)> sdf,
                  const Point& lo, const Point& hi)
{
  Region g = box_region(lo, hi);
  g.name = name;
  g.sdf = std::move(sdf);
  const int m = 100;
  std::size_t inside = 0;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j)
      for (int k = 0; k < m; ++k)
      {
        const Point p{lo[0] + (i + 0.5) * (hi[0] - lo[0]) / m, lo[1] + (j + 0.5) * (hi[1] - lo[1]) / m,
                      lo[2] + (k + 0.5) * (hi[2] - lo[2]) / m};
        inside += g.sdf(p) < 0.0;
      }
  g.volume *= double(inside) / (double(m) * m * m);
  if (!(g.volume > 0.0))
    throw std::runtime_error("region '" + name + "' has no point inside its bounding box");
  return g;
}

Packing generate_packing(const Region& g, const PackingOptions& o)
{
  if (!(o.radius_ratio >= 1.0 && o.radius_ratio <= 3.0))
    impl::out_of_range("radius ratio Rmax/Rmin", o.radius_ratio, "in [1, 3]");
  if (!(o.target_fraction > 0.0 && o.target_fraction < 0.74))
    impl::out_of_range("target packing fraction", o.target_fraction, "in (0, 0.74)");
  if (!(o.tolerance > 0.0))
    impl::out_of_range("overlap tolerance", o.tolerance, "> 0");
  if (o.count == 0 && !(o.mean_radius > 0.0))
    impl::out_of_range("mean radius", o.mean_radius, "> 0 m (or give a number of spheres)");
  const double q = o.radius_ratio;
  // E[r^3] for r uniform in [a, q a], per a^3
  const double er3 = q > 1.0 ? (std::pow(q, 4) - 1.0) / (4.0 * (q - 1.0)) : 1.0;
  // graded: the region's volume weighted by scale^-3 (what sets the count)
  const bool graded = static_cast<bool>(o.size_scale);
  Graded grade = graded ? graded_volume(g, o.size_scale) : Graded{g.volume, 1.0};
  std::size_t n = o.count;
  if (n == 0)
  {
    const double a = 2.0 * o.mean_radius / (1.0 + q);
    n = static_cast<std::size_t>(std::llround(o.target_fraction * grade.weighted
                                              / (4.0 / 3.0 * std::numbers::pi * er3 * a * a * a)));
  }
  if (n < 2)
  {
    std::ostringstream m;
    m << "region '" << g.name << "' (" << g.volume << " m^3) holds fewer than 2 spheres of mean radius "
      << o.mean_radius << " m: use smaller spheres or a larger region";
    throw std::runtime_error(m.str());
  }
  std::mt19937_64 gen(o.seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  Packing p;
  p.r.resize(n);
  for (auto& r : p.r)
    r = 1.0 + (q - 1.0) * u01(gen);
  // the radii scaled to the target fraction (after the start, if graded:
  // each radius times the scale where its sphere starts); rmin: the smallest
  // radius a draw can give, rmin_unit: the same where the scale is 1
  double rmin = 0.0, rmin_unit = 0.0;
  auto fit_radii = [&]()
  {
    double vol = 0.0;
    for (const double r : p.r)
      vol += 4.0 / 3.0 * std::numbers::pi * r * r * r;
    const double scale = std::cbrt(o.target_fraction * g.volume / vol);
    for (auto& r : p.r)
      r *= scale;
    rmin_unit = scale;
    rmin = scale * grade.smallest;
  };
  if (!graded)
    fit_radii();
  const double s0 = 0.8;
  // Stratified start: one sphere per cell of a grid over the bounding box
  // (cells whose centre lies inside, chosen at random), jittered within it.
  // Graded: the grid is that of the smallest scale, a cell kept with the
  // probability (smallest / scale)^3 at its centre.
  p.x.resize(3 * n);
  {
    double c = grade.smallest * std::cbrt(grade.weighted / n);
    std::vector<Point> cells;
    for (int attempt = 0; attempt < 50; ++attempt)
    {
      cells.clear();
      int m[3];
      for (int k = 0; k < 3; ++k)
        m[k] = std::max(1, static_cast<int>(std::floor((g.hi[k] - g.lo[k]) / c)));
      double h3[3];
      for (int k = 0; k < 3; ++k)
        h3[k] = (g.hi[k] - g.lo[k]) / m[k];
      for (int i = 0; i < m[0]; ++i)
        for (int j = 0; j < m[1]; ++j)
          for (int k = 0; k < m[2]; ++k)
          {
            const Point centre{g.lo[0] + (i + 0.5) * h3[0], g.lo[1] + (j + 0.5) * h3[1],
                               g.lo[2] + (k + 0.5) * h3[2]};
            if (g.sdf(centre) < 0.0
                && (!graded || u01(gen) < std::pow(grade.smallest / checked_scale(o.size_scale, centre), 3)))
              cells.push_back(centre);
          }
      if (cells.size() >= n)
      {
        c = std::min({h3[0], h3[1], h3[2]});
        break;
      }
      c *= 0.97;
    }
    if (cells.size() < n)
      throw std::runtime_error("packing: the region is too thin for spheres of this size");
    std::shuffle(cells.begin(), cells.end(), gen);
    for (std::size_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k)
        p.x[3 * i + k] = cells[i][k] + 0.5 * c * (2.0 * u01(gen) - 1.0);
    if (graded)
    {
      // (the smallest scale a sphere got: below the grid's if the finest
      // part is thinner than the grid's spacing)
      for (std::size_t i = 0; i < n; ++i)
      {
        const double si = checked_scale(o.size_scale, {p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]});
        p.r[i] *= si;
        grade.smallest = std::min(grade.smallest, si);
      }
      fit_radii();
    }
    // memory order along a Morton curve from the start (radii are i.i.d.)
    morton_sort(p, g);
  }
  const double tol = o.tolerance * rmin;
  // Relaxation by FIRE (Bitzek et al. 2006) on the overlap energy, with each
  // sphere's Jacobi displacement d (its share of the overlaps it is in,
  // weighted by the other's volume, plus the boundary push) as the force:
  // about 3x fewer sweeps than heavy-ball momentum restarted per sphere.
  // Sums are taken in fixed blocks of spheres, so the run is the same
  // whatever the thread count.
  const double skin = 1.0 * rmin, h = 1e-7 * (g.hi[0] - g.lo[0] + g.hi[1] - g.lo[1]);
  const int grow = o.growth_sweeps;
  const double hug = rmin, max_step = 0.1 * rmin;
  // jammed when the largest overlap fell by less than 10 % over check_every
  // sweeps: all radii are then scaled by `backoff` (0.6 % of the volume)
  const int check_every = 100;
  const double backoff = 0.998;
  // FIRE constants: Bitzek et al.'s (N_min 5, f_inc 1.1, f_dec 0.5, f_alpha
  // 0.99) with alpha_0 = 0.2 and the time step of the preconditioned force
  // kept in [0.7, 1] (1 = a full Jacobi step): the boundary terms are not the
  // gradient of one energy, so uphill steps are frequent in small packings,
  // and halving the step down to 0.2 or less tripled their sweeps.
  const double dt_max = 1.0, dt_min = 0.7, alpha0 = 0.2;
  const int n_min = 5;
  double dt = dt_min, alpha = alpha0;
  int n_pos = 0;
  constexpr std::size_t block = 1024;
  const std::size_t blocks = (n + block - 1) / block;
  std::vector<std::array<double, 3>> part(blocks);
  std::vector<Ball> ball(n); // what a neighbour read needs, in one cache line
  for (std::size_t i = 0; i < n; ++i)
    ball[i] = {p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2], p.r[i]};
  Csr nb;
  std::vector<double> x_build, f(3 * n), v(3 * n, 0.0);
  std::vector<std::uint8_t> near(n, 1);
  double last_check = 1e300, moved2 = 1e300; // largest squared move since the last build
  for (int sweep = 0; sweep < o.max_sweeps; ++sweep)
  {
    const double s = std::min(1.0, s0 + (1.0 - s0) * sweep / grow);
    if (moved2 > 0.25 * skin * skin)
    {
      nb = neighbours(p.x, p.r, skin);
      x_build = p.x;
      ++p.rebuilds;
#pragma omp parallel for schedule(static)
      for (std::size_t i = 0; i < n; ++i)
        near[i] = g.sdf({p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]}) > -(p.r[i] + hug + skin);
    }
    // 1. forces; power F.v and |F|^2 per block
    double max_ov = 0.0, max_pen = 0.0;
#pragma omp parallel for schedule(static) reduction(max : max_ov, max_pen)
    for (std::size_t b = 0; b < blocks; ++b)
    {
      double power = 0.0, ff = 0.0;
      for (std::size_t i = b * block; i < std::min(n, (b + 1) * block); ++i)
      {
        double d[3] = {0.0, 0.0, 0.0};
        const Ball bi = ball[i];
        const double wi = bi.r * bi.r * bi.r;
        for (std::int32_t q2 = nb.start[i]; q2 < nb.start[i + 1]; ++q2)
        {
          const Ball bj = ball[nb.items[q2]];
          const double dx = bj.x - bi.x, dy = bj.y - bi.y, dz = bj.z - bi.z;
          const double d2 = dx * dx + dy * dy + dz * dz, reach = s * (bi.r + bj.r);
          if (d2 >= reach * reach || d2 <= 0.0)
            continue;
          const double dist = std::sqrt(d2);
          const double ov = reach - dist;
          max_ov = std::max(max_ov, ov);
          const double wj = bj.r * bj.r * bj.r;
          const double c = ov * wj / ((wi + wj) * dist);
          d[0] -= c * dx;
          d[1] -= c * dy;
          d[2] -= c * dz;
        }
        // Boundary: push back what crosses it; once grown, also pull the
        // outer layer (within hug of the boundary) onto it, so faces are
        // covered.
        if (near[i])
        {
          const Point c{bi.x + d[0], bi.y + d[1], bi.z + d[2]};
          const double pen = g.sdf(c) + s * bi.r;
          if (pen > 0.0 || (s >= 1.0 && pen > -hug))
          {
            max_pen = std::max(max_pen, pen);
            const Point gr = gradient(g, c, h);
            const double move = pen > 0.0 ? pen : 0.5 * pen; // gentle pull onto the wall
            for (int k = 0; k < 3; ++k)
              d[k] -= move * gr[k];
          }
        }
        for (int k = 0; k < 3; ++k)
        {
          f[3 * i + k] = d[k];
          power += d[k] * v[3 * i + k];
          ff += d[k] * d[k];
        }
      }
      part[b] = {power, ff, 0.0};
    }
    double power = 0.0, ff = 0.0;
    for (const auto& q2 : part)
    {
      power += q2[0];
      ff += q2[1];
    }
    // 2. FIRE's control: speed up while the motion goes downhill, stop and
    // restart gently when it goes uphill
    if (power > 0.0)
    {
      if (++n_pos > n_min)
      {
        dt = std::min(1.1 * dt, dt_max);
        alpha *= 0.99;
      }
    }
    else
    {
      n_pos = 0;
      dt = std::max(0.5 * dt, dt_min);
      alpha = alpha0;
      std::fill(v.begin(), v.end(), 0.0);
    }
#pragma omp parallel for schedule(static)
    for (std::size_t b = 0; b < blocks; ++b)
    {
      double vv = 0.0;
      for (std::size_t k = 3 * b * block; k < 3 * std::min(n, (b + 1) * block); ++k)
      {
        v[k] += dt * f[k];
        vv += v[k] * v[k];
      }
      part[b][2] = vv;
    }
    double vv = 0.0;
    for (const auto& q2 : part)
      vv += q2[2];
    // 3. mix the velocity towards the force, move (at most max_step per
    // sweep: no sphere outruns its neighbour list)
    const double mix = ff > 0.0 ? alpha * std::sqrt(vv / ff) : 0.0;
    moved2 = 0.0;
#pragma omp parallel for schedule(static) reduction(max : moved2)
    for (std::size_t i = 0; i < n; ++i)
    {
      double* vi = &v[3 * i];
      double step2 = 0.0;
      for (int k = 0; k < 3; ++k)
      {
        vi[k] = (1.0 - alpha) * vi[k] + mix * f[3 * i + k];
        step2 += vi[k] * vi[k];
      }
      const double len = dt * std::sqrt(step2);
      const double cap = dt * (len > max_step ? max_step / len : 1.0);
      double m2 = 0.0;
      for (int k = 0; k < 3; ++k)
      {
        p.x[3 * i + k] += cap * vi[k];
        const double dk = p.x[3 * i + k] - x_build[3 * i + k];
        m2 += dk * dk;
      }
      ball[i] = {p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2], p.r[i]};
      moved2 = std::max(moved2, m2);
    }
    p.sweeps = sweep + 1;
    // jammed (the overlap no longer falls): back off by shrinking all radii
    if (s >= 1.0 && (sweep - grow) % check_every == check_every - 1)
    {
      if (max_ov > 0.9 * last_check && max_ov > o.shrink_below * rmin)
      {
        for (std::size_t i = 0; i < n; ++i)
        {
          p.r[i] *= backoff;
          ball[i].r = p.r[i];
        }
        ++p.backoffs;
        std::fill(v.begin(), v.end(), 0.0);
      }
      last_check = max_ov;
    }
    p.max_overlap = max_ov / rmin;
    p.max_penetration = max_pen / rmin;
    if (o.verbose && sweep % 100 == 0)
      std::printf("packing sweep %d: scale %.3f, max overlap %.2e Rmin, penetration %.2e Rmin, "
                  "FIRE step %.2f\n",
                  sweep, s, p.max_overlap, p.max_penetration, dt);
    if (s >= 1.0 && ((max_ov < tol && max_pen < tol)
                     || (max_ov < o.shrink_below * rmin && max_pen < o.shrink_below * rmin)))
    {
      // Remove what is left by shrinking the spheres concerned (each by half
      // the overlap of a pair, the whole penetration at the boundary).
      std::vector<double> cut(n, 0.0);
      nb = neighbours(p.x, p.r, skin);
#pragma omp parallel for schedule(static)
      for (std::size_t i = 0; i < n; ++i)
      {
        for (std::int32_t q2 = nb.start[i]; q2 < nb.start[i + 1]; ++q2)
        {
          const std::int32_t j = nb.items[q2];
          const double dist = std::sqrt(std::pow(p.x[3 * j] - p.x[3 * i], 2)
                                        + std::pow(p.x[3 * j + 1] - p.x[3 * i + 1], 2)
                                        + std::pow(p.x[3 * j + 2] - p.x[3 * i + 2], 2));
          cut[i] = std::max(cut[i], 0.5 * (p.r[i] + p.r[j] - dist));
        }
        cut[i] = std::max(cut[i], g.sdf({p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]}) + p.r[i]);
      }
      for (std::size_t i = 0; i < n; ++i)
        if (cut[i] > 0.0)
        {
          p.r[i] -= cut[i] * (1.0 + 1e-9);
          p.max_shrink = std::max(p.max_shrink, cut[i] / rmin);
          ++p.shrunk;
        }
      p.max_overlap = p.max_penetration = 0.0;
      // (graded: the spheres added are those of scale 1, so a face is
      // filled where it is left wider than the largest of them allow)
      const double r_lo = rmin_unit * std::pow(backoff, p.backoffs);
      p.filled = fill_uncovered(p, g, r_lo, q * r_lo, h);
      morton_sort(p, g);
      return p;
    }
  }
  std::ostringstream m;
  m << "packing did not converge in " << o.max_sweeps << " sweeps: overlap " << p.max_overlap
    << " Rmin (tolerance " << o.tolerance << "); lower the target fraction ("
    << o.target_fraction << ") or raise --max-sweeps";
  throw std::runtime_error(m.str());
}

double packing_fraction(const Packing& p, const Region& g, double margin, std::size_t samples)
{
  const double rmax = *std::max_element(p.r.begin(), p.r.end());
  CellGrid grid(p.x, 2.0 * rmax);
  const double vol = (g.hi[0] - g.lo[0]) * (g.hi[1] - g.lo[1]) * (g.hi[2] - g.lo[2]);
  const double h = std::cbrt(vol / samples);
  int m[3];
  for (int k = 0; k < 3; ++k)
    m[k] = std::max(1, static_cast<int>((g.hi[k] - g.lo[k]) / h));
  std::size_t in = 0, solid = 0;
#pragma omp parallel for collapse(2) reduction(+ : in, solid) schedule(static)
  for (int i = 0; i < m[0]; ++i)
    for (int j = 0; j < m[1]; ++j)
      for (int k = 0; k < m[2]; ++k)
      {
        const double c[3] = {g.lo[0] + (i + 0.5) * (g.hi[0] - g.lo[0]) / m[0],
                             g.lo[1] + (j + 0.5) * (g.hi[1] - g.lo[1]) / m[1],
                             g.lo[2] + (k + 0.5) * (g.hi[2] - g.lo[2]) / m[2]};
        if (g.sdf({c[0], c[1], c[2]}) >= -margin)
          continue;
        ++in;
        bool hit = false;
        grid.for_each_near(c,
                           [&](std::int32_t q)
                           {
                             const double dx = p.x[3 * q] - c[0], dy = p.x[3 * q + 1] - c[1],
                                          dz = p.x[3 * q + 2] - c[2];
                             hit = hit || dx * dx + dy * dy + dz * dz < p.r[q] * p.r[q];
                           });
        solid += hit;
      }
  if (in == 0)
    throw std::runtime_error("packing_fraction: the margin leaves no sample inside the region");
  return double(solid) / double(in);
}

double face_gap(const Packing& p, const Region& g, int axis, double value, int m)
{
  const double rmax = *std::max_element(p.r.begin(), p.r.end());
  CellGrid grid(p.x, 2.0 * rmax);
  const int a = (axis + 1) % 3, b = (axis + 2) % 3;
  const double size = g.hi[a] - g.lo[a] + g.hi[b] - g.lo[b];
  double worst = 0.0;
  for (int i = 0; i <= m; ++i)
    for (int j = 0; j <= m; ++j)
    {
      double c[3];
      c[axis] = value;
      c[a] = g.lo[a] + (g.hi[a] - g.lo[a]) * i / m;
      c[b] = g.lo[b] + (g.hi[b] - g.lo[b]) * j / m;
      // on the face, at least Rmax from its edges (corners cannot be filled)
      if (g.sdf({c[0], c[1], c[2]}) > 1e-9 * size)
        continue;
      bool inner = true;
      for (int e : {a, b})
      {
        double probe[3] = {c[0], c[1], c[2]};
        for (double dd : {-rmax, rmax})
        {
          probe[e] = c[e] + dd;
          inner = inner && g.sdf({probe[0], probe[1], probe[2]}) <= 1e-9 * size;
        }
      }
      if (!inner)
        continue;
      double best = 2.0 * rmax;
      grid.for_each_near(c,
                         [&](std::int32_t q)
                         {
                           const double dx = p.x[3 * q] - c[0], dy = p.x[3 * q + 1] - c[1],
                                        dz = p.x[3 * q + 2] - c[2];
                           best = std::min(best, std::sqrt(dx * dx + dy * dy + dz * dz) - p.r[q]);
                         });
      worst = std::max(worst, best);
    }
  return worst;
}

void write_packing(const std::filesystem::path& file, const Packing& p)
{
  if (file.has_parent_path())
    std::filesystem::create_directories(file.parent_path());
  std::ofstream out(file);
  if (!out)
    throw std::runtime_error("cannot write packing file '" + file.string() + "'");
  out << "# x y z r [m], " << p.size() << " spheres\n" << std::setprecision(17);
  for (std::size_t i = 0; i < p.size(); ++i)
    out << p.x[3 * i] << ' ' << p.x[3 * i + 1] << ' ' << p.x[3 * i + 2] << ' ' << p.r[i] << '\n';
  out.flush();
  if (!out)
    throw std::runtime_error("writing packing file '" + file.string() + "' failed (disk full?)");
}

Packing read_packing(const std::filesystem::path& file)
{
  std::ifstream in(file);
  if (!in)
    throw std::runtime_error("cannot open packing file '" + file.string() + "'");
  Packing p;
  std::string line;
  std::size_t no = 0;
  while (std::getline(in, line))
  {
    ++no;
    const auto hash = line.find('#');
    if (hash != std::string::npos)
      line.erase(hash);
    if (line.find_first_not_of(" \t\r") == std::string::npos)
      continue;
    std::istringstream s(line);
    double v[4];
    std::string extra;
    if (!(s >> v[0] >> v[1] >> v[2] >> v[3]) || (s >> extra))
      throw std::runtime_error(file.string() + ":" + std::to_string(no)
                               + ": expected four numbers 'x y z r', got '" + line + "'");
    for (double c : v)
      if (!std::isfinite(c))
        throw std::runtime_error(file.string() + ":" + std::to_string(no) + ": non-finite value");
    if (!(v[3] > 0.0))
      throw std::runtime_error(file.string() + ":" + std::to_string(no) + ": radius "
                               + std::to_string(v[3]) + " must be > 0");
    p.x.insert(p.x.end(), v, v + 3);
    p.r.push_back(v[3]);
  }
  if (p.r.empty())
    throw std::runtime_error("packing file '" + file.string() + "' holds no sphere");
  return p;
}

std::pair<double, std::size_t> largest_protrusion(const Region& region, const Packing& p)
{
  std::pair<double, std::size_t> worst{-1e300, 0};
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    const double out = (region.sdf({p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]}) + p.r[i]) / p.r[i];
    if (out > worst.first)
      worst = {out, i};
  }
  return worst;
}

void check_packing_fits(const Region& region, const Packing& p, const std::string& what)
{
  const auto sphere = [&](std::size_t i)
  {
    std::ostringstream s;
    s << "sphere " << i + 1 << " (centre " << p.x[3 * i] << ", " << p.x[3 * i + 1] << ", " << p.x[3 * i + 2]
      << " m, radius " << p.r[i] << " m)";
    return s.str();
  };
  for (std::size_t i = 0; i < p.size(); ++i)
    if (region.sdf({p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]}) > 0.0)
      throw std::runtime_error(what + ": " + sphere(i) + " is centred outside the region '" + region.name
                               + "': not this region's packing");
  // half a radius: far above a generated packing's round-off, far below
  // what a file of another scale gives
  const auto [out, i] = largest_protrusion(region, p);
  if (out > 0.5)
  {
    std::ostringstream s;
    s << what << ": " << sphere(i) << " lies " << out * p.r[i] << " m out of the region '" << region.name
      << "' (allowed: half its radius): not this region's packing, or a radius out of scale";
    throw std::runtime_error(s.str());
  }
}

std::vector<std::uint8_t> inside(const Region& region, std::span<const double> x, double margin)
{
  std::vector<std::uint8_t> f(x.size() / 3);
  for (std::size_t i = 0; i < f.size(); ++i)
    f[i] = region.sdf({x[3 * i], x[3 * i + 1], x[3 * i + 2]}) < -margin ? 1 : 0;
  return f;
}

std::vector<std::uint8_t> bulk_spheres(const Region& region, std::span<const double> x,
                                       std::span<const double> r)
{
  const double rmax = r.empty() ? 0.0 : *std::max_element(r.begin(), r.end());
  auto bulk = inside(region, x, 2.0 * rmax);
  if (std::find(bulk.begin(), bulk.end(), 1) == bulk.end())
    throw std::runtime_error("region '" + region.name + "': no sphere lies 2 Rmax (" + std::to_string(2.0 * rmax)
                             + " m) inside the boundary to set the bulk's links per sphere: the region is "
                               "too small for these spheres");
  return bulk;
}

double lambda_for_bulk_links(const Region& region, std::span<const double> x, std::span<const double> r,
                             double links_per_sphere)
{
  return lambda_for_mean_links(x, r, links_per_sphere, bulk_spheres(region, x, r));
}

} // namespace dembridge::dem
