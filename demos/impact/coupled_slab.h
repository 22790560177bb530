#pragma once
/// @file coupled_slab.h
/// The coupled slab of the impact program (slab_coupling.h): a DE core
/// round the projectile's path tied to reinforced-concrete shells over the
/// rest of the slab (docs/impact.md, "Coupled slabs"). Library
/// impact_coupled_case (DOLFINx, Gmsh).

#include "slab_coupling.h"

#include "dembridge/bridge/fictive.h"
#include "dembridge/bridge/slab.h"
#include "dembridge/shell/model.h"

#include <span>

namespace dembridge::demo
{

/// The slab's plan, thickness, element sizes and edges from the scenario's
/// target and [shells] keys (no core: its centre is projectile.aim_m).
bridge::SlabSpec slab_plan(const Scenario& s);

/// The slab's parts from the scenario's target and [shells] keys.
/// @throws std::runtime_error naming the keys: no core size, a core and
///   band not inside the slab, elements larger than the band.
bridge::SlabSpec slab_spec(const Scenario& s);

/// The shells' section: the concrete's E, nu and density, the slab's
/// thickness (shell::Material), and the mats of the scenario as steel
/// layers at their heights (`normal_z`: the sign of the shells' normal
/// along z, +1 or -1).
shell::Material shell_material(const Scenario& s);
shell::Reinforcement shell_steel(const Scenario& s, double normal_z);

/// The coupled slab of a scenario with shells.model = "coupled".
std::unique_ptr<SlabCoupling> make_slab_coupling(const Scenario& s);

/// The shells' deflection at shells.deflection_points_m: each point located
/// in its shell element at the mid-surface (bridge::locate), u_z there
/// interpolated from the element's nodes (u_x under an in-plane pulse).
class ShellPoints
{
public:
  ShellPoints(const shell::FEModel& fe, const Scenario& s);
  std::vector<double> deflections(std::span<const double> u) const;
  std::size_t size() const { return _n; }

private:
  std::unique_ptr<bridge::CouplingOperator> _op;
  std::size_t _n = 0, _dofs = 0;
  int _component = 2;
};

/// The shells' largest |u_z| at the dofs u [m].
double max_deflection(const shell::FEModel& fe, std::span<const double> u);
/// The supports' force on the shells along z at the dofs u [N]: the held
/// dofs' reactions r summed over the nodes, and a frame's springs.
double support_reaction(const shell::FEModel& fe, std::span<const double> r, std::span<const double> u);

struct ImpactConfig;
/// Runs a scenario with shells.model = "fe": the slab all in shells (the
/// coupled slab's, without the hole; a node at projectile.aim_m), loaded
/// by the pulse on the nodes of its disc (each its share of the disc's
/// tributary area). Writes shell.xdmf and history.csv; returns the summary
/// (ImpactConfig::shells_only).
nlohmann::json run_shell_slab(const ImpactConfig& cfg);

} // namespace dembridge::demo
