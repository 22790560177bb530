// dem_throughput: speed of the DEM step on a bonded cube.
//
// For each size it generates a packing of a cube (timing the generator),
// bonds it (12 links per sphere), holds the bottom face and pulls the top one
// slowly (links stay elastic: strengths set very high), with contact
// detection on, and times `--steps` steps. Prints ns per link-step and per
// particle-step, bytes per link (spheres, links and neighbour pairs
// included), the thread count (OMP_NUM_THREADS) and the generator's spheres
// per second.
//
// Sample runs:
//   build/bin/dem_throughput --particles 10000 50000 --summary out/dem_throughput.json
//   OMP_NUM_THREADS=1 build/bin/dem_throughput --packing my_spheres.txt
#include "dembridge/dem/packing.h"
#include "dembridge/dem/solver.h"
#include "options.h"
#include "support.h"

#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>
#include <numbers>
#include <omp.h>

namespace
{
template <typename T>
std::size_t bytes(const std::vector<T>& v)
{
  return v.capacity() * sizeof(T);
}

/// The bonded cube's packing: read from a file (moved to z >= 0; its side
/// is its height) or generated in a 0.1 m cube (the packing rate measured).
struct Cube
{
  dembridge::dem::Packing pk;
  double side = 0.0;      ///< [m]
  double pack_rate = 0.0; ///< spheres per second of packing (0 if read)
};

Cube cube(const std::string& packing_file, long count, const std::string& save_packing)
{
  using namespace dembridge;
  Cube c;
  if (!packing_file.empty())
  {
    c.pk = dem::read_packing(packing_file);
    double lo = 1e300, hi = -1e300;
    for (std::size_t i = 0; i < c.pk.size(); ++i)
    {
      lo = std::min(lo, c.pk.x[3 * i + 2] - c.pk.r[i]);
      hi = std::max(hi, c.pk.x[3 * i + 2] + c.pk.r[i]);
    }
    c.side = hi - lo;
    for (std::size_t i = 0; i < c.pk.size(); ++i)
      c.pk.x[3 * i + 2] -= lo;
    return c;
  }
  c.side = 0.1;
  dem::PackingOptions po;
  po.count = static_cast<std::size_t>(count);
  demo::Stopwatch t;
  c.pk = dem::generate_packing(dem::box_region({0, 0, 0}, {c.side, c.side, c.side}), po);
  c.pack_rate = c.pk.size() / t.seconds();
  if (!save_packing.empty())
    dem::write_packing(save_packing, c.pk);
  return c;
}

/// The cube bonded (elastic links, about 12 per sphere), its bottom held
/// and its top pulled; `repeat` blocks of `steps` timed steps, the fastest
/// kept. Prints its row and returns its figures.
nlohmann::json measure(const Cube& c, int steps, int repeat)
{
  using namespace dembridge;
  double solid = 0.0;
  for (double r : c.pk.r)
    solid += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  dem::Material mat;
  mat.tensile = mat.cohesion = 1e12; // elastic links
  auto p = dem::make_particles(c.pk.x, c.pk.r, mat.density, solid / std::pow(c.side, 3));
  const double lambda = dem::lambda_for_mean_links(p.x, p.r, 12.0);
  auto links = dem::create_links(p, lambda, mat);
  const double dt = 0.9 * dem::critical_time_step(p, links);
  const double rmin = *std::min_element(p.r.begin(), p.r.end());
  dem::DemSolver solver(p, links, mat, dt, 0.0, 0.5 * rmin);
  const double rmax = *std::max_element(p.r.begin(), p.r.end());
  auto bottom = dem::DemSolver::select(p, [&](const auto& x) { return x[2] < rmax; }, "bottom");
  auto top = dem::DemSolver::select(p, [&](const auto& x) { return x[2] > c.side - rmax; }, "top");
  solver.add_motion({"bottom", bottom, dem::MotionKind::fixed, {true, true, true}, {}});
  solver.add_motion({"top", top, dem::MotionKind::velocity, {false, false, true}, [](double) { return 0.01; }});
  solver.start();
  solver.step(); // warm-up
  double sec = 1e300, share_f = 0.0, share_n = 0.0, share_i = 0.0;
  for (int rep = 0; rep < std::max(repeat, 1); ++rep)
  {
    const dem::DemTimings before = solver.timings();
    demo::Stopwatch t;
    for (int s = 0; s < steps; ++s)
      solver.step();
    const double block = t.seconds();
    if (block < sec)
    {
      sec = block;
      const dem::DemTimings& tm = solver.timings();
      share_f = (tm.forces - before.forces) / sec;
      share_n = (tm.neighbours - before.neighbours) / sec;
      share_i = (tm.integration - before.integration) / sec;
    }
  }
  const double ns_link = 1e9 * sec / (double(steps) * links.size());
  const double ns_part = 1e9 * sec / (double(steps) * p.size());
  const auto& nl = solver.neighbours();
  const std::size_t mem = bytes(p.x) + bytes(p.x0) + bytes(p.v) + bytes(p.w) + bytes(p.f) + bytes(p.t) + bytes(p.r)
                          + bytes(p.m) + bytes(p.inertia) + bytes(p.weight) + bytes(links.a) + bytes(links.b)
                          + bytes(links.d0) + bytes(links.kn) + bytes(links.ks) + bytes(links.fs) + bytes(links.n)
                          + bytes(links.delta_max) + bytes(links.state) + bytes(links.weight)
                          + solver.bytes(); // neighbour list and force-loop scratch
  const double bpl = double(mem) / links.size();
  const int threads = omp_get_max_threads();
  std::printf("%11zu %10zu %8d %13.1f %17.1f %11.1f %18.0f %6.0f%% %10.0f%% %11.0f%%\n", p.size(), links.size(),
              threads, ns_link, ns_part, bpl, c.pack_rate, 100 * share_f, 100 * share_n, 100 * share_i);
  return {{"particles", p.size()}, {"links", links.size()}, {"threads", threads},
          {"ns_per_link_step", ns_link}, {"ns_per_particle_step", ns_part},
          {"bytes_per_link", bpl}, {"packing_spheres_per_s", c.pack_rate},
          {"neighbour_pairs", nl.size()},
          {"share_forces", share_f}, {"share_neighbours", share_n},
          {"share_integration", share_i}, {"neighbour_builds", nl.builds()}, {"steps", steps}, {"wall_s", sec}};
}
} // namespace

