// Shell meshes through Gmsh's C++ API: a slab's outline with a hole for the
// DE core, meshed into triangles or quadrilaterals, and .msh files.
#include "dembridge/shell/gmsh.h"
#include "mesh_internal.h"

#include "dembridge/core/text.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <gmsh.h>
#include <omp.h>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace dembridge::shell
{
namespace
{
using core::number_text;

/// OpenMP's thread count as found, put back when this goes.
struct ThreadCount
{
  int n = omp_get_max_threads();
  ~ThreadCount() { omp_set_num_threads(n); }
};

/// Gmsh's global state for one use: initialised quietly, finalised on exit
/// (exceptions included). Gmsh sets the process's OpenMP thread count to its
/// own option General.NumThreads (1) when it starts and when it meshes; the
/// session puts back the count it found (its member goes after finalize(),
/// or alone if the constructor throws), or every parallel loop run after the
/// mesh (the spheres' step of a coupled slab) would run on one thread.
struct GmshSession
{
  GmshSession()
  {
    gmsh::initialize(0, nullptr, false);
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::model::add("dembridge");
  }
  ~GmshSession() { gmsh::finalize(); }
  ThreadCount threads;
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;
};

/// The current model's linear triangles (Gmsh type 2) or quadrilaterals
/// (type 3) as a shell mesh placed by p; `what` names the source in errors.
std::shared_ptr<dolfinx::mesh::Mesh> from_model(MPI_Comm comm, const Placement& p, const std::string& what)
{
  std::vector<std::size_t> tags, nodes_tri, nodes_quad, unused;
  gmsh::model::mesh::getElementsByType(2, unused, nodes_tri);
  gmsh::model::mesh::getElementsByType(3, unused, nodes_quad);
  if (nodes_tri.empty() == nodes_quad.empty())
    throw std::runtime_error(what + ": " + (nodes_tri.empty() ? "no triangle or quadrilateral"
                                                              : "both triangles (" + std::to_string(nodes_tri.size() / 3)
                                                                    + ") and quadrilaterals ("
                                                                    + std::to_string(nodes_quad.size() / 4)
                                                                    + "); a shell mesh holds one kind"));
  const bool quads = !nodes_quad.empty();
  const auto& conn = quads ? nodes_quad : nodes_tri;
  std::vector<double> coord, param;
  gmsh::model::mesh::getNodes(tags, coord, param, -1, -1, false, false);
  std::unordered_map<std::size_t, std::size_t> at; // a node tag's position in tags
  for (std::size_t k = 0; k < tags.size(); ++k)
    at[tags[k]] = k;
  // the used nodes, numbered in the order of their tags
  std::vector<std::size_t> used(conn.begin(), conn.end());
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  std::unordered_map<std::size_t, std::int64_t> number;
  std::vector<double> x;
  for (auto t : used)
  {
    number[t] = static_cast<std::int64_t>(number.size());
    const std::size_t k = at.at(t);
    const auto y = p.apply({coord[3 * k], coord[3 * k + 1], coord[3 * k + 2]});
    x.insert(x.end(), y.begin(), y.end());
  }
  std::vector<std::int64_t> cells;
  cells.reserve(conn.size());
  const std::size_t npc = quads ? 4 : 3;
  for (std::size_t c = 0; c < conn.size(); c += npc)
  {
    if (quads) // Gmsh's quadrilaterals run round; DOLFINx's are tensor-product ordered
      cells.insert(cells.end(), {number[conn[c]], number[conn[c + 1]], number[conn[c + 3]], number[conn[c + 2]]});
    else
      cells.insert(cells.end(), {number[conn[c]], number[conn[c + 1]], number[conn[c + 2]]});
  }
  return impl::shell_mesh(comm, std::move(x), std::move(cells), quads ? Cell::quadrilateral : Cell::triangle);
}

/// A closed loop of straight lines through the points (x, y), z = 0.
int polygon(const std::vector<std::array<double, 2>>& xy, double size)
{
  std::vector<int> pts, lines;
  for (const auto& q : xy)
    pts.push_back(gmsh::model::geo::addPoint(q[0], q[1], 0.0, size));
  for (std::size_t k = 0; k < pts.size(); ++k)
    lines.push_back(gmsh::model::geo::addLine(pts[k], pts[(k + 1) % pts.size()]));
  return gmsh::model::geo::addCurveLoop(lines);
}

/// A circle of four quarter arcs.
int circle(const std::array<double, 2>& c, double r, double size)
{
  const int centre = gmsh::model::geo::addPoint(c[0], c[1], 0.0, size);
  std::vector<int> pts, arcs;
  for (int k = 0; k < 4; ++k)
  {
    const double a = 0.5 * M_PI * k;
    pts.push_back(gmsh::model::geo::addPoint(c[0] + r * std::cos(a), c[1] + r * std::sin(a), 0.0, size));
  }
  for (int k = 0; k < 4; ++k)
    arcs.push_back(gmsh::model::geo::addCircleArc(pts[k], centre, pts[(k + 1) % 4]));
  return gmsh::model::geo::addCurveLoop(arcs);
}
} // namespace

void SlabOutline::validate() const
{
  for (auto [name, v] : {std::pair{"slab length lx", lx}, {"slab width ly", ly}, {"element size", size}})
    if (!(v > 0.0) || !std::isfinite(v))
      throw std::runtime_error(std::string(name) + " " + number_text(v) + " m: must be > 0");
  for (auto [name, v] : {std::pair{"element size", size}, {"outer element size", outer_size}})
    if (v > std::min(lx, ly))
      throw std::runtime_error(std::string(name) + " " + number_text(v) + " m: must not exceed the slab's shorter side, "
                               + number_text(std::min(lx, ly)) + " m");
  if (!(outer_size >= 0.0))
    throw std::runtime_error("outer element size " + number_text(outer_size) + " m: must be >= 0 (0: the element size)");
  std::array<double, 2> reach{0.0, 0.0};
  if (hole == Hole::rectangle)
  {
    if (!(half[0] > 0.0 && half[1] > 0.0))
      throw std::runtime_error("hole half sizes " + number_text(half[0]) + " x " + number_text(half[1]) + " m: both must be > 0");
    reach = half;
  }
  else if (hole == Hole::circle)
  {
    if (!(radius > 0.0) || !std::isfinite(radius))
      throw std::runtime_error("hole radius " + number_text(radius) + " m: must be > 0");
    reach = {radius, radius};
  }
  if (hole == Hole::none && !(centre[0] > 0.0 && centre[0] < lx && centre[1] > 0.0 && centre[1] < ly))
    throw std::runtime_error("the centre (" + number_text(centre[0]) + ", " + number_text(centre[1]) + ") m must lie "
                             "strictly inside the slab [0, " + number_text(lx) + "] x [0, " + number_text(ly) + "] m");
  if (hole != Hole::none
      && !(centre[0] - reach[0] > 0.0 && centre[0] + reach[0] < lx && centre[1] - reach[1] > 0.0
           && centre[1] + reach[1] < ly))
    throw std::runtime_error("the hole about (" + number_text(centre[0]) + ", " + number_text(centre[1]) + ") m, reaching "
                             + number_text(reach[0]) + " x " + number_text(reach[1]) + " m, must lie strictly inside the slab [0, "
                             + number_text(lx) + "] x [0, " + number_text(ly) + "] m");
}

std::shared_ptr<dolfinx::mesh::Mesh> mesh_outline(MPI_Comm comm, const SlabOutline& o, Cell cell, const Placement& p)
{
  o.validate();
  if (cell != Cell::triangle && cell != Cell::quadrilateral)
    throw std::runtime_error("a shell mesh needs triangles or quadrilaterals, not " + to_string(cell));
  GmshSession session;
  const double outer = o.outer_size > 0.0 ? o.outer_size : o.size;
  std::vector<int> loops{polygon({{0.0, 0.0}, {o.lx, 0.0}, {o.lx, o.ly}, {0.0, o.ly}}, outer)};
  if (o.hole == SlabOutline::Hole::rectangle)
  {
    const auto c = o.centre, h = o.half;
    loops.push_back(polygon(
        {{c[0] - h[0], c[1] - h[1]}, {c[0] + h[0], c[1] - h[1]}, {c[0] + h[0], c[1] + h[1]}, {c[0] - h[0], c[1] + h[1]}},
        o.size));
  }
  else if (o.hole == SlabOutline::Hole::circle)
    loops.push_back(circle(o.centre, o.radius, o.size));
  const int surface = gmsh::model::geo::addPlaneSurface(loops);
  // no hole: a node at the centre, where the elements are `size` (graded to
  // the corners' from there)
  const int centre = o.hole == SlabOutline::Hole::none ? gmsh::model::geo::addPoint(o.centre[0], o.centre[1], 0.0, o.size) : -1;
  gmsh::model::geo::synchronize();
  if (centre >= 0)
    gmsh::model::mesh::embed(0, {centre}, 2, surface);
  gmsh::option::setNumber("Mesh.MeshSizeMax", std::max(o.size, outer));
  if (cell == Cell::quadrilateral)
  {
    gmsh::option::setNumber("Mesh.Algorithm", 6); // frontal-Delaunay (8, its quadrilateral variant, crashes in Gmsh 4.8)
    gmsh::option::setNumber("Mesh.RecombinationAlgorithm", 3); // blossom, full-quad
    gmsh::option::setNumber("Mesh.RecombineAll", 1);
  }
  try
  {
    gmsh::model::mesh::generate(2);
  }
  catch (...)
  {
    throw std::runtime_error("Gmsh could not mesh the slab's outline (" + number_text(o.lx) + " x " + number_text(o.ly)
                             + " m, element size " + number_text(o.size) + " m)");
  }
  return from_model(comm, p, "the Gmsh mesh of the slab's outline");
}

std::shared_ptr<dolfinx::mesh::Mesh> read_gmsh(MPI_Comm comm, const std::filesystem::path& file)
{
  if (!std::filesystem::is_regular_file(file))
    throw std::runtime_error("Gmsh mesh " + file.string() + ": no such file");
  GmshSession session;
  try
  {
    gmsh::open(file.string());
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("Gmsh mesh " + file.string() + ": cannot be read (" + e.what() + ")");
  }
  catch (...)
  {
    throw std::runtime_error("Gmsh mesh " + file.string() + ": cannot be read");
  }
  return from_model(comm, {}, "Gmsh mesh " + file.string());
}

} // namespace dembridge::shell
