#pragma once
/// @file model.h
/// Finite-element model on DOLFINx: a Reissner-Mindlin shell (6 dofs per node:
/// 3 translations, 3 rotations, global frame) or a linear-elastic solid
/// (3 dofs per node), with lumped mass, internal forces and the critical time
/// step. The physics is in the UFL files shell/forms/shell.py and solid.py.
///
/// Dof layout: dof = node * block_size + component, nodes numbered as the
/// DOLFINx P1 dofmap. Serial (one MPI rank).

#include "dembridge/shell/explicit.h"

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

typedef struct _p_Mat* Mat; // PETSc matrix handle

namespace dolfinx::mesh
{
class Mesh;
}
namespace dolfinx::fem
{
class FunctionSpace;
}

namespace dembridge::shell
{

/// Material and section of the FE model (SI units).
struct Material
{
  double youngs_modulus = 30e9;     ///< E [Pa]
  double poisson_ratio = 0.2;       ///< nu [-], in (-1, 0.5)
  double density = 2400.0;          ///< rho [kg/m^3]
  double thickness = 0.25;          ///< h [m] (shells)
  double shear_factor = 5.0 / 6.0;  ///< k [-] (shells)
  double drilling = 1.0;            ///< drilling penalty as a fraction of G h [-] (shells; Hughes-Brezzi: 1)
};

/// Throws std::runtime_error naming the value and the allowed range.
void validate(const Material& m, bool shell);

/// One layer of bars of a reinforced-concrete shell section, smeared over the
/// width (the bars' area per unit width is pi d^2 / (4 s)).
struct BarLayer
{
  int direction = 0;     ///< 0: the bars run along d1, 1: along d2 = n x d1
  double diameter = 0.0; ///< bar diameter d [m], > 0
  double spacing = 0.0;  ///< centre-to-centre spacing s [m], > d (bars apart)
  double z = 0.0;        ///< height of the bars' axes above the mid-surface, along the cell normal [m]
};

/// The steel of a reinforced-concrete shell section: bars elastic, uniaxial
/// along their direction, taking the place of concrete (transformed section,
/// E_s - E). The section's membrane, coupling and bending stiffnesses along a
/// bar direction gain (E_s - E) (A, S, I), the sums of a, a z and a z^2 over
/// the layers of that direction (shell/forms/shell.py).
struct Reinforcement
{
  double youngs_modulus = 200e9;                  ///< E_s [Pa], > 0
  double density = 7850.0;                        ///< rho_s [kg/m^3], > 0
  std::array<double, 3> direction{1.0, 0.0, 0.0}; ///< global vector; d1 is its projection on each cell
  std::vector<BarLayer> layers;
};

/// The sums (A, S, I) = sum of (a, a z, a z^2) over the layers of each
/// direction [m^2/m, m^3/m, m^4/m]: index 0 for d1, 1 for d2.
std::array<std::array<double, 3>, 2> section_sums(const Reinforcement& r);

/// Throws std::runtime_error naming the layer, the value and what is allowed:
/// E_s, rho_s <= 0, a zero direction, a direction index other than 0 or 1, a
/// diameter <= 0, a spacing <= the diameter (bars overlapping), a layer whose
/// bars reach outside the thickness h (|z| + d/2 > h/2).
void validate(const Reinforcement& r, double thickness);

/// How internal forces are computed.
enum class ForceMethod
{
  matmult,  ///< stiffness assembled once (PETSc BAIJ), f = K u (linear forms)
  residual  ///< residual form assembled at every call (non-linear forms)
};
ForceMethod parse_force_method(const std::string& s);

/// f = f_int(u) behind one interface.
class InternalForce
{
public:
  virtual ~InternalForce() = default;
  /// @param u dofs (num_dofs), @param f output (num_dofs) [N, N m]
  virtual void apply(std::span<const double> u, std::span<double> f) = 0;
  /// Called when the energy weight changes.
  virtual void update() = 0;
};

class FEModel
{
public:
  /// Builds the spaces and forms. The mesh's cells decide: triangles and
  /// quadrilaterals in 3D give a shell, tetrahedra and hexahedra a solid.
  /// @throws std::runtime_error on bad material values or a mesh of the wrong
  ///   geometric dimension (a shell needs gdim 3).
  FEModel(std::shared_ptr<dolfinx::mesh::Mesh> mesh, const Material& material,
          ForceMethod method = ForceMethod::matmult);
  ~FEModel();
  FEModel(FEModel&&) noexcept;
  FEModel& operator=(FEModel&&) noexcept;

  bool is_shell() const;
  /// 6 for shells, 3 for solids.
  int block_size() const;
  std::size_t num_nodes() const;
  std::size_t num_dofs() const;
  const Material& material() const;

  /// Node coordinates, shape (num_nodes, 3), row-major [m].
  std::span<const double> node_coordinates() const;
  /// Cell-to-node lists, shape (num_cells, nodes_per_cell), in the reference
  /// cell's vertex order (quadrilaterals and hexahedra in tensor order).
  std::span<const std::int32_t> cell_nodes() const;
  int nodes_per_cell() const;
  std::size_t num_cells() const;

