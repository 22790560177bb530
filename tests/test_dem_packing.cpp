// Packing generator: density, overlaps, faces, isotropy, links per sphere,
// determinism, regions, packing files.
#include "dembridge/dem/assembly.h"
#include "dembridge/dem/neighbours.h"
#include "dembridge/dem/packing.h"

#include <catch2/catch.hpp>
#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <omp.h>

using namespace dembridge::dem;
using Catch::Contains;

namespace
{
/// Largest pair overlap and boundary penetration (brute force over a grid).
std::pair<double, double> worst(const Packing& p, const Region& g)
{
  double ov = 0.0, pen = 0.0;
  const double rmax = *std::max_element(p.r.begin(), p.r.end());
  CellGrid grid(p.x, 2.0 * rmax);
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    grid.for_each_near(&p.x[3 * i],
                       [&](std::int32_t j)
                       {
                         if (j <= static_cast<std::int32_t>(i))
                           return;
                         const double d = std::hypot(p.x[3 * j] - p.x[3 * i], p.x[3 * j + 1] - p.x[3 * i + 1],
                                                     p.x[3 * j + 2] - p.x[3 * i + 2]);
                         ov = std::max(ov, p.r[i] + p.r[j] - d);
                       });
    pen = std::max(pen, g.sdf({p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]}) + p.r[i]);
  }
  return {ov, pen};
}

const Packing& cube_packing()
{
  // ~4000 spheres in a 0.1 m cube, Rmax/Rmin = 2 (default options)
  static const Packing p = []
  {
    PackingOptions o;
    o.mean_radius = 0.0025;
    return generate_packing(box_region({0, 0, 0}, {0.1, 0.1, 0.1}), o);
  }();
  return p;
}
} // namespace

TEST_CASE("packing: dense in the bulk, no overlap, faces filled", "[dem][packing]")
{
  const auto g = box_region({0, 0, 0}, {0.1, 0.1, 0.1});
  const Packing& p = cube_packing();
  const double rmin = 2.0 * 0.0025 / 3.0, rmax = 2.0 * rmin;
  INFO(p.size() << " spheres, " << p.sweeps << " sweeps, shrunk " << p.shrunk << " by up to "
                << p.max_shrink << " Rmin");
  // radii within [Rmin, Rmax] up to the final shrink (at most 2 % of Rmin)
  for (double r : p.r)
  {
    CHECK(r <= rmax * (1 + 1e-12));
    CHECK(r >= rmin * (1 - 0.02));
  }
  // overlap and boundary penetration at most 1e-3 Rmin (the required bound)
  const auto [ov, pen] = worst(p, g);
  CHECK(ov <= 1e-3 * rmin);
  CHECK(pen <= 1e-3 * rmin);
  // solid fraction >= 0.60 in the bulk (two Rmax away from the walls, where
  // the wall layer's lower density does not reach)
  const double bulk = packing_fraction(p, g, 2.0 * rmax, 1000000);
  INFO("bulk packing fraction " << bulk);
  CHECK(bulk >= 0.60);
  // no gap wider than Rmax at any of the six flat faces
  for (int axis = 0; axis < 3; ++axis)
    for (double v : {0.0, 0.1})
    {
      const double gap = face_gap(p, g, axis, v, 100);
      INFO("face " << axis << " at " << v << ": gap " << gap / rmax << " Rmax");
      CHECK(gap <= rmax);
    }
}

TEST_CASE("packing: isotropic fabric and about 12 links per sphere", "[dem][packing]")
{
  const Packing& p = cube_packing();
  const double lambda = lambda_for_mean_links(p.x, p.r, 12.0);
  INFO("lambda for 12 links per sphere: " << lambda);
  CHECK(lambda >= 1.0);
  CHECK(lambda < 1.6);
  auto parts = make_particles(p.x, p.r, 2400.0, 0.6);
  auto links = create_links(parts, lambda, Material{});
  const double mean = 2.0 * links.size() / p.size();
  CHECK(mean >= 12.0);
  CHECK(mean < 12.1);
  // fabric tensor F = <n n> of the links, away from the walls (the wall
  // layer is anisotropic by construction): eigenvalues within 10 % of each
  // other (the required bound; an isotropic set gives 1/3 each)
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  int count = 0;
  for (std::size_t k = 0; k < links.size(); ++k)
  {
    const double* a = &p.x[3 * links.a[k]];
    bool inner = true;
    for (int d = 0; d < 3; ++d)
      inner = inner && a[d] > 0.015 && a[d] < 0.085;
    if (!inner)
      continue;
    Eigen::Vector3d n(links.n[3 * k], links.n[3 * k + 1], links.n[3 * k + 2]);
    F += n * n.transpose();
    ++count;
  }
  F /= count;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(F);
  const auto ev = es.eigenvalues();
  INFO("fabric eigenvalues " << ev.transpose());
  CHECK(ev.maxCoeff() / ev.minCoeff() < 1.10);
}

