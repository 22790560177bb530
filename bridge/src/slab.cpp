// The parts of a coupled slab (slab.h): the overlap round the core, the DE
// region, the shells with the hole, the supports.
#include "dembridge/bridge/slab.h"
#include "dembridge/shell/explicit.h"

#include "dembridge/core/text.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>

namespace dembridge::bridge
{
namespace
{
using core::number_text;

/// The core's reach from its axis along x and y [m].
std::array<double, 2> core_reach(const SlabSpec& s)
{
  return s.core == SlabSpec::Core::box ? s.core_half : std::array<double, 2>{s.core_radius, s.core_radius};
}
} // namespace

void SlabSpec::validate() const
{
  for (auto [name, v] : {std::pair{"slab size x", size[0]}, {"slab size y", size[1]}, {"slab thickness", thickness},
                         {"overlap band", band}, {"shell element size", element_size}})
    if (!(v > 0.0) || !std::isfinite(v))
      throw std::runtime_error(std::string(name) + " " + number_text(v) + " m: must be > 0");
  const auto r = core_reach(*this);
  if (!(r[0] > 0.0 && r[1] > 0.0))
    throw std::runtime_error("core size " + number_text(r[0]) + " x " + number_text(r[1]) + " m: must be > 0");
  for (int k = 0; k < 2; ++k)
    if (!(std::abs(centre[k]) + r[k] + band < 0.5 * size[k]))
      throw std::runtime_error("the core about (" + number_text(centre[0]) + ", " + number_text(centre[1]) + ") m with its band ("
                               + number_text(r[k]) + " + " + number_text(band) + " m) must lie strictly inside the slab's plan, "
                               + number_text(size[0]) + " x " + number_text(size[1]) + " m");
  if (element_size > band)
    throw std::runtime_error("shell element size " + number_text(element_size) + " m: must not exceed the overlap band, "
                             + number_text(band) + " m (the band must hold shell nodes across it)");
  if (edges == Edges::frame)
    for (int k = 0; k < 2; ++k)
      if (!(frame_width > 0.0) || !(std::abs(centre[k]) + r[k] + band < 0.5 * size[k] - frame_width))
        throw std::runtime_error("the frame under the edges, " + number_text(frame_width) + " m wide, must lie beyond "
                                 "the core and its band (" + number_text(r[k]) + " + " + number_text(band)
                                 + " m about " + number_text(centre[k]) + " m) in the slab's plan, "
                                 + number_text(size[0]) + " x " + number_text(size[1]) + " m");
}

Overlap slab_overlap(const SlabSpec& s)
{
  return s.core == SlabSpec::Core::box ? Overlap::box(s.centre, s.core_half, s.band)
                                       : Overlap::cylinder(s.centre, s.core_radius, s.band);
}

dem::Region slab_de_region(const SlabSpec& s)
{
  s.validate();
  const Overlap o = slab_overlap(s);
  const auto r = core_reach(s);
  const double h = s.thickness, w = s.band;
  return dem::sdf_region(
      s.core == SlabSpec::Core::box ? "the box core and its band" : "the cylinder core and its band",
      [o, h, w](const dem::Point& x) { return std::max(o.distance({x[0], x[1], x[2]}) - w, std::abs(x[2] + 0.5 * h) - 0.5 * h); },
      {s.centre[0] - r[0] - w, s.centre[1] - r[1] - w, -h}, {s.centre[0] + r[0] + w, s.centre[1] + r[1] + w, 0.0});
}

std::shared_ptr<dolfinx::mesh::Mesh> slab_shells(MPI_Comm comm, const SlabSpec& s)
{
  s.validate();
  shell::SlabOutline o;
  o.lx = s.size[0];
  o.ly = s.size[1];
  o.size = s.element_size;
  o.outer_size = s.outer_element_size;
  o.centre = {s.centre[0] + 0.5 * s.size[0], s.centre[1] + 0.5 * s.size[1]}; // the outline's frame: [0, l]
  if (s.core == SlabSpec::Core::box)
  {
    o.hole = shell::SlabOutline::Hole::rectangle;
    o.half = s.core_half;
  }
  else
  {
    o.hole = shell::SlabOutline::Hole::circle;
    o.radius = s.core_radius;
  }
  shell::Placement p;
  p.origin = {-0.5 * s.size[0], -0.5 * s.size[1], -0.5 * s.thickness};
  return shell::mesh_outline(comm, o, s.cell, p);
}

std::vector<std::int32_t> slab_support_dofs(const shell::FEModel& fe, const SlabSpec& s)
{
  if (s.edges == SlabSpec::Edges::free || s.edges == SlabSpec::Edges::frame)
    return {};
  const double tol = 1e-9 * std::max(s.size[0], s.size[1]);
  const auto nodes = shell::select_nodes(
      fe.node_coordinates(),
      [&](const std::array<double, 3>& x)
      { return std::abs(std::abs(x[0]) - 0.5 * s.size[0]) < tol || std::abs(std::abs(x[1]) - 0.5 * s.size[1]) < tol; },
      "the slab's outer edges");
  std::vector<int> comps(s.edges == SlabSpec::Edges::clamped ? fe.block_size() : 3);
  std::iota(comps.begin(), comps.end(), 0);
  return shell::node_dofs(nodes, fe.block_size(), comps);
}

std::size_t slab_frame_springs(shell::FEModel& fe, const SlabSpec& s, double youngs_modulus)
{
  if (s.edges != SlabSpec::Edges::frame)
    return 0;
  const double tol = 1e-9 * std::max(s.size[0], s.size[1]);
  const double w = s.frame_width;
  const auto nodes = shell::select_nodes(
      fe.node_coordinates(),
      [&](const std::array<double, 3>& x)
      { return std::abs(x[0]) > 0.5 * s.size[0] - w - tol || std::abs(x[1]) > 0.5 * s.size[1] - w - tol; },
      "the frame's strip under the slab's edges (target.support_width_m)");
  const auto area = fe.nodal_measure();
  const double per_area = youngs_modulus / (0.5 * s.thickness); // [N/m^3]
  std::vector<std::int32_t> dofs;
  std::vector<double> k;
  for (auto n : nodes)
  {
    dofs.push_back(n * fe.block_size() + 2);
    k.push_back(per_area * area[n]);
  }
  fe.set_support_springs(std::move(dofs), std::move(k));
  return nodes.size();
}

} // namespace dembridge::bridge
