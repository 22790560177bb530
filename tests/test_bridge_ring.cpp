// The coupling through a ring-shaped overlap: a square plate of shells with
// a square hole round a DE core, the band of width 20 mm round the hole
// shared. The patch tests of the planar overlap, on the ring: a uniform
// velocity is carried unchanged, a rigid rotation is left as it is by the
// multiplier correction, and the constraint holds after every step.
#include "dembridge/bridge/coupled.h"
#include "dembridge/bridge/slab.h"
#include "dembridge/dem/material_file.h"
#include "dembridge/dem/packing.h"
#include "dembridge/shell/gmsh.h"
#include "dembridge/shell/mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mpi.h>
#include <numbers>
#include <omp.h>
#include <unistd.h>
#include <catch2/catch.hpp>

using namespace dembridge;

namespace
{
constexpr double side = 0.16, thick = 0.02, band = 0.02;
const std::array<double, 2> centre{0.08, 0.08}, half{0.03, 0.03}; // the core: the hole [0.05, 0.11]^2

struct Ring
{
  std::unique_ptr<shell::FEModel> fe;
  dem::Particles p;
  dem::Links l;
  dem::Material mat;
  bridge::Overlap overlap = bridge::Overlap::box(centre, half, band);
};

/// The plate's shells on `mesh` and elastic spheres of 2.5 mm packed in `region`.
Ring make_ring(std::shared_ptr<dolfinx::mesh::Mesh> mesh, const bridge::Overlap& overlap, const dem::Region& region)
{
  Ring b;
  b.overlap = overlap;
  shell::Material sm;
  sm.thickness = thick;
  b.fe = std::make_unique<shell::FEModel>(mesh, sm);
  dem::PackingOptions po;
  po.mean_radius = 2.5e-3;
  const auto pk = dem::generate_packing(region, po);
  double solid = 0.0;
  for (double r : pk.r)
    solid += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  b.mat = dem::read_material(DEMBRIDGE_SOURCE_DIR "/demos/calibrate/materials/default.json").material;
  b.mat.tensile = b.mat.cohesion = 1e12; // elastic
  b.p = dem::make_particles(pk.x, pk.r, b.mat.density, solid / region.volume);
  b.l = dem::create_links(b.p, dem::lambda_for_mean_links(b.p.x, b.p.r, 12.0), b.mat);
  return b;
}

/// The square hole on a 10 mm grid of quadrilaterals, its edges on the
/// grid's lines; the spheres in the core and its band (the band's corners
/// rounded where the distance is), through the plate's thickness.
Ring make_ring()
{
  const auto overlap = bridge::Overlap::box(centre, half, band);
  const auto region = dem::sdf_region(
      "core and band",
      [overlap](const dem::Point& x)
      { return std::max(overlap.distance({x[0], x[1], x[2]}) - band, std::abs(x[2]) - 0.5 * thick); },
      {0.03, 0.03, -0.5 * thick}, {0.13, 0.13, 0.5 * thick});
  return make_ring(shell::create_shell_rectangle_with_hole(MPI_COMM_WORLD, side, side, 16, 16,
                                                           {{0.05, 0.05}, {0.11, 0.11}}, shell::Cell::quadrilateral),
                   overlap, region);
}

struct Drift
{
  double de = 0.0, fe = 0.0, residual = 0.0;
};

/// Every sphere and shell node starts at velocity V; `steps` coupled steps;
/// the largest deviations from V and the largest constraint residual.
Drift uniform_velocity(Ring& b, const std::array<double, 3>& V, int steps)
{
  bridge::CouplingOptions o;
  o.overlap = b.overlap;
  bridge::CoupledSolver s(*b.fe, b.p, b.l, b.mat, o);
  REQUIRE(s.constrained() > 100); // the ring holds spheres all round
  std::vector<double> u(b.fe->num_dofs(), 0.0), v(b.fe->num_dofs(), 0.0);
  for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
    for (int d = 0; d < 3; ++d)
      v[6 * k + d] = V[d];
  for (std::size_t i = 0; i < b.p.size(); ++i)
    for (int d = 0; d < 3; ++d)
      b.p.v[3 * i + d] = V[d];
  s.start(u, v);
  Drift off;
  for (int k = 0; k < steps; ++k)
    off.residual = std::max(off.residual, s.step());
  for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
    for (int d = 0; d < 3; ++d)
      off.fe = std::max(off.fe, std::abs(s.fe().v()[6 * k + d] - V[d]));
  for (std::size_t i = 0; i < b.p.size(); ++i)
    for (int d = 0; d < 3; ++d)
      off.de = std::max(off.de, std::abs(b.p.v[3 * i + d] - V[d]));
  return off;
}
} // namespace

