#include "dembridge/shell/mesh.h"
#include "mesh_internal.h"

#include <cmath>
#include <dolfinx/fem/CoordinateElement.h>
#include <dolfinx/graph/AdjacencyList.h>
#include <dolfinx/io/XDMFFile.h>
#include <dolfinx/mesh/Mesh.h>
#include <dolfinx/mesh/generation.h>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace dembridge::shell
{

std::array<double, 3> Placement::apply(const std::array<double, 3>& x) const
{
  std::array<double, 3> y = origin;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      y[i] += rotation[3 * i + j] * x[j];
  return y;
}

Placement Placement::rotation_about(std::array<double, 3> a, double angle,
                                    std::array<double, 3> shift)
{
  const double n = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  if (!(n > 0.0))
    throw std::runtime_error("rotation axis must be a non-zero vector");
  for (auto& c : a)
    c /= n;
  const double c = std::cos(angle), s = std::sin(angle), t = 1.0 - c;
  Placement p;
  p.origin = shift;
  p.rotation = {t * a[0] * a[0] + c,        t * a[0] * a[1] - s * a[2],
                t * a[0] * a[2] + s * a[1], t * a[0] * a[1] + s * a[2],
                t * a[1] * a[1] + c,        t * a[1] * a[2] - s * a[0],
                t * a[0] * a[2] - s * a[1], t * a[1] * a[2] + s * a[0],
                t * a[2] * a[2] + c};
  return p;
}

Cell parse_cell(const std::string& name)
{
  if (name == "triangle")
    return Cell::triangle;
  if (name == "quadrilateral" || name == "quad")
    return Cell::quadrilateral;
  if (name == "tetrahedron" || name == "tet")
    return Cell::tetrahedron;
  if (name == "hexahedron" || name == "hex")
    return Cell::hexahedron;
  throw std::runtime_error("cell type '" + name
                           + "': allowed are triangle, quadrilateral, tetrahedron, hexahedron");
}

std::string to_string(Cell c)
{
  switch (c)
  {
  case Cell::triangle:
    return "triangle";
  case Cell::quadrilateral:
    return "quadrilateral";
  case Cell::tetrahedron:
    return "tetrahedron";
  default:
    return "hexahedron";
  }
}

namespace
{
void check_divisions(std::initializer_list<int> n)
{
  for (int k : n)
    if (k < 1)
      throw std::runtime_error("mesh divisions " + std::to_string(k) + ": must be >= 1");
}
void check_lengths(std::initializer_list<double> l)
{
  for (double k : l)
    if (!(k > 0.0) || !std::isfinite(k))
      throw std::runtime_error("mesh length " + std::to_string(k) + " m: must be > 0");
}
} // namespace

std::shared_ptr<dolfinx::mesh::Mesh> impl::shell_mesh(MPI_Comm comm, std::vector<double> x,
                                                      std::vector<std::int64_t> cells, Cell cell)
{
  const int npc = cell == Cell::triangle ? 3 : 4;
  const auto ct = cell == Cell::triangle ? dolfinx::mesh::CellType::triangle : dolfinx::mesh::CellType::quadrilateral;
  auto adj = dolfinx::graph::regular_adjacency_list(std::move(cells), npc);
  const std::size_t nn = x.size() / 3;
  return std::make_shared<dolfinx::mesh::Mesh>(dolfinx::mesh::create_mesh(
      comm, adj, dolfinx::fem::CoordinateElement(ct, 1), x, {nn, 3},
      dolfinx::mesh::GhostMode::none));
}

namespace
{
/// The structured nx x ny grid of [0, lx] x [0, ly], its cells (i, j) kept
/// where keep(i, j), the vertices of no kept cell left out (the others in
/// their grid order), placed by p.
std::shared_ptr<dolfinx::mesh::Mesh> structured_shell(MPI_Comm comm, double lx, double ly, int nx, int ny, Cell cell,
                                                      const Placement& p,
                                                      const std::function<bool(int, int)>& keep)
{
  check_divisions({nx, ny});
  check_lengths({lx, ly});
  if (cell != Cell::triangle && cell != Cell::quadrilateral)
    throw std::runtime_error("a shell mesh needs triangles or quadrilaterals, not "
                             + to_string(cell));
  auto id = [nx](int i, int j) { return std::int64_t(j) * (nx + 1) + i; };
  std::vector<std::int64_t> cells;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
    {
      if (!keep(i, j))
        continue;
      const std::int64_t v00 = id(i, j), v10 = id(i + 1, j), v01 = id(i, j + 1),
                         v11 = id(i + 1, j + 1);
      if (cell == Cell::quadrilateral)
        cells.insert(cells.end(), {v00, v10, v01, v11});
      else if ((i + j) % 2 == 0)
        cells.insert(cells.end(), {v00, v10, v11, v00, v11, v01});
      else
        cells.insert(cells.end(), {v00, v10, v01, v10, v11, v01});
    }
  if (cells.empty())
    throw std::runtime_error("the shell mesh has no cell left (a hole covering the whole rectangle)");
  // the used vertices, numbered in their grid order
  std::vector<std::int64_t> number(std::size_t(nx + 1) * (ny + 1), -1);
  for (auto v : cells)
    number[v] = 0;
  std::vector<double> x;
  std::int64_t used = 0;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
    {
      if (number[id(i, j)] < 0)
        continue;
      number[id(i, j)] = used++;
      const auto y = p.apply({lx * i / nx, ly * j / ny, 0.0});
      x.insert(x.end(), y.begin(), y.end());
    }
  for (auto& v : cells)
    v = number[v];
  return impl::shell_mesh(comm, std::move(x), std::move(cells), cell);
}

/// The grid line of `value` on a grid of n divisions of [0, l].
/// @throws std::runtime_error naming the value unless it lies on one.
int grid_line(double value, double l, int n, const char* what)
{
  const double t = value / l * n;
  const double k = std::round(t);
  if (!(std::abs(t - k) <= 1e-9 * n) || k < 0 || k > n)
    throw std::runtime_error(std::string("hole ") + what + " " + std::to_string(value) + " m: must lie on a grid line, "
                             "a multiple of " + std::to_string(l / n) + " m in [0, " + std::to_string(l) + "] m");
  return static_cast<int>(k);
}
} // namespace

std::shared_ptr<dolfinx::mesh::Mesh>
create_shell_rectangle(MPI_Comm comm, double lx, double ly, int nx, int ny,
                       Cell cell, const Placement& p)
{
  return structured_shell(comm, lx, ly, nx, ny, cell, p, [](int, int) { return true; });
}

std::shared_ptr<dolfinx::mesh::Mesh> create_shell_rectangle_with_hole(MPI_Comm comm, double lx, double ly, int nx,
                                                                      int ny, const RectangularHole& hole, Cell cell,
                                                                      const Placement& p)
{
  check_divisions({nx, ny});
  check_lengths({lx, ly});
  const int i0 = grid_line(hole.lo[0], lx, nx, "x from"), i1 = grid_line(hole.hi[0], lx, nx, "x to");
  const int j0 = grid_line(hole.lo[1], ly, ny, "y from"), j1 = grid_line(hole.hi[1], ly, ny, "y to");
  if (!(i1 > i0 && j1 > j0))
    throw std::runtime_error("hole from (" + std::to_string(hole.lo[0]) + ", " + std::to_string(hole.lo[1]) + ") to ("
                             + std::to_string(hole.hi[0]) + ", " + std::to_string(hole.hi[1])
                             + ") m: its upper corner must exceed the lower on both axes");
  return structured_shell(comm, lx, ly, nx, ny, cell, p,
                          [=](int i, int j) { return !(i >= i0 && i < i1 && j >= j0 && j < j1); });
}

std::shared_ptr<dolfinx::mesh::Mesh>
create_solid_box(MPI_Comm comm, std::array<double, 3> l, std::array<int, 3> n,
                 Cell cell, const Placement& p)
{
  check_divisions({n[0], n[1], n[2]});
  check_lengths({l[0], l[1], l[2]});
  dolfinx::mesh::CellType ct;
  if (cell == Cell::hexahedron)
    ct = dolfinx::mesh::CellType::hexahedron;
  else if (cell == Cell::tetrahedron)
    ct = dolfinx::mesh::CellType::tetrahedron;
  else
    throw std::runtime_error("a solid mesh needs tetrahedra or hexahedra, not "
                             + to_string(cell));
  auto mesh = std::make_shared<dolfinx::mesh::Mesh>(dolfinx::mesh::create_box(
      comm, {{{0.0, 0.0, 0.0}, {l[0], l[1], l[2]}}},
      {std::size_t(n[0]), std::size_t(n[1]), std::size_t(n[2])}, ct,
      dolfinx::mesh::GhostMode::none));
  auto x = mesh->geometry().x();
  for (std::size_t i = 0; i < x.size() / 3; ++i)
  {
    const auto y = p.apply({x[3 * i], x[3 * i + 1], x[3 * i + 2]});
    std::copy(y.begin(), y.end(), x.begin() + 3 * i);
  }
  return mesh;
}

std::shared_ptr<dolfinx::mesh::Mesh> read_mesh(MPI_Comm comm,
                                               const std::filesystem::path& file,
                                               const std::string& name)
{
  if (!std::filesystem::is_regular_file(file))
    throw std::runtime_error("mesh file '" + file.string()
                             + "' does not exist or is not a file");
  try
  {
    dolfinx::io::XDMFFile f(comm, file, "r");
    const auto [ct, degree] = f.read_cell_type(name);
    if (degree != 1)
      throw std::runtime_error("cells of degree " + std::to_string(degree)
                               + "; only linear (degree 1) cells are supported");
    dolfinx::fem::CoordinateElement cmap(ct, degree);
    return std::make_shared<dolfinx::mesh::Mesh>(
        f.read_mesh(cmap, dolfinx::mesh::GhostMode::none, name));
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("cannot read mesh '" + name + "' from '" + file.string()
                             + "': " + e.what());
  }
}

void write_mesh(const dolfinx::mesh::Mesh& mesh, const std::filesystem::path& file)
{
  dolfinx::io::XDMFFile f(mesh.comm(), file, "w");
  f.write_mesh(mesh);
}

} // namespace dembridge::shell