TEST_CASE("packing: same seed, same packing; another seed, another one", "[dem][packing]")
{
  const auto g = cylinder_region({0, 0, 0}, 0.03, 0.06);
  PackingOptions o;
  o.count = 800;
  o.seed = 42;
  const auto a = generate_packing(g, o), b = generate_packing(g, o);
  CHECK(a.x == b.x);
  CHECK(a.r == b.r);
  o.seed = 43;
  const auto c = generate_packing(g, o);
  CHECK(a.x != c.x);
  // the cylinder is filled: no sphere sticks out
  CHECK(worst(a, g).second <= 1e-3 * *std::min_element(a.r.begin(), a.r.end()));
}

TEST_CASE("packing: the same packing on 1, 2 and 3 threads", "[dem][packing]")
{
  // 5000 spheres: five blocks of the fixed-block sums that steer the
  // minimiser, split differently between threads; the result must not
  // change by a bit (a thread-count-dependent sum would change it at
  // round-off level, and the minimiser amplifies that)
  const auto g = box_region({0, 0, 0}, {0.05, 0.05, 0.05});
  PackingOptions o;
  o.count = 5000;
  const int before = omp_get_max_threads();
  std::vector<Packing> runs;
  for (int t : {1, 2, 3})
  {
    omp_set_num_threads(t);
    runs.push_back(generate_packing(g, o));
  }
  omp_set_num_threads(before);
  for (int k : {1, 2})
  {
    CHECK(runs[k].x == runs[0].x);
    CHECK(runs[k].r == runs[0].r);
  }
}

TEST_CASE("packing: any region from a signed distance (a sphere)", "[dem][packing]")
{
  const auto g = sdf_region("ball", [](const Point& x) { return std::hypot(x[0], x[1], x[2]) - 0.05; },
                            {-0.05, -0.05, -0.05}, {0.05, 0.05, 0.05});
  // grid volume estimate of 4/3 pi R^3 within 1 % (100^3 samples)
  CHECK(std::abs(g.volume / (4.0 / 3.0 * M_PI * std::pow(0.05, 3)) - 1.0) < 0.01);
  PackingOptions o;
  o.count = 1000;
  const auto p = generate_packing(g, o);
  CHECK(p.size() == 1000 + p.filled); // the count asked, plus the spheres filling the boundary
  CHECK(p.filled < 50);
  CHECK(worst(p, g).second <= 1e-3 * *std::min_element(p.r.begin(), p.r.end()));
}