TEST_CASE("ring overlap: a uniform velocity is carried unchanged, the constraint held every step",
          "[bridge][coupled][ring]")
{
  auto b = make_ring();
  // the residual after each correction: the constraint G_FE v_FE = G_DE v_DE
  // holds to the multiplier solve's round-off (the required 1e-10 of the motion)
  const std::array<double, 3> V{0.3, -0.2, 0.1};
  const double vn = std::sqrt(0.14);
  const Drift off = uniform_velocity(b, V, 200);
  INFO("off by " << off.de << " m/s (spheres), " << off.fe << " m/s (shell nodes); largest residual " << off.residual
                 << " m/s");
  CHECK(off.residual < 1e-10 * vn);
  CHECK(off.de < 1e-10 * vn);
  CHECK(off.fe < 1e-10 * vn);
}

TEST_CASE("ring overlap: a rigid rotation is left as it is by the correction, then changes at second order",
          "[bridge][coupled][ring]")
{
  // As the planar patch test (test_bridge_coupled.cpp): the rigid field
  // satisfies the constraint, so start()'s correction changes nothing (the
  // required 1e-10); over steps, straight-line drift strains the links at
  // second order in omega t, so halving omega divides the deviation by 4.
  auto b0 = make_ring();
  const std::vector<double> x0 = b0.p.x;
  struct Off
  {
    double de = 0.0, fe = 0.0, vmax = 0.0, residual = 0.0;
  };
  auto run = [&](double scale)
  {
    auto b = make_ring(); // the same packing (deterministic)
    REQUIRE(b.p.x == x0);
    bridge::CouplingOptions o;
    o.overlap = b.overlap;
    bridge::CoupledSolver s(*b.fe, b.p, b.l, b.mat, o);
    const std::array<double, 3> om{0.2 * scale, -0.1 * scale, 0.3 * scale}, c{0.08, 0.08, 0.0};
    auto rigid = [&](const double* x)
    {
      const double r[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
      return std::array<double, 3>{om[1] * r[2] - om[2] * r[1], om[2] * r[0] - om[0] * r[2],
                                   om[0] * r[1] - om[1] * r[0]};
    };
    const auto xn = b.fe->node_coordinates();
    std::vector<double> u(b.fe->num_dofs(), 0.0), v(b.fe->num_dofs(), 0.0);
    for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
    {
      const auto vk = rigid(&xn[3 * k]);
      for (int d = 0; d < 3; ++d)
      {
        v[6 * k + d] = vk[d];
        v[6 * k + 3 + d] = om[d];
      }
    }
    for (std::size_t i = 0; i < b.p.size(); ++i)
    {
      const auto vi = rigid(&x0[3 * i]);
      for (int d = 0; d < 3; ++d)
      {
        b.p.v[3 * i + d] = vi[d];
        b.p.w[3 * i + d] = om[d];
      }
    }
    auto measure = [&](Off off)
    {
      for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
      {
        const auto vk = rigid(&xn[3 * k]);
        for (int d = 0; d < 3; ++d)
        {
          off.vmax = std::max(off.vmax, std::abs(vk[d]));
          off.fe = std::max(off.fe, std::abs(s.fe().v()[6 * k + d] - vk[d]));
        }
      }
      for (std::size_t i = 0; i < b.p.size(); ++i)
      {
        const auto vi = rigid(&x0[3 * i]);
        for (int d = 0; d < 3; ++d)
          off.de = std::max(off.de, std::abs(b.p.v[3 * i + d] - vi[d]));
      }
      return off;
    };
    s.start(u, v);
    const Off at_start = measure({});
    Off after;
    for (int k = 0; k < 10; ++k)
      after.residual = std::max(after.residual, s.step());
    return std::pair{at_start, measure(after)};
  };
  const auto [start_full, full] = run(1.0);
  const Off half_omega = run(0.5).second;
  INFO("after start(): spheres off by " << start_full.de << " m/s, shell nodes by " << start_full.fe
                                        << " m/s, largest velocity " << start_full.vmax << " m/s");
  CHECK(start_full.de < 1e-10 * start_full.vmax);
  CHECK(start_full.fe < 1e-10 * start_full.vmax);
  INFO("after 10 steps: spheres off by " << full.de << " m/s (half omega " << half_omega.de << "), shell nodes by "
                                         << full.fe << " (" << half_omega.fe << "); largest residual " << full.residual);
  CHECK(full.residual < 1e-10 * full.vmax);
  // second order: x 1/4 with half omega (3 allows for round-off)
  CHECK(half_omega.de < full.de / 3.0);
  CHECK(half_omega.fe < full.fe / 3.0);
}

TEST_CASE("ring overlap: the shells' mesh with a hole", "[shell][ring]")
{
  auto mesh = shell::create_shell_rectangle_with_hole(MPI_COMM_WORLD, side, side, 16, 16, {{0.05, 0.05}, {0.11, 0.11}},
                                                      shell::Cell::quadrilateral);
  shell::Material sm;
  sm.thickness = thick;
  shell::FEModel fe(mesh, sm);
  // 17^2 grid vertices less the 5^2 strictly inside the hole
  CHECK(fe.num_nodes() == 17 * 17 - 5 * 5);
  const auto x = fe.node_coordinates();
  for (std::size_t k = 0; k < fe.num_nodes(); ++k)
  {
    const bool inside = x[3 * k] > 0.05 + 1e-12 && x[3 * k] < 0.11 - 1e-12 && x[3 * k + 1] > 0.05 + 1e-12
                        && x[3 * k + 1] < 0.11 - 1e-12;
    CHECK(!inside);
  }
  // its boundary: the outline's 4 x 16 nodes and the hole's edge, 4 x 6
  const auto edge = fe.boundary_nodes();
  CHECK(edge.size() == 4 * 16 + 4 * 6);
  for (std::int32_t k : edge)
  {
    const double* p = &x[3 * k];
    auto on = [](double v, double a) { return std::abs(v - a) < 1e-12; };
    const bool outline = on(p[0], 0.0) || on(p[0], side) || on(p[1], 0.0) || on(p[1], side);
    const bool hole = (on(p[0], 0.05) || on(p[0], 0.11) || on(p[1], 0.05) || on(p[1], 0.11))
                      && p[0] > 0.05 - 1e-12 && p[0] < 0.11 + 1e-12 && p[1] > 0.05 - 1e-12 && p[1] < 0.11 + 1e-12;
    CHECK((outline || hole));
  }
  using Catch::Contains;
  CHECK_THROWS_WITH(shell::create_shell_rectangle_with_hole(MPI_COMM_WORLD, side, side, 16, 16,
                                                            {{0.055, 0.05}, {0.11, 0.11}}, shell::Cell::quadrilateral),
                    Contains("hole x from 0.055") && Contains("grid line"));
  CHECK_THROWS_WITH(shell::create_shell_rectangle_with_hole(MPI_COMM_WORLD, side, side, 16, 16,
                                                            {{0.11, 0.05}, {0.05, 0.11}}, shell::Cell::quadrilateral),
                    Contains("upper corner must exceed"));
  CHECK_THROWS_WITH(shell::create_shell_rectangle_with_hole(MPI_COMM_WORLD, side, side, 16, 16,
                                                            {{0.0, 0.0}, {side, side}}, shell::Cell::triangle),
                    Contains("no cell left"));
}

namespace
{
/// The shells' area [m^2] from their cells (flat: two triangles per quadrilateral).
double mesh_area(const shell::FEModel& fe)
{
  const auto x = fe.node_coordinates();
  const auto cells = fe.cell_nodes();
  const std::size_t npc = static_cast<std::size_t>(fe.nodes_per_cell());
  auto tri = [&](int a, int b, int c)
  {
    const double u[3] = {x[3 * b] - x[3 * a], x[3 * b + 1] - x[3 * a + 1], x[3 * b + 2] - x[3 * a + 2]};
    const double v[3] = {x[3 * c] - x[3 * a], x[3 * c + 1] - x[3 * a + 1], x[3 * c + 2] - x[3 * a + 2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    return 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  };
  double area = 0.0;
  for (std::size_t c = 0; c < cells.size(); c += npc)
  {
    const auto* v = &cells[c];
    area += npc == 3 ? tri(v[0], v[1], v[2]) : tri(v[0], v[1], v[3]) + tri(v[0], v[3], v[2]);
  }
  return area;
}

/// The shells on `mesh` with the ring's section.
shell::FEModel shells(std::shared_ptr<dolfinx::mesh::Mesh> mesh)
{
  shell::Material sm;
  sm.thickness = thick;
  return shell::FEModel(mesh, sm);
}

/// The test slab's outline with a circular hole of 30 mm about its centre,
/// elements of 10 mm.
shell::SlabOutline circle_outline()
{
  shell::SlabOutline o;
  o.lx = o.ly = side;
  o.hole = shell::SlabOutline::Hole::circle;
  o.centre = centre;
  o.radius = 0.03;
  o.size = 0.01;
  return o;
}
} // namespace

TEST_CASE("Gmsh: a slab's outline with a circular hole, quadrilaterals", "[shell][ring][gmsh]")
{
  const shell::SlabOutline o = circle_outline();
  const shell::FEModel fe = shells(shell::mesh_outline(MPI_COMM_WORLD, o, shell::Cell::quadrilateral));
  CHECK(fe.nodes_per_cell() == 4);
  // the hole's boundary: a regular polygon of N nodes on the circle (each
  // quarter arc divided alike), so the area is exactly the square's less it
  const auto x = fe.node_coordinates();
  const std::size_t nn = x.size() / 3;
  int on_circle = 0;
  double inside = 0.0;
  for (std::size_t k = 0; k < nn; ++k)
  {
    const double r = std::hypot(x[3 * k] - centre[0], x[3 * k + 1] - centre[1]);
    on_circle += std::abs(r - o.radius) < 1e-12;
    inside = std::max(inside, o.radius - r);
  }
  REQUIRE(on_circle >= 16);
  const double N = on_circle, polygon = 0.5 * N * o.radius * o.radius * std::sin(2.0 * std::numbers::pi / N);
  INFO(nn << " nodes, " << on_circle << " on the hole's circle");
  CHECK(std::abs(mesh_area(fe) / (side * side - polygon) - 1.0) < 1e-12);
  CHECK(inside < 1e-12); // no node inside the hole
  // triangles on request
  CHECK(shells(shell::mesh_outline(MPI_COMM_WORLD, o, shell::Cell::triangle)).nodes_per_cell() == 3);
  // bad outlines, named
  using Catch::Contains;
  auto bad = o;
  bad.radius = 0.09;
  CHECK_THROWS_WITH(shell::mesh_outline(MPI_COMM_WORLD, bad, shell::Cell::triangle),
                    Contains("must lie strictly inside the slab"));
  bad = o;
  bad.size = 0.0;
  CHECK_THROWS_WITH(shell::mesh_outline(MPI_COMM_WORLD, bad, shell::Cell::triangle), Contains("element size 0 m"));
  CHECK_THROWS_WITH(shell::mesh_outline(MPI_COMM_WORLD, o, shell::Cell::hexahedron), Contains("not hexahedron"));
}

TEST_CASE("Gmsh: meshing leaves the process's OpenMP thread count as it was", "[shell][gmsh]")
{
  // Gmsh sets the OpenMP thread count to its own option (1) when it starts
  // and when it meshes: without the session's restore, a coupled slab's
  // spheres would step on one thread after their shells were meshed.
  struct Restore // (the count the other tests run with, whatever happens here)
  {
    int n = omp_get_max_threads();
    ~Restore() { omp_set_num_threads(n); }
  } restore;
  omp_set_num_threads(3);
  const shell::FEModel fe = shells(shell::mesh_outline(MPI_COMM_WORLD, circle_outline(), shell::Cell::quadrilateral));
  const int after = omp_get_max_threads();
  CHECK(fe.nodes_per_cell() == 4);
  CHECK(after == 3);
}

TEST_CASE("Gmsh: a .msh file is read; bad files are refused naming them", "[shell][gmsh]")
{
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("dembridge-gmsh-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // two quadrilaterals over [0, 2] x [0, 1] (MSH 2.2, ASCII)
  {
    std::ofstream f(dir / "two.msh");
    f << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n6\n1 0 0 0\n2 1 0 0\n3 2 0 0\n4 0 1 0\n5 1 1 0\n6 2 1 0\n"
         "$EndNodes\n$Elements\n2\n1 3 2 1 1 1 2 5 4\n2 3 2 1 1 2 3 6 5\n$EndElements\n";
  }
  const shell::FEModel fe = shells(shell::read_gmsh(MPI_COMM_WORLD, dir / "two.msh"));
  CHECK(fe.cell_nodes().size() == 2 * 4);
  CHECK(std::abs(mesh_area(fe) - 2.0) < 1e-14);
  CHECK(fe.num_nodes() == 6);
  {
    std::ofstream f(dir / "bad.msh");
    f << "not a mesh\n";
  }
  using Catch::Contains;
  CHECK_THROWS_WITH(shell::read_gmsh(MPI_COMM_WORLD, dir / "missing.msh"), Contains("missing.msh: no such file"));
  CHECK_THROWS_WITH(shell::read_gmsh(MPI_COMM_WORLD, dir / "bad.msh"), Contains("bad.msh"));
  fs::remove_all(dir);
}

namespace
{
/// The plate of the ring tests as the coupled slab's builder makes it
/// (slab.h), centred on the origin: a cylinder core of 30 mm, shells of 10 mm.
bridge::SlabSpec cylinder_slab(shell::Cell cell)
{
  bridge::SlabSpec spec;
  spec.size = {side, side};
  spec.thickness = thick;
  spec.core = bridge::SlabSpec::Core::cylinder;
  spec.core_radius = 0.03;
  spec.band = band;
  spec.element_size = 0.01;
  spec.cell = cell;
  return spec;
}
} // namespace

TEST_CASE("ring overlap round a cylinder core, shells meshed by Gmsh: a uniform velocity is carried unchanged",
          "[bridge][coupled][ring][gmsh]")
{
  // the parts from the coupled slab's builder (slab.h), in its frame: the
  // plate centred on the origin, z in [-thick, 0]
  bridge::SlabSpec spec = cylinder_slab(shell::Cell::quadrilateral);
  const dem::Region region = bridge::slab_de_region(spec);
  auto b = make_ring(bridge::slab_shells(MPI_COMM_WORLD, spec), bridge::slab_overlap(spec), region);
  // the shells: none inside the core, at the mid-surface
  const auto x = b.fe->node_coordinates();
  double inside = 0.0, off_plane = 0.0;
  for (std::size_t k = 0; 3 * k < x.size(); ++k)
  {
    inside = std::max(inside, -b.overlap.distance({x[3 * k], x[3 * k + 1], x[3 * k + 2]}));
    off_plane = std::max(off_plane, std::abs(x[3 * k + 2] + 0.5 * thick));
  }
  CHECK(inside < 1e-12);
  CHECK(off_plane < 1e-12);
  // the DE region: the cylinder of radius r + band through the thickness
  // (its volume measured on a grid, 1e-2)
  CHECK(std::abs(region.volume / (std::numbers::pi * 0.05 * 0.05 * thick) - 1.0) < 1e-2);
  const std::array<double, 3> V{0.3, -0.2, 0.1};
  const double vn = std::sqrt(0.14);
  const Drift off = uniform_velocity(b, V, 100);
  INFO("off by " << off.de << " m/s (spheres), " << off.fe << " m/s (shell nodes); largest residual " << off.residual);
  CHECK(off.residual < 1e-10 * vn);
  CHECK(off.de < 1e-10 * vn);
  CHECK(off.fe < 1e-10 * vn);
  // the supports: the outer edges' nodes, 3 dofs each simply supported, 6 clamped
  const auto held = bridge::slab_support_dofs(*b.fe, spec);
  spec.edges = bridge::SlabSpec::Edges::clamped;
  const auto clamped = bridge::slab_support_dofs(*b.fe, spec);
  REQUIRE(held.size() > 0);
  CHECK(2 * held.size() == clamped.size());
  for (std::size_t q = 0; q < held.size(); q += 3)
  {
    const std::size_t k = held[q] / 6;
    CHECK(std::max(std::abs(x[3 * k]), std::abs(x[3 * k + 1])) > 0.5 * side - 1e-9);
  }
  spec.edges = bridge::SlabSpec::Edges::free;
  CHECK(bridge::slab_support_dofs(*b.fe, spec).empty());
  using Catch::Contains;
  spec.band = 0.06; // the band reaches past the plate's edge
  CHECK_THROWS_WITH(bridge::slab_de_region(spec), Contains("must lie strictly inside the slab"));
  spec.band = 0.005; // narrower than the shells' elements
  CHECK_THROWS_WITH(bridge::slab_shells(MPI_COMM_WORLD, spec), Contains("must not exceed the overlap band"));
}

TEST_CASE("shell meshes that do not fit the slab's core are refused", "[bridge][ring][gmsh]")
{
  // A mesh made elsewhere for a coupled slab (read_gmsh, one's own) must
  // leave the core to the spheres and reach the band's inner edge: shells
  // inside the core would stand where only spheres should, a hole larger
  // than the core would leave the band's spheres in no element (tied by
  // extrapolation, or refused only at a thickness away). The meshes below
  // are the builder's for other slabs, checked against this one.
  using Catch::Contains;
  for (auto cell : {shell::Cell::quadrilateral, shell::Cell::triangle})
  {
    const bridge::SlabSpec spec = cylinder_slab(cell);
    const auto mesh_for = [&](auto change)
    {
      bridge::SlabSpec other = spec;
      change(other);
      return shells(bridge::slab_shells(MPI_COMM_WORLD, other));
    };
    CHECK_NOTHROW(bridge::check_slab_shells(shells(bridge::slab_shells(MPI_COMM_WORLD, spec)), spec));
    // within 1 % of the band (0.2 mm) passes, 2 mm does not
    CHECK_NOTHROW(bridge::check_slab_shells(mesh_for([](auto& o) { o.core_radius += 1e-4; }), spec));
    CHECK_THROWS_WITH(bridge::check_slab_shells(mesh_for([](auto& o) { o.core_radius += 2e-3; }), spec),
                      Contains("of the hole's edge lie beyond a cylinder core of radius 0.03 m")
                          && Contains("the farthest by 0.002 m"));
    CHECK_THROWS_WITH(bridge::check_slab_shells(mesh_for([](auto& o) { o.core_radius -= 2e-3; }), spec),
                      Contains("lie inside a cylinder core of radius 0.03 m"));
    // a square hole round the round core: its corners reach beyond
    CHECK_THROWS_WITH(bridge::check_slab_shells(mesh_for(
                                                    [](auto& o)
                                                    {
                                                      o.core = bridge::SlabSpec::Core::box;
                                                      o.core_half = {o.core_radius, o.core_radius};
                                                    }),
                                                spec),
                      Contains("of the hole's edge lie beyond") && Contains("the farthest by 0.0124"));
    // the core elsewhere in the plan
    CHECK_THROWS_WITH(bridge::check_slab_shells(mesh_for([](auto& o) { o.centre = {0.01, 0.0}; }), spec),
                      Contains("lie inside a cylinder core"));
    // at another height: the mid-surface of a 30 mm slab
    CHECK_THROWS_WITH(bridge::check_slab_shells(mesh_for([](auto& o) { o.thickness = 0.03; }), spec),
                      Contains("lie off the slab's mid-surface z = -0.01 m") && Contains("the farthest by 0.005 m"));
    // a larger plan
    CHECK_THROWS_WITH(bridge::check_slab_shells(mesh_for([](auto& o) { o.size = {0.2, 0.2}; }), spec),
                      Contains("lie outside the slab's plan, 0.16 x 0.16 m"));
    // a smaller plan
    CHECK_THROWS_WITH(bridge::check_slab_shells(mesh_for([](auto& o) { o.size = {0.16, 0.14}; }), spec),
                      Contains("it reaches -0.07 m along y, short of the slab's plan"));
    // no hole: 3 x 3 elements of 53 mm, whose nodes all lie outside the
    // 30 mm core, cover it whole
    const shell::Placement at{{-0.5 * side, -0.5 * side, -0.5 * thick}};
    CHECK_THROWS_WITH(bridge::check_slab_shells(shells(shell::create_shell_rectangle(MPI_COMM_WORLD, side, side, 3, 3, cell, at)), spec),
                      Contains("no hole for a cylinder core of radius 0.03 m"));
  }
}

namespace
{

/// The first mode's shape of the simply supported square plate, sin sin.
double mode(const double* x) { return std::sin(std::numbers::pi * x[0] / side) * std::sin(std::numbers::pi * x[1] / side); }

/// The translations of the nodes on the plate's outer edges (simply supported, held in plane).
std::vector<std::int32_t> edge_dofs(const shell::FEModel& fe)
{
  const auto nodes = shell::select_nodes(
      fe.node_coordinates(),
      [](const std::array<double, 3>& x)
      { return x[0] < 1e-9 || x[1] < 1e-9 || x[0] > side - 1e-9 || x[1] > side - 1e-9; },
      "edges");
  const std::vector<int> translations{0, 1, 2};
  return shell::node_dofs(nodes, fe.block_size(), translations);
}

/// The times at which w(t) crosses zero downwards then upwards: half a
/// period and a period after a start at w = 0 moving up.
struct Crossings
{
  double half = 0.0, full = 0.0, peak = 0.0;
  void add(double t_old, double w_old, double t, double w)
  {
    peak = std::max(peak, w);
    if (w_old > 0.0 && w <= 0.0 && half == 0.0)
      half = t_old + (t - t_old) * w_old / (w_old - w);
    if (w_old < 0.0 && w >= 0.0 && half > 0.0 && full == 0.0)
      full = t_old + (t - t_old) * w_old / (w_old - w);
  }
};
} // namespace

namespace
{
constexpr double V_mode = 0.1; // the first mode's velocity at the centre [m/s]

/// The all-shell plate (the ring's grid, no hole), started in its first mode.
Crossings all_shell_plate()
{
  shell::Material sm;
  sm.thickness = thick; // (E, nu and rho the defaults, the concrete's)
  shell::FEModel whole(shell::create_shell_rectangle(MPI_COMM_WORLD, side, side, 16, 16, shell::Cell::quadrilateral),
                       sm);
  const auto m = whole.lumped_mass();
  shell::ExplicitSolver fe(m, whole.internal_force_fn(), 0.8 * whole.critical_time_step(m), 0.0);
  fe.add_motion({"edges", edge_dofs(whole), shell::MotionKind::fixed, {}});
  const auto xw = whole.node_coordinates();
  std::vector<double> u(whole.num_dofs(), 0.0), v(whole.num_dofs(), 0.0);
  std::size_t centre_node = 0;
  for (std::size_t k = 0; k < whole.num_nodes(); ++k)
  {
    v[6 * k + 2] = V_mode * mode(&xw[3 * k]);
    if (std::hypot(xw[3 * k] - 0.08, xw[3 * k + 1] - 0.08) < 1e-9)
      centre_node = k;
  }
  fe.set_state(u, v);
  Crossings c;
  for (double t = 0.0, w = 0.0; c.full == 0.0 && t < 2e-3;)
  {
    fe.step();
    const double t_new = t + fe.dt(), w_new = fe.u()[6 * centre_node + 2];
    c.add(t, w, t_new, w_new);
    t = t_new;
    w = w_new;
  }
  return c;
}

/// The mean z displacement of the spheres `ids`.
double mean_w(const dem::Particles& p, const std::vector<std::int32_t>& ids)
{
  double w = 0.0;
  for (auto i : ids)
    w += p.x[3 * i + 2] - p.x0[3 * i + 2];
  return w / double(ids.size());
}

/// The all-DE plate of spheres of mean radius r, started in its first mode;
/// simply supported: the outermost spheres of the mid-surface's edge lines
/// (within r of a lateral face and of the mid-surface) held along z only,
/// so that the edges turn freely (holding a band through the thickness, or
/// in plane too, clamps them: 28 % shorter periods).
Crossings all_de_plate(double r, std::size_t& spheres)
{
  dem::PackingOptions po;
  po.mean_radius = r;
  const auto region = dem::box_region({0.0, 0.0, -0.5 * thick}, {side, side, 0.5 * thick});
  const auto pk = dem::generate_packing(region, po);
  double solid = 0.0;
  for (double q : pk.r)
    solid += 4.0 / 3.0 * std::numbers::pi * q * q * q;
  dem::Material mat = dem::read_material(DEMBRIDGE_SOURCE_DIR "/demos/calibrate/materials/default.json").material;
  mat.tensile = mat.cohesion = 1e12;
  dem::Particles p = dem::make_particles(pk.x, pk.r, mat.density, solid / region.volume);
  dem::Links l = dem::create_links(p, dem::lambda_for_mean_links(p.x, p.r, 12.0), mat);
  dem::DemSolver s(p, l, mat, 0.8 * dem::critical_time_step(p, l), 0.0, 0.5 * r);
  auto on_edge = [&](const std::array<double, 3>& x)
  { return (x[0] < r || x[1] < r || x[0] > side - r || x[1] > side - r) && std::abs(x[2]) < r; };
  s.add_motion({"edges", dem::DemSolver::select(p, on_edge, "edges"), dem::MotionKind::displacement,
                {false, false, true}, [](double) { return 0.0; }});
  std::vector<std::int32_t> middle;
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    p.v[3 * i + 2] = V_mode * mode(&p.x[3 * i]);
    if (std::hypot(p.x[3 * i] - 0.08, p.x[3 * i + 1] - 0.08) < 6e-3)
      middle.push_back(static_cast<std::int32_t>(i));
  }
  s.start();
  Crossings c;
  for (double t = 0.0, w = 0.0; c.full == 0.0 && t < 2e-3;)
  {
    s.step();
    const double w_new = mean_w(p, middle);
    c.add(t, w, t + s.dt(), w_new);
    t += s.dt();
    w = w_new;
  }
  spheres = p.size();
  return c;
}
} // namespace

TEST_CASE("ring overlap: an elastic plate's first mode, coupled against all shells and all DE", "[bridge][coupled][ring][long]")
{
  // A simply supported square plate (0.16 m, 20 mm thick, the default
  // concrete's E 30 GPa, nu 0.2, 2400 kg/m^3) starts with the velocity of
  // its first mode, sin(std::numbers::pi x / a) sin(std::numbers::pi y / a) x 0.1 m/s: all shells; all
  // DE (2.5 mm spheres); and shells round a DE core (the ring set-up
  // above). The coupled plate's period and peak deflection at the centre
  // must agree with each of the others within 2 % and 5 % (the issue's
  // bounds): the core is the same concrete, so the coupling must neither
  // stiffen nor soften the plate.
  const Crossings shells = all_shell_plate();
  REQUIRE(shells.full > 0.0);
  std::size_t n_de = 0;
  const Crossings de = all_de_plate(2.5e-3, n_de);
  REQUIRE(de.full > 0.0);

  auto b = make_ring();
  bridge::CouplingOptions o;
  o.overlap = b.overlap;
  bridge::CoupledSolver s(*b.fe, b.p, b.l, b.mat, o);
  s.fe().add_motion({"edges", edge_dofs(*b.fe), shell::MotionKind::fixed, {}});
  const auto xr = b.fe->node_coordinates();
  std::vector<double> ur(b.fe->num_dofs(), 0.0), vr(b.fe->num_dofs(), 0.0);
  for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
    vr[6 * k + 2] = V_mode * mode(&xr[3 * k]);
  std::vector<std::int32_t> middle;
  for (std::size_t i = 0; i < b.p.size(); ++i)
  {
    b.p.v[3 * i + 2] = V_mode * mode(&b.p.x[3 * i]);
    if (std::hypot(b.p.x[3 * i] - 0.08, b.p.x[3 * i + 1] - 0.08) < 6e-3)
      middle.push_back(static_cast<std::int32_t>(i));
  }
  REQUIRE(middle.size() > 5);
  s.start(ur, vr);
  Crossings coupled;
  for (double t = 0.0, w = 0.0; coupled.full == 0.0 && t < 2e-3;)
  {
    s.step(false);
    const double t_new = t + s.dt(), w_new = mean_w(b.p, middle);
    coupled.add(t, w, t_new, w_new);
    t = t_new;
    w = w_new;
  }
  REQUIRE(coupled.full > 0.0);
  INFO("period: shells " << shells.full << " s, all DE " << de.full << " s (" << n_de << " spheres), coupled "
                         << coupled.full << " s; peak deflection " << shells.peak << ", " << de.peak << ", "
                         << coupled.peak << " m");
  CHECK(std::abs(coupled.full / shells.full - 1.0) < 0.02);
  CHECK(std::abs(coupled.peak / shells.peak - 1.0) < 0.05);
  CHECK(std::abs(coupled.full / de.full - 1.0) < 0.02);
  CHECK(std::abs(coupled.peak / de.peak - 1.0) < 0.05);
}

TEST_CASE("study: the all-DE plate's first mode at two sphere sizes", "[.][study][long]")
{
  // build/bin/unit_tests "[study]": the all-DE plate against the all-shell
  // plate at 2.5 and 1.75 mm (not run by the suite)
  const Crossings shells = all_shell_plate();
  for (double r : {2.5e-3, 1.75e-3})
  {
    std::size_t n = 0;
    const Crossings de = all_de_plate(r, n);
    WARN("mean radius " << r << " m, " << n << " spheres: period " << de.full << " s against the shells' "
                        << shells.full << " s (" << 100.0 * (de.full / shells.full - 1.0) << " %); peak " << de.peak
                        << " m against " << shells.peak << " m (" << 100.0 * (de.peak / shells.peak - 1.0) << " %)");
  }
}

TEST_CASE("fictive elements: spheres round a circular hole are placed where they are, quadrilaterals and triangles",
          "[bridge][ring][gmsh]")
{
  // The band's spheres located in Gmsh's shells round a cylinder core: the
  // shells' interpolation of their own node coordinates at each sphere's
  // element and reference coordinates must give the sphere's position
  // (round-off). Newton's inversion of a quadrilateral's bilinear map may
  // stop anywhere for a point outside the element, also inside the
  // reference square: such a point, placed in an element far from it and
  // tied there, would stiffen the slab (bridge/fictive.cpp, invert).
  for (auto cell : {shell::Cell::quadrilateral, shell::Cell::triangle})
  {
    const bridge::SlabSpec spec = cylinder_slab(cell);
    const dem::Region region = bridge::slab_de_region(spec);
    auto b = make_ring(bridge::slab_shells(MPI_COMM_WORLD, spec), bridge::slab_overlap(spec), region);
    bridge::ShellGeometry g{b.fe->node_coordinates(), b.fe->nodal_normals(), b.fe->cell_nodes(), b.fe->nodes_per_cell(),
                            thick};
    std::vector<double> pts;
    for (std::size_t i = 0; i < b.p.size(); ++i)
      if (b.overlap.weight({b.p.x[3 * i], b.p.x[3 * i + 1], b.p.x[3 * i + 2]}) > 0.0)
        pts.insert(pts.end(), {b.p.x[3 * i], b.p.x[3 * i + 1], b.p.x[3 * i + 2]});
    const auto op = bridge::locate(g, pts);
    std::vector<double> u(6 * b.fe->num_nodes(), 0.0), v(pts.size());
    const auto x = b.fe->node_coordinates();
    for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
      for (int c = 0; c < 3; ++c)
        u[6 * k + c] = x[3 * k + c];
    op.interpolate(u, v);
    double worst = 0.0;
    std::size_t bad = 0;
    for (std::size_t i = 0; 3 * i < pts.size(); ++i)
    {
      const double d = std::hypot(v[3 * i] - pts[3 * i], v[3 * i + 1] - pts[3 * i + 1]);
      worst = std::max(worst, d);
      bad += d > 1e-4;
    }
    INFO("cell " << shell::to_string(cell) << ": worst in-plane mismatch " << worst << " m, " << bad
                  << " spheres off by > 0.1 mm; placed by the nearest rule " << op.outside() << ", in several "
                  << op.ambiguous());
    CHECK(worst < 1e-12);
    CHECK(op.ambiguous() == 0);
  }
}
