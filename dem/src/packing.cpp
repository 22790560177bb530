#include "dembridge/dem/packing.h"
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

Csr neighbours(const std::vector<double>& x, const std::vector<double>& r, double reach)
{
  const std::size_t n = r.size();
  const double rmax = *std::max_element(r.begin(), r.end());
  CellGrid grid(x, 2.0 * rmax + reach);
  Csr c;
  c.start.assign(n + 1, 0);
  auto visit = [&](std::size_t i, auto&& emit)
  {
    grid.for_each_near(&x[3 * i],
                       [&](std::int32_t j)
                       {
                         if (j == static_cast<std::int32_t>(i))
                           return;
                         const double dx = x[3 * j] - x[3 * i], dy = x[3 * j + 1] - x[3 * i + 1],
                                      dz = x[3 * j + 2] - x[3 * i + 2];
                         const double lim = r[i] + r[j] + reach;
                         if (dx * dx + dy * dy + dz * dz < lim * lim)
                           emit(j);
                       });
  };
  // one pass: each thread fills its own contiguous block of spheres
  std::vector<std::vector<std::int32_t>> chunk;
#pragma omp parallel
  {
#pragma omp single
    chunk.resize(omp_get_num_threads());
    auto& buf = chunk[omp_get_thread_num()];
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < n; ++i)
    {
      const std::size_t first = buf.size();
      visit(i, [&](std::int32_t j) { buf.push_back(j); });
      std::sort(buf.begin() + first, buf.end());
      c.start[i + 1] = static_cast<std::int32_t>(buf.size() - first);
    }
  }
  for (std::size_t i = 0; i < n; ++i)
    c.start[i + 1] += c.start[i];
  c.items.clear();
  c.items.reserve(c.start[n]);
  for (auto& b2 : chunk) // static schedule: thread blocks are in sphere order
    c.items.insert(c.items.end(), b2.begin(), b2.end());
  return c;
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
} // namespace

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
  std::size_t n = o.count;
  if (n == 0)
  {
    const double a = 2.0 * o.mean_radius / (1.0 + q);
    n = static_cast<std::size_t>(std::llround(o.target_fraction * g.volume
                                              / (4.0 / 3.0 * std::numbers::pi * er3 * a * a * a)));
  }
  if (n < 2)
    throw std::runtime_error("the region holds fewer than 2 spheres of that size: use smaller spheres");
  std::mt19937_64 gen(o.seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  Packing p;
  p.r.resize(n);
  double vol = 0.0;
  for (auto& r : p.r)
  {
    r = 1.0 + (q - 1.0) * u01(gen);
    vol += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  }
  const double scale = std::cbrt(o.target_fraction * g.volume / vol);
  for (auto& r : p.r)
    r *= scale;
  const double rmin = scale;
  const double tol = o.tolerance * rmin;
  const double s0 = 0.8;
  // Stratified start: one sphere per cell of a grid over the bounding box
  // (cells whose centre lies inside, chosen at random), jittered within it.
  p.x.resize(3 * n);
  {
    double c = std::cbrt(g.volume / n);
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
            const Point q{g.lo[0] + (i + 0.5) * h3[0], g.lo[1] + (j + 0.5) * h3[1],
                          g.lo[2] + (k + 0.5) * h3[2]};
            if (g.sdf(q) < 0.0)
              cells.push_back(q);
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
    // memory order along a Morton curve from the start (radii are i.i.d.)
    morton_sort(p, g);
  }
  std::vector<double> w(n);
  for (std::size_t i = 0; i < n; ++i)
    w[i] = p.r[i] * p.r[i] * p.r[i];

  const double skin = 1.0 * rmin, h = 1e-7 * (g.hi[0] - g.lo[0] + g.hi[1] - g.lo[1]);
  const int grow = o.growth_sweeps;
  const double beta = 0.7, hug = rmin, max_step = 0.1 * rmin;
  Csr nb;
  std::vector<double> x_build, disp(3 * n), mom(3 * n, 0.0);
  std::vector<std::uint8_t> near(n, 1);
  double last_check = 1e300;
  double s = s0;
  for (int sweep = 0; sweep < o.max_sweeps; ++sweep)
  {
    s = std::min(1.0, s0 + (1.0 - s0) * sweep / grow);
    bool rebuild = sweep == 0;
    if (!rebuild)
    {
      double m2 = 0.0;
      for (std::size_t i = 0; i < 3 * n; i += 3)
      {
        const double dx = p.x[i] - x_build[i], dy = p.x[i + 1] - x_build[i + 1],
                     dz = p.x[i + 2] - x_build[i + 2];
        m2 = std::max(m2, dx * dx + dy * dy + dz * dz);
      }
      rebuild = m2 > 0.25 * skin * skin;
    }
    if (rebuild)
    {
      nb = neighbours(p.x, p.r, skin);
      x_build = p.x;
      ++p.rebuilds;
#pragma omp parallel for schedule(static)
      for (std::size_t i = 0; i < n; ++i)
        near[i] = g.sdf({p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]}) > -(p.r[i] + hug + skin);
    }
    double max_ov = 0.0, max_pen = 0.0;
#pragma omp parallel for schedule(static) reduction(max : max_ov, max_pen)
    for (std::size_t i = 0; i < n; ++i)
    {
      double d[3] = {0.0, 0.0, 0.0};
      const double* xi = &p.x[3 * i];
      for (std::int32_t q2 = nb.start[i]; q2 < nb.start[i + 1]; ++q2)
      {
        const std::int32_t j = nb.items[q2];
        const double* xj = &p.x[3 * j];
        const double dx = xj[0] - xi[0], dy = xj[1] - xi[1], dz = xj[2] - xi[2];
        const double d2 = dx * dx + dy * dy + dz * dz, reach = s * (p.r[i] + p.r[j]);
        if (d2 >= reach * reach || d2 <= 0.0)
          continue;
        const double dist = std::sqrt(d2);
        const double ov = reach - dist;
        max_ov = std::max(max_ov, ov);
        const double f = ov * w[j] / (w[i] + w[j]) / dist;
        d[0] -= f * dx;
        d[1] -= f * dy;
        d[2] -= f * dz;
      }
      // Boundary: push back what crosses it; once grown, also pull the outer
      // layer (within hug of the boundary) onto it, so faces are covered.
      const Point c{xi[0] + d[0], xi[1] + d[1], xi[2] + d[2]};
      const double pen = near[i] ? g.sdf(c) + s * p.r[i] : -1e300;
      if (pen > 0.0 || (s >= 1.0 && pen > -hug))
      {
        max_pen = std::max(max_pen, pen);
        const Point gr = gradient(g, c, h);
        const double move = pen > 0.0 ? pen : 0.25 * pen; // gentle pull onto the wall
        for (int k = 0; k < 3; ++k)
          d[k] -= move * gr[k];
      }
      // heavy-ball momentum, restarted per sphere when it turns back
      double* m = &mom[3 * i];
      const double turn = m[0] * d[0] + m[1] * d[1] + m[2] * d[2];
      for (int k = 0; k < 3; ++k)
        m[k] = turn < 0.0 ? d[k] : beta * m[k] + d[k];
      // at most max_step per sweep: no sphere outruns its neighbour list
      const double mm = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
      const double cap = mm > max_step ? max_step / mm : 1.0;
      for (int k = 0; k < 3; ++k)
        disp[3 * i + k] = cap * m[k];
    }
    for (std::size_t i = 0; i < 3 * n; ++i)
      p.x[i] += disp[i];
    p.sweeps = sweep + 1;
    // jammed (the overlap no longer falls): back off by shrinking all radii
    if (s >= 1.0 && (sweep - grow) % 250 == 249)
    {
      if (max_ov > 0.7 * last_check && max_ov > o.shrink_below * rmin)
      {
        for (auto& r : p.r)
          r *= 0.995;
        for (auto& v : w)
          v *= 0.995 * 0.995 * 0.995;
        ++p.backoffs;
        std::fill(mom.begin(), mom.end(), 0.0);
      }
      last_check = max_ov;
    }
    p.max_overlap = max_ov / rmin;
    p.max_penetration = max_pen / rmin;
    if (o.verbose && sweep % 100 == 0)
      std::printf("packing sweep %d: scale %.3f, max overlap %.2e Rmin, penetration %.2e Rmin\n",
                  sweep, s, p.max_overlap, p.max_penetration);
    if (s >= 1.0 && ((max_ov < tol && max_pen < tol)
                     || (max_ov < o.shrink_below * rmin && max_pen < o.shrink_below * rmin)))
    {
      // Remove what is left by shrinking the spheres concerned (each by half
      // the overlap of a pair, the whole penetration at the boundary).
      std::vector<double> cut(n, 0.0);
      nb = neighbours(p.x, p.r, skin);
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

} // namespace dembridge::dem
