#pragma once
/// @file fictive.h
/// Fictive 3D elements around a shell mid-surface (the paper's equations [5]
/// and [6], docs/method.md sections 3.3-3.5), the location of particles in them, and the
/// interpolation operator G_FE that gives a particle's velocity from the
/// shell's nodal translations and rotations.
///
/// Each shell node has two fictive nodes x +- (h/2) n_bar (n_bar the average
/// nodal normal). A triangle and its fictive nodes make a 6-node wedge, a
/// quadrilateral an 8-node hexahedron. A particle at reference coordinates
/// (xi, eta, zeta) of a fictive element moves with
///   v_i = sum_J [ (N_J^- + N_J^+) v_J + (h/2) (N_J^+ - N_J^-) (omega_J x n_J) ],
/// N_J^-/N_J^+ the shape functions of the bottom/top fictive node of shell
/// node J (fictive-node kinematics u_f = u + z theta x n_bar).
///
/// Points in no fictive element, or in several (the paper's Figure 6), follow
/// a documented rule: in several, the element in which the point lies deepest
/// (largest smallest margin of its reference coordinates) wins; in none, the
/// element whose (clamped) nearest point is closest wins, and the point then
/// follows that nearest point. Both cases are counted. A point farther than
/// `max_distance` from every element is an error.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace dembridge::bridge
{

/// The shell side as plain arrays (from shell::FEModel).
struct ShellGeometry
{
  std::span<const double> x;              ///< node coordinates (nodes, 3) [m]
  std::span<const double> normals;        ///< average unit normals (nodes, 3)
  std::span<const std::int32_t> cells;    ///< (cells, npc): triangles, or quads in tensor order
  int nodes_per_cell = 4;                 ///< 3 or 4
  double thickness = 0.0;                 ///< h [m]
};

/// Fictive node coordinates (2 per shell node: 2k at -h/2, 2k+1 at +h/2),
/// shape (2 nodes, 3).
std::vector<double> fictive_nodes(const ShellGeometry& g);

struct LocateOptions
{
  double tolerance = 1e-9;     ///< on reference coordinates, to count a point as inside
  double max_distance = -1.0;  ///< [m]; < 0: the thickness h
};

/// G_FE for a set of particles: for particle p (row), the shell cell it lies
/// in and, for each of the cell's npc nodes, the weights a (on translations)
/// and b (on omega x n_bar).
class CouplingOperator
{
public:
  std::size_t size() const { return _cell.size(); }
  int nodes_per_cell() const { return _npc; }
  /// Dofs per FE node: 6 for shells (translations, rotations), 3 for solids.
  int block_size() const { return _bs; }
  std::span<const std::int32_t> cells() const { return _cell; }
  /// Reference coordinates of each point in its element, (points, 3).
  std::span<const double> reference() const { return _ref; }
  /// Shell nodes, weights a and b, and node normals of each point's row,
  /// (points, npc) and (points, npc, 3).
  std::span<const std::int32_t> nodes() const { return _nodes; }
  std::span<const double> a() const { return _a; }
  std::span<const double> b() const { return _b; }
  std::span<const double> normals() const { return _n; }
  std::size_t outside() const { return _outside; }   ///< placed by the nearest rule
  std::size_t ambiguous() const { return _ambiguous; } ///< inside several elements

  /// v (points, 3) = G_FE u, with u the FE dofs (nodes, block_size): for
  /// shells translations then rotations (or their rates), global frame.
  void interpolate(std::span<const double> u, std::span<double> v) const;
  /// f_fe (nodes, block_size) += G_FE^T f (points, 3): forces (and moments)
  /// on the FE nodes equivalent to the point forces f.
  void add_transpose(std::span<const double> f, std::span<double> f_shell) const;

private:
  friend CouplingOperator locate(const ShellGeometry&, std::span<const double>,
                                 const LocateOptions&);
  friend CouplingOperator locate_in_solid(std::span<const double>, std::span<const std::int32_t>,
                                          int, std::span<const double>, const LocateOptions&);
  int _npc = 4, _bs = 6;
  std::vector<std::int32_t> _cell, _nodes; // nodes: (points, npc)
  std::vector<double> _a, _b;              // (points, npc)
  std::vector<double> _n;                  // normals of the nodes, (points, npc, 3)
  std::vector<double> _ref;
  std::size_t _outside = 0, _ambiguous = 0;
};

/// Locates the points (points, 3) [m] in the fictive elements of the shell.
/// @throws std::runtime_error if a point is farther than max_distance from
///   every fictive element (the message gives the point and the distance),
///   or on bad geometry (thickness <= 0, npc not 3 or 4).
CouplingOperator locate(const ShellGeometry& g, std::span<const double> points,
                        const LocateOptions& opt = {});

/// Locates the points in the cells of a 3D solid mesh (P1 tetrahedra, 4
/// nodes, or hexahedra, 8 nodes in tensor order) and builds G_FE for 3 dofs
/// per node (v_i = sum_J N_J(x_i) v_J). Same rules as `locate` for points in
/// several cells or in none (max_distance < 0: the largest cell size / 10).
/// @param x node coordinates (nodes, 3); @param cells (cells, npc)
CouplingOperator locate_in_solid(std::span<const double> x, std::span<const std::int32_t> cells,
                                 int nodes_per_cell, std::span<const double> points,
                                 const LocateOptions& opt = {});

} // namespace dembridge::bridge
