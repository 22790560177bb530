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