  /// Shells: average unit normals at the nodes (mean of the adjacent cells'
  /// unit normals, normalised), shape (num_nodes, 3). Throws for solids.
  std::span<const double> nodal_normals() const;
  /// Shells: the section's stresses at the dofs u, averaged over each cell,
  /// shape (cells, 36): [0:9] the concrete's stress at the face on the side
  /// of the normal, [9:18] at the other face [Pa] (plane stress, linear
  /// elastic, the bars' share left out), [18:27] the membrane forces [N/m],
  /// [27:36] the bending moments [N m/m]; each a 3 x 3 tensor in the global
  /// frame, row-major (shell/forms/shell.py). Throws for solids.
  std::vector<double> section_stresses(std::span<const double> u) const;
  /// Shells: tributary mid-surface area per node [m^2] (row sums of the area
  /// mass); solids: tributary volume [m^3].
  std::vector<double> nodal_measure() const;

  /// Lumped mass per dof [kg, kg m^2 for rotations: rho h^3/12 per area].
  std::vector<double> lumped_mass() const;

  /// Shells: gives the listed cells (every cell if none is listed) the
  /// reinforced section r, replacing what they had (an r without layers
  /// makes them plain again); reassembles the stiffness. The lumped mass
  /// (lumped_mass()) includes the bars' from then on.
  /// @throws std::runtime_error for solids, a bad r (validate), a cell out of
  ///   range, or a direction normal to one of the cells.
  void set_reinforcement(const Reinforcement& r, std::span<const std::int32_t> cells = {});

  /// Energy weight eta at the nodes (P1, in [0, 1]); default 1. Setting it
  /// updates the internal forces (reassembles K for `matmult`).
  void set_weight(std::span<const double> eta);
  std::span<const double> weight() const;

  /// Compression-only springs: a rigid support the shell rests on (a frame
  /// under a slab's edges). Spring q acts on dof dofs[q] with the force
  /// -k[q] min(u, 0): it resists the dof's moving below 0 and lets it move
  /// away freely. Its energy, k min(u, 0)^2 / 2, is u f / 2, so a strain
  /// energy taken as u . f_int / 2 stays exact. Replaces those set before.
  /// solve_static and lowest_mode leave them out (the sections alone).
  /// @throws std::runtime_error for sizes that differ, a dof out of range
  ///   or a stiffness not > 0.
  void set_support_springs(std::vector<std::int32_t> dofs, std::vector<double> k);
  std::span<const std::int32_t> support_spring_dofs() const;
  /// The springs' force on the shell at u, summed over them (> 0 pushes the
  /// dofs' positive way) [N].
  double support_spring_force(std::span<const double> u) const;

  /// f = f_int(u) [N, N m]: the sections' forces and the support springs'.
  void internal_force(std::span<const double> u, std::span<double> f) const;
  InternalForceFn internal_force_fn() const;
  /// The linear force whose largest eigenvalue bounds the step: as
  /// internal_force_fn(), the support springs two-sided.
  InternalForceFn bounding_force_fn() const;

  /// Critical time step 2 / sqrt(lambda_max(M^-1 K)) for the given lumped
  /// mass (power iteration; support springs counted two-sided) [s].
  double critical_time_step(std::span<const double> mass) const;

  /// Tributary weights of the given boundary nodes for a load spread
  /// uniformly over the boundary facets (edges of shells, faces of solids)
  /// whose vertices are all selected; the weights sum to 1.
  /// @throws std::runtime_error if the nodes span no boundary facet.
  std::vector<double> boundary_load_weights(std::span<const std::int32_t> nodes) const;

  /// The nodes on the mesh's boundary: those of its exterior facets (edges
  /// of shells, faces of solids; the outline and any hole's edge), sorted.
  std::vector<std::int32_t> boundary_nodes() const;

  /// Shells: a pressure p(t) [Pa] on the given nodes as a nodal load,
  /// f_i = p(t) A_i n_i with A_i the tributary area and n_i the average
  /// normal (positive p pushes along +n). @throws for solids or no node.
  NodalLoad pressure_load(const std::string& name, std::span<const std::int32_t> nodes,
                          History p) const;

  /// Direct solve K u = f with the listed dofs fixed (PETSc LU) [m, rad].
  std::vector<double> solve_static(std::span<const double> f,
                                   std::span<const std::int32_t> fixed_dofs) const;

  /// Lowest eigenpair of K x = lambda M x (fixed dofs held) by `iterations`
  /// steps of inverse iteration from x0 (one LU factorisation). Returns the
  /// M-normalised vector and its Rayleigh quotient lambda [1/s^2].
  std::pair<std::vector<double>, double>
  lowest_mode(std::span<const double> mass, std::span<const std::int32_t> fixed_dofs,
              std::span<const double> x0, int iterations = 4) const;

  /// The assembled stiffness (PETSc BAIJ) of the `matmult` method, owned by
  /// the model; nullptr for `residual`.
  Mat stiffness_matrix() const;

  std::shared_ptr<const dolfinx::fem::FunctionSpace> function_space() const;
  std::shared_ptr<dolfinx::mesh::Mesh> mesh() const;

private:
  /// The nodes of each exterior facet, in the facet's closure order.
  std::vector<std::vector<std::int32_t>> boundary_facets() const;
  struct Impl;
  std::unique_ptr<Impl> _impl;
};

} // namespace dembridge::shell
