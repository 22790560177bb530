#pragma once
/// @file output.h
/// XDMF + HDF5 time series of an FE model for ParaView: displacement [m],
/// velocity [m/s] and, for shells, rotation [rad], angular velocity [rad/s]
/// and average nodal normal, each a 3-vector field at the nodes. The mesh
/// (reference coordinates /mesh/geometry, cells /mesh/topology) is written
/// once; each time step is one grid carrying every field (/frame_k/<field>),
/// all in 64-bit floats, so one can colour by one field and warp by another.
/// The file is flushed and the XDMF rewritten at every frame. A model whose
/// energy weight (FEModel::weight, a coupled model's) is not 1 everywhere
/// also gets that weight as a scalar node field, `weight`, in every grid.
/// Shells also carry their section's fields per cell (FEModel::
/// section_stresses), 3 x 3 tensors in the global frame: `stress_top` and
/// `stress_bottom`, the concrete's stresses at the face on the side of the
/// normal and at the other [Pa], `membrane_force` [N/m] and
/// `bending_moment` [N m/m]. The writer keeps a reference to the model,
/// which must outlive it.

#include "dembridge/core/checkpoint.h"

#include <filesystem>
#include <memory>
#include <span>

namespace dembridge::shell
{
class FEModel;

class XdmfWriter
{
public:
  /// Opens `file` (.xdmf; the .h5 beside it) for writing and writes the mesh.
  XdmfWriter(const FEModel& model, const std::filesystem::path& file);
  /// Continues the series `file` from a checkpoint written by save(): its
  /// frames up to the checkpoint are kept, later ones dropped.
  XdmfWriter(const FEModel& model, const std::filesystem::path& file, const checkpoint::Group& resume);
  ~XdmfWriter();
  /// Appends the fields at time t from the dof arrays u, v (num_dofs).
  void write(double t, std::span<const double> u, std::span<const double> v);
  /// Flushes and closes (also done by the destructor).
  void close();
  /// The frames written so far (their times), to a checkpoint.
  void save(const checkpoint::Group& g) const;
  std::size_t frames() const;

private:
  struct Impl;
  std::unique_ptr<Impl> _impl;
};

} // namespace dembridge::shell
