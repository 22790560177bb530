#pragma once
/// @file output.h
/// XDMF + HDF5 time series of the particles for ParaView: position (as the
/// points), radius [m], displacement [m], velocity [m/s], damage (broken /
/// initial links of each sphere) and, optionally, the broken links as line
/// cells (the crack pattern). Every frame is flushed and the XDMF rewritten,
/// so what was written stays readable if the run stops.

#include "dembridge/dem/assembly.h"
#include "dembridge/dem/bars.h"
#include "dembridge/dem/body.h"
#include "dembridge/core/checkpoint.h"

#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace dembridge::dem
{

class ParticleWriter
{
public:
  /// Creates `file` (.xdmf) and the .h5 beside it. @param cracks also write
  /// the broken links as a second grid "cracks".
  ParticleWriter(const std::filesystem::path& file, const Links& links, std::size_t particles,
                 bool cracks = true);
  /// Continues the series `file` from a checkpoint written by save(): its
  /// frames up to the checkpoint are kept, later ones dropped.
  ParticleWriter(const std::filesystem::path& file, const Links& links, std::size_t particles,
                 bool cracks, const checkpoint::Group& resume);
  ~ParticleWriter();
  ParticleWriter(const ParticleWriter&) = delete;
  ParticleWriter& operator=(const ParticleWriter&) = delete;

  /// Adds a rigid body's surface as a grid of its own (`name`, triangles;
  /// position and velocity per vertex), before the first frame (and again,
  /// the same, after a resume): each frame then places it where the body is.
  void add_surface(const std::string& name, SurfaceMesh mesh);
  /// Appends a frame at time t [s]; `bodies`: one per surface added, in
  /// the same order.
  void write(double t, const Particles& p, const Links& l, std::span<const RigidBody> bodies = {});
  std::size_t frames() const { return _times.size(); }
  void close();
  /// The frames written so far (times, crack counts), to a checkpoint.
  void save(const checkpoint::Group& g) const;

private:
  void write_xdmf() const;
  std::filesystem::path _xdmf, _h5;
  long _file = -1; // hid_t
  bool _cracks;
  std::vector<double> _times;
  std::vector<std::size_t> _broken_count;
  std::size_t _n;
  std::vector<int> _initial_links; // per particle
  struct Surface
  {
    std::string name;
    SurfaceMesh mesh;
  };
  std::vector<Surface> _surfaces;
};

/// XDMF + HDF5 time series of the bars (bars.h) for ParaView: a line mesh of
/// their elements, the nodes' positions and displacements [m] and velocities
/// [m/s], and per
/// element its axial force [N], plastic strain [-], the mean slip of its
/// bonds [m] (|slip|, 0 without a bond) and whether it broke (0 or 1).
class BarWriter
{
public:
  /// Creates `file` (.xdmf) and the .h5 beside it.
  BarWriter(const std::filesystem::path& file, const Bars& bars);
  /// Continues the series from a checkpoint written by save() (frames after
  /// it dropped).
  BarWriter(const std::filesystem::path& file, const Bars& bars, const checkpoint::Group& resume);
  ~BarWriter();
  BarWriter(const BarWriter&) = delete;
  BarWriter& operator=(const BarWriter&) = delete;
  void write(double t, const Bars& bars);
  void close();
  void save(const checkpoint::Group& g) const;
  std::size_t frames() const { return _times.size(); }

private:
  void write_xdmf() const;
  std::filesystem::path _xdmf, _h5;
  long _file = -1; // hid_t
  std::size_t _nodes, _elements;
  std::vector<double> _times;
};

} // namespace dembridge::dem
