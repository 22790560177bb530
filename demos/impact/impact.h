#pragma once
/// @file impact.h
/// A rigid projectile striking a slab of DE concrete (docs/impact.md): the
/// run of the impact demo, as a function the demo and the tests share.

#include "scenario.h"
#include "slab_coupling.h"

#include "dembridge/dem/assembly.h"

#include "restart.h"

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace dembridge::demo
{

struct ImpactConfig
{
  Scenario scenario;
  std::string output_dir; ///< "" = no files
  bool plot = true;       ///< a PNG of the projectile's history (needs --output)
  bool quiet = false;
  /// Checkpoints and restart (restart.h); null: neither.
  const RestartOptions* restart = nullptr;
  /// Builds the coupled slab of a scenario with shells.model = "coupled"
  /// (make_slab_coupling, coupled_slab.h); empty: such a scenario is refused.
  SlabCouplingFactory coupling;
  /// Runs a scenario with shells.model = "fe": the slab all in shells under
  /// the pulse (run_shell_slab, coupled_slab.h); empty: such a scenario is
  /// refused.
  std::function<nlohmann::json(const ImpactConfig&)> shells_only;
};

/// The craters measured on the slab (docs/impact.md, "Measurements"). A
/// sphere is detached when it has lost every link it had, or left the
/// domain. The slab is cut into layers 2 Rmax thick parallel to its faces;
/// in each, the detached spheres' volume over the layer's thickness and
/// the packing fraction gives the area they occupied, and its equivalent
/// diameter. The front crater is the run of layers from the struck face
/// whose equivalent diameter exceeds twice the projectile's (wider than its
/// tunnel); its diameter is that of the first layer (0 without a crater),
/// its depth where the run ends, its mass the detached mass in it. The rear
/// scab likewise from the rear face, over the layers the crater left.
struct Crater
{
  double diameter = 0.0; ///< [m]
  double depth = 0.0;    ///< [m]
  double mass = 0.0;     ///< [kg]
};

struct CraterInput
{
  std::vector<double> x0;            ///< initial centres (n, 3) [m]
  std::vector<double> r, m;          ///< radii [m], masses [kg]
  std::vector<std::uint8_t> detached;
  double thickness = 0.0;            ///< slab in z in [-thickness, 0] [m]
  double layer = 0.0;                ///< layer thickness [m]
  double fraction = 0.6;             ///< packing fraction [-]
  double tunnel = 0.0;               ///< equivalent diameter a crater must exceed [m]
};

/// The front crater (from z = 0 down) and the rear scab (from z = -thickness up).
std::pair<Crater, Crater> measure_craters(const CraterInput& in);

/// Runs the scenario; returns the summary (docs/impact.md lists its keys:
/// perforated, striking_velocity_m_s, residual_velocity_m_s,
/// penetration_depth_m, front_crater_*, rear_scab_*, ejected_mass_kg,
/// energy, particles, steps, dt_s, wall_s, ...). With an output folder,
/// writes particles.xdmf (the spheres, the cracks, the projectile's surface),
/// history.csv, packing.txt, scenario.json and history.png.
nlohmann::json run_impact(const ImpactConfig& cfg);

} // namespace dembridge::demo