int main(int argc, char** argv)
{
  using namespace dembridge;
  std::vector<long> sizes{10000, 50000};
  int steps = 200;
  std::string packing_file, output, summary;
  CLI::App app{"DEM step throughput on a bonded cube", "dem_throughput"};
  using demo::Allowed;
  demo::add_integers(app, "--particles", sizes, "numbers of spheres (one run each)", Allowed::closed(8, 1e8));
  demo::add_input_file(app, "--packing", packing_file, "use this 'x y z r' packing [m] instead of generating");
  std::string save_packing;
  demo::add_output_file(app, "--save-packing", save_packing,
                        "write the generated packing of the last size to this 'x y z r' file");
  demo::add_integer(app, "--steps", steps, "timed steps per block", Allowed::closed(1, 1e7));
  int repeat = 3;
  demo::add_integer(app, "--repeat", repeat, "timed blocks per size; the fastest is reported (a shared "
                                             "machine's noise only ever slows a block down)", Allowed::closed(1, 1000));
  demo::add_output_dir(app, "--output", output, "output folder (unused: only the summary is written)");
  demo::add_output_file(app, "--summary", summary, "JSON file with the figures");
  if (const int rc = demo::parse_options(app, argc, argv); rc >= 0)
    return rc;

  return demo::run_guarded(argc, argv, [&]
  {
    demo::echo_options(app);
    if (steps < 1)
      throw std::runtime_error("--steps " + std::to_string(steps) + ": must be >= 1");
    nlohmann::json cases = nlohmann::json::array();
    std::cout << "  particles      links  threads  ns/link-step  ns/particle-step  bytes/link  "
                 "packing spheres/s  forces  neighbours  integration\n";
    const std::size_t runs = packing_file.empty() ? sizes.size() : 1;
    for (std::size_t run = 0; run < runs; ++run)
      cases.push_back(measure(cube(packing_file, sizes[run], run + 1 == runs ? save_packing : ""), steps, repeat));
    nlohmann::json out = cases.back();
    out["cases"] = cases;
    out["peak_rss_bytes"] = demo::peak_rss_bytes();
    if (!summary.empty())
      demo::write_summary(summary, out);
  }, summary);
}