TEST_CASE("packing: graded by a size scale (finer spheres in part of the region)", "[dem][packing]")
{
  // a 0.1 x 0.05 x 0.05 m box: scale 0.5 for x < 0.04 m, growing linearly to
  // 1 at x = 0.06 m; mean radius 3 mm where the scale is 1
  const auto g = box_region({0, 0, 0}, {0.1, 0.05, 0.05});
  PackingOptions o;
  o.mean_radius = 0.003;
  o.size_scale = [](const Point& x) { return 0.5 + 0.5 * std::clamp((x[0] - 0.04) / 0.02, 0.0, 1.0); };
  const Packing p = generate_packing(g, o);
  const double rmin_fine = 0.5 * 2.0 * 0.003 / 3.0;
  INFO(p.size() << " spheres, " << p.sweeps << " sweeps, " << p.backoffs << " backoffs");
  const auto [ov, pen] = worst(p, g);
  CHECK(ov <= 1e-3 * rmin_fine);
  CHECK(pen <= 1e-3 * rmin_fine);
  // mean radius on either side of the ramp: the radii are drawn from the
  // same [Rmin, Rmax] on both sides, so the fine side's is half the coarse
  // side's, and the coarse side's the 3 mm asked. Bounds: 3 %, three
  // standard errors of the coarse side's mean (~400 draws, uniform on
  // [2, 4] mm: 0.58 mm / sqrt(400) = 0.029 mm, 1 % of 3 mm) plus the
  // packing's final shrink (at most 2 % of Rmin)
  double sum[2] = {0, 0};
  int n[2] = {0, 0};
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    const double x = p.x[3 * i];
    if (x < 0.035 || x > 0.065)
    {
      sum[x > 0.05] += p.r[i];
      ++n[x > 0.05];
    }
  }
  const double fine = sum[0] / n[0], coarse = sum[1] / n[1];
  INFO("mean radius " << fine << " m (" << n[0] << " spheres) and " << coarse << " m (" << n[1] << ")");
  CHECK(std::abs(coarse / 0.003 - 1.0) < 0.03);
  CHECK(std::abs(fine / coarse - 0.5) < 0.5 * 0.03);
  // the same solid fraction on both sides, as dense as a uniform packing's
  // bulk (>= 0.60, the first test), boxes 2 Rmax clear of the walls
  const double f_fine = packing_fraction(p, box_region({0.004, 0.004, 0.004}, {0.036, 0.046, 0.046}), 0.0, 400000);
  const double f_coarse = packing_fraction(p, box_region({0.064, 0.008, 0.008}, {0.092, 0.042, 0.042}), 0.0, 400000);
  INFO("solid fraction " << f_fine << " (fine) and " << f_coarse << " (coarse)");
  CHECK(f_fine >= 0.60);
  CHECK(f_coarse >= 0.60);
  CHECK(std::abs(f_fine - f_coarse) < 0.02);
  // links per sphere do not depend on the scale (the packing looks the same
  // at either scale): each side's bulk within 5 % of the whole bulk's 12 (a
  // sphere's count scatters by about 2, so the coarse side's mean over ~150
  // bulk spheres has a standard error of 0.16, 1.4 %: 5 % is 3.5 of them)
  const double lambda = lambda_for_bulk_links(g, p.x, p.r, 12.0);
  auto parts = make_particles(p.x, p.r, 2400.0, 0.6);
  auto links = create_links(parts, lambda, Material{});
  std::vector<int> count(p.size(), 0);
  for (std::size_t k = 0; k < links.size(); ++k)
  {
    ++count[links.a[k]];
    ++count[links.b[k]];
  }
  double c[2] = {0, 0};
  int m[2] = {0, 0};
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    const double* x = &p.x[3 * i];
    const double wall = 2.0 * (4.0 / 3.0 * 0.003) * (x[0] < 0.05 ? 0.5 : 1.0); // 2 Rmax of its side
    const bool inner = x[1] > wall && x[1] < 0.05 - wall && x[2] > wall && x[2] < 0.05 - wall;
    if (inner && (x[0] > wall && x[0] < 0.035))
    {
      c[0] += count[i];
      ++m[0];
    }
    else if (inner && x[0] > 0.065 && x[0] < 0.1 - wall)
    {
      c[1] += count[i];
      ++m[1];
    }
  }
  INFO("links per sphere " << c[0] / m[0] << " (fine) and " << c[1] / m[1] << " (coarse), lambda " << lambda);
  CHECK(std::abs(c[0] / m[0] / 12.0 - 1.0) < 0.05);
  CHECK(std::abs(c[1] / m[1] / 12.0 - 1.0) < 0.05);
  // a scale outside (0, 1] is an error naming it
  o.size_scale = [](const Point&) { return 1.5; };
  CHECK_THROWS_WITH(generate_packing(g, o), Contains("size scale") && Contains("(0, 1]"));
}

TEST_CASE("packing files: round trip and malformed lines", "[dem][packing][errors]")
{
  const auto dir = std::filesystem::temp_directory_path() / "dembridge_packing";
  std::filesystem::create_directories(dir);
  PackingOptions o;
  o.count = 300;
  const auto p = generate_packing(box_region({0, 0, 0}, {0.05, 0.05, 0.05}), o);
  write_packing(dir / "p.txt", p);
  const auto q = read_packing(dir / "p.txt");
  CHECK(q.x == p.x);
  CHECK(q.r == p.r);
  std::ofstream(dir / "bad.txt") << "# comment\n0 0 0 0.001\n0 0 0.002\n";
  CHECK_THROWS_WITH(read_packing(dir / "bad.txt"), Contains("bad.txt:3") && Contains("four numbers"));
  std::ofstream(dir / "neg.txt") << "0 0 0 -0.001\n";
  CHECK_THROWS_WITH(read_packing(dir / "neg.txt"), Contains("neg.txt:1") && Contains("radius"));
  CHECK_THROWS_WITH(read_packing(dir / "none.txt"), Contains("cannot open"));
}

TEST_CASE("packing: bad options", "[dem][packing][errors]")
{
  const auto g = box_region({0, 0, 0}, {0.05, 0.05, 0.05});
  PackingOptions o;
  o.count = 100;
  o.radius_ratio = 3.5;
  CHECK_THROWS_WITH(generate_packing(g, o), Contains("radius ratio") && Contains("[1, 3]"));
  o = {};
  o.mean_radius = -1.0;
  CHECK_THROWS_WITH(generate_packing(g, o), Contains("mean radius"));
  o = {};
  o.count = 100;
  o.target_fraction = 0.8;
  CHECK_THROWS_WITH(generate_packing(g, o), Contains("packing fraction"));
  CHECK_THROWS_WITH(box_region({0, 0, 0}, {1, -1, 1}), Contains("box size"));
}
