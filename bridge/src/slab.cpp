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

namespace
{
/// Counts the nodes whose excess is above tol; keeps the worst.
struct Offence
{
  std::size_t count = 0;
  double worst = 0.0;
  std::array<double, 3> at{};
  void see(double excess, double tol, const double* x)
  {
    if (!(excess > tol))
      return;
    ++count;
    if (excess > worst)
    {
      worst = excess;
      at = {x[0], x[1], x[2]};
    }
  }
  void raise(const std::string& what, const std::string& allowed) const
  {
    if (count == 0)
      return;
    throw std::runtime_error("shell mesh: " + std::to_string(count) + " nodes " + what + ", the farthest by "
                             + number_text(worst) + " m at (" + number_text(at[0]) + ", " + number_text(at[1]) + ", "
                             + number_text(at[2]) + ") m; " + allowed);
  }
};

} // namespace

void check_slab_shells(const shell::FEModel& fe, const SlabSpec& s)
{
  s.validate();
  const Overlap o = slab_overlap(s);
  const double tol = 0.01 * s.band, plane_tol = 1e-6 * s.thickness;
  const double edge_tol = 1e-6 * std::max(s.size[0], s.size[1]);
  const auto x = fe.node_coordinates();
  const std::size_t n = fe.num_nodes();
  std::vector<std::uint8_t> boundary(n, 0); // 1 on the mesh's boundary: the plan's edges and the hole's
  for (std::int32_t k : fe.boundary_nodes())
    boundary[k] = 1;
  Offence plane, plan, inside, hole;
  std::size_t hole_nodes = 0;
  std::array<double, 4> reach{0.0, 0.0, 0.0, 0.0}; // the mesh's extent: -x, +x, -y, +y
  for (std::size_t k = 0; k < n; ++k)
  {
    const double* p = &x[3 * k];
    reach = {std::max(reach[0], -p[0]), std::max(reach[1], p[0]), std::max(reach[2], -p[1]), std::max(reach[3], p[1])};
    plane.see(std::abs(p[2] + 0.5 * s.thickness), plane_tol, p);
    const double out = std::max(std::abs(p[0]) - 0.5 * s.size[0], std::abs(p[1]) - 0.5 * s.size[1]);
    plan.see(out, edge_tol, p);
    const double d = o.distance({p[0], p[1], p[2]});
    inside.see(-d, tol, p);
    if (boundary[k] && out < -tol) // on the mesh's boundary, not on the plan's edges: the hole's edge
    {
      ++hole_nodes;
      hole.see(d, tol, p);
    }
  }
  plane.raise("lie off the slab's mid-surface z = " + number_text(-0.5 * s.thickness) + " m",
              "the shells must lie there (the frame: struck face z = 0)");
  plan.raise("lie outside the slab's plan, " + number_text(s.size[0]) + " x " + number_text(s.size[1]) + " m about the origin",
             "the shells must cover the plan and no more");
  for (int q = 0; q < 4; ++q)
    if (reach[q] < 0.5 * s.size[q / 2] - tol)
      throw std::runtime_error("shell mesh: it reaches " + number_text(q % 2 ? reach[q] : -reach[q]) + " m along "
                               + (q / 2 ? "y" : "x") + ", short of the slab's plan, " + number_text(s.size[0]) + " x "
                               + number_text(s.size[1]) + " m about the origin: the shells must cover the plan");
  inside.raise("lie inside " + o.what(), "the shells' hole must match the core (within 1 % of the band, "
                                                 + number_text(tol) + " m)");
  hole.raise("of the hole's edge lie beyond " + o.what(),
             "the band's spheres there would lie in no shell element: the hole must match the core (within 1 % of the band, "
                 + number_text(tol) + " m)");
  if (hole_nodes == 0)
    throw std::runtime_error("shell mesh: no hole for " + o.what() + ": the shells must leave the core to the spheres");
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
