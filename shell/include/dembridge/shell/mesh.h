#pragma once
/// @file mesh.h
/// Shell mid-surface meshes (geometric dimension 3, topological 2) and solid
/// meshes, placed anywhere in space, and meshes read from XDMF files.

#include <array>
#include <filesystem>
#include <memory>
#include <mpi.h>
#include <string>

namespace dolfinx::mesh
{
class Mesh;
}

namespace dembridge::shell
{

/// Rigid placement x_global = origin + R x_local (R row-major 3 x 3, a rotation).
struct Placement
{
  std::array<double, 3> origin{0.0, 0.0, 0.0};
  std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::array<double, 3> apply(const std::array<double, 3>& x) const;
  /// Rotation by `angle` [rad] about the unit `axis` through the origin,
  /// followed by a translation `shift` [m].
  static Placement rotation_about(std::array<double, 3> axis, double angle,
                                  std::array<double, 3> shift = {0, 0, 0});
};

/// Cell types of the shell and solid meshes.
enum class Cell
{
  triangle,
  quadrilateral,
  tetrahedron,
  hexahedron
};

/// Parses "triangle", "quadrilateral", "tetrahedron", "hexahedron".
Cell parse_cell(const std::string& name);
std::string to_string(Cell c);

/// Structured rectangle [0, lx] x [0, ly] of the local (x, y) plane, z = 0,
/// with nx x ny quadrilaterals (or 2 nx ny triangles, diagonals alternating),
/// placed by `p`. A strip is a rectangle with few divisions across.
std::shared_ptr<dolfinx::mesh::Mesh>
create_shell_rectangle(MPI_Comm comm, double lx, double ly, int nx, int ny,
                       Cell cell, const Placement& p = {});

/// A rectangular hole [lo, hi] of a structured rectangle, in its local
/// (x, y) coordinates [m]; its edges lie on the grid's lines.
struct RectangularHole
{
  std::array<double, 2> lo{0.0, 0.0};
  std::array<double, 2> hi{0.0, 0.0};
};

/// The structured rectangle of create_shell_rectangle without the cells
/// inside `hole` (a slab's shells round a DE core); the vertices of no cell
/// are left out. @throws std::runtime_error naming a hole edge off the grid's
/// lines or outside [0, l], or a hole whose corners are not ordered.
std::shared_ptr<dolfinx::mesh::Mesh>
create_shell_rectangle_with_hole(MPI_Comm comm, double lx, double ly, int nx, int ny, const RectangularHole& hole,
                                 Cell cell, const Placement& p = {});

/// Structured box [0, lx] x [0, ly] x [0, lz] of hexahedra (or tetrahedra),
/// placed by `p`.
std::shared_ptr<dolfinx::mesh::Mesh>
create_solid_box(MPI_Comm comm, std::array<double, 3> l, std::array<int, 3> n,
                 Cell cell, const Placement& p = {});

/// Reads a mesh (linear triangles or quadrilaterals in 3D for shells;
/// tetrahedra or hexahedra for solids) from an XDMF file written by DOLFINx or
/// meshio, grid name `name`.
/// @throws std::runtime_error with the path if the file cannot be read.
std::shared_ptr<dolfinx::mesh::Mesh> read_mesh(MPI_Comm comm,
                                               const std::filesystem::path& file,
                                               const std::string& name = "mesh");

/// Writes a mesh to XDMF (grid name "mesh"), e.g. to give users a template.
void write_mesh(const dolfinx::mesh::Mesh& mesh, const std::filesystem::path& file);

} // namespace dembridge::shell
