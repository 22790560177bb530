#pragma once
/// @file gmsh.h
/// Shell meshes through Gmsh's C++ API (Debian's libgmsh-dev): a slab's
/// outline with a hole for a DE core, and .msh files. In the library
/// dembridge::shell_gmsh (link it to use these; the other programs do not
/// load Gmsh and its dependencies at start-up).

#include "dembridge/shell/mesh.h"

#include <array>
#include <filesystem>
#include <memory>
#include <mpi.h>

namespace dembridge::shell
{

/// A slab's outline for Gmsh: the rectangle [0, lx] x [0, ly] of the local
/// (x, y) plane, with a hole for the DE core or none.
struct SlabOutline
{
  enum class Hole
  {
    none,
    rectangle, ///< |x - centre| <= half on both axes
    circle     ///< |x - centre| <= radius
  };
  double lx = 0.0, ly = 0.0; ///< [m]
  Hole hole = Hole::none;
  /// the hole's centre; without a hole a node is placed there, where the
  /// elements are `size` [m]
  std::array<double, 2> centre{0.0, 0.0};
  std::array<double, 2> half{0.0, 0.0};   ///< a rectangular hole's half sizes [m]
  double radius = 0.0;                    ///< a circular hole's radius [m]
  double size = 0.0;                      ///< the elements' target size [m] (at the hole)
  /// at the outer rectangle's corners [m], the size graded from `size` at
  /// the hole (Gmsh interpolates the points' sizes); 0 = `size` everywhere
  double outer_size = 0.0;
  /// @throws std::runtime_error naming the value: lengths or size not > 0, a
  ///   size above the rectangle's shorter side, an outer size below 0 or
  ///   above the shorter side, a hole not strictly inside.
  void validate() const;
};

/// The outline meshed by Gmsh (its C++ API): triangles, or quadrilaterals
/// (recombined; every cell a quadrilateral), of about `size`, z = 0, placed
/// by `p`. @throws std::runtime_error on a bad outline or a Gmsh failure.
std::shared_ptr<dolfinx::mesh::Mesh> mesh_outline(MPI_Comm comm, const SlabOutline& o, Cell cell,
                                                  const Placement& p = {});

/// A shell mesh from a Gmsh .msh file: its linear triangles or its linear
/// quadrilaterals (one kind; points, lines and other cells are ignored).
/// @throws std::runtime_error naming the file if it cannot be read, holds
///   no surface cell or holds both kinds.
std::shared_ptr<dolfinx::mesh::Mesh> read_gmsh(MPI_Comm comm, const std::filesystem::path& file);

} // namespace dembridge::shell
