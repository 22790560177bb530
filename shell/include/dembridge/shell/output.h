#pragma once
/// @file output.h
/// XDMF + HDF5 time series of an FE model for ParaView: displacement [m],
/// velocity [m/s] and, for shells, rotation [rad], angular velocity [rad/s]
/// and average nodal normal, each as a 3-vector field on the mesh.

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
  ~XdmfWriter();
  /// Appends the fields at time t from the dof arrays u, v (num_dofs).
  void write(double t, std::span<const double> u, std::span<const double> v);
  /// Flushes and closes (also done by the destructor).
  void close();

private:
  struct Impl;
  std::unique_ptr<Impl> _impl;
};

} // namespace dembridge::shell
