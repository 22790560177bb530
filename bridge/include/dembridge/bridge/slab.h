#pragma once
/// @file slab.h
/// The parts of a coupled slab: a DE core (a box or a cylinder through the
/// thickness) where the projectile strikes, the overlap band round it, and
/// the shells of the rest of the slab with a hole for the core, supported
/// on their outer edges. In the impact program's frame: x, y in
/// [-size / 2, size / 2], z in [-thickness, 0] (the struck face z = 0), the
/// shells' mid-surface at z = -thickness / 2. In the library dembridge::slab
/// (it meshes with Gmsh: shell/gmsh.h).

#include "dembridge/bridge/weight.h"
#include "dembridge/dem/packing.h"
#include "dembridge/shell/gmsh.h"
#include "dembridge/shell/model.h"

#include <array>
#include <cstdint>
#include <memory>
#include <mpi.h>
#include <vector>

namespace dembridge::bridge
{

struct SlabSpec
{
  enum class Core
  {
    box,     ///< |x - centre| <= core_half on both axes
    cylinder ///< |x - centre| <= core_radius
  };
  enum class Edges
  {
    free,
    simply_supported, ///< the edge nodes' translations held
    clamped,          ///< the edge nodes' translations and rotations held
    frame             ///< resting on a rigid frame under the rear face (slab_frame_springs)
  };
  std::array<double, 2> size{0.0, 0.0}; ///< the slab's plan [m]
  double thickness = 0.0;               ///< [m]
  Core core = Core::cylinder;
  std::array<double, 2> centre{0.0, 0.0};    ///< the core's axis [m]
  std::array<double, 2> core_half{0.0, 0.0}; ///< a box core's half sizes [m]
  double core_radius = 0.0;                  ///< a cylinder core's radius [m]
  double band = 0.0;                         ///< the overlap's width round the core [m]
  double element_size = 0.0;                 ///< the shells' at the core [m]
  double outer_element_size = 0.0;           ///< at the slab's corners, graded from element_size [m]; 0 = uniform
  shell::Cell cell = shell::Cell::quadrilateral;
  Edges edges = Edges::simply_supported;
  double frame_width = 0.0; ///< Edges::frame: the frame's width, inwards from the plan's edges [m]
  /// @throws std::runtime_error naming the value: sizes not > 0, a core
  ///   whose band does not lie strictly inside the slab, elements larger
  ///   than the band (the band must hold shell nodes across it).
  void validate() const;
};

/// The overlap: the band of width `band` round the core (Overlap::box or
/// Overlap::cylinder about the z axis).
Overlap slab_overlap(const SlabSpec& s);
/// The DE region: the core and its band through the thickness, for the
/// packing (the band's outer corners rounded, as the distance is).
dem::Region slab_de_region(const SlabSpec& s);
/// The shells: the slab's plan less the core, meshed by Gmsh (elements of
/// about element_size), placed at the mid-surface.
std::shared_ptr<dolfinx::mesh::Mesh> slab_shells(MPI_Comm comm, const SlabSpec& s);
/// Checks that shells meshed elsewhere (shell::read_gmsh, a mesh of one's
/// own) fit the slab: every node on the mid-surface (z = -thickness / 2,
/// within 1e-6 of the thickness) and in the plan; none inside the core and
/// the hole's edge on the core's boundary, both within 1 % of the band (the
/// band's spheres would otherwise lie in no shell element, or shells would
/// stand where only spheres should). slab_shells' meshes pass by
/// construction.
/// @throws std::runtime_error naming how many nodes are off, the worst by
///   how much and where.
void check_slab_shells(const shell::FEModel& fe, const SlabSpec& s);
/// The dofs the edges hold (none for free edges): the nodes on the plan's
/// outer boundary, their translations (simply supported) or all six
/// (clamped).
std::vector<std::int32_t> slab_support_dofs(const shell::FEModel& fe, const SlabSpec& s);
/// Edges::frame: the slab rests on a rigid frame, the strip of the rear face
/// within frame_width of the plan's edges. Each shell node over the strip
/// gets a compression-only spring on u_z (FEModel::set_support_springs) of
/// stiffness E A / (thickness / 2), A its tributary area: the concrete
/// between the mid-surface and the rear face, in compression, carries the
/// bearing. Sets them on fe and returns how many; none for other edges.
/// @throws std::runtime_error if no node lies over the strip.
std::size_t slab_frame_springs(shell::FEModel& fe, const SlabSpec& s, double youngs_modulus);

} // namespace dembridge::bridge
