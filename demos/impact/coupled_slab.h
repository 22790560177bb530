#pragma once
/// @file coupled_slab.h
/// The coupled slab of the impact program (slab_coupling.h): a DE core
/// round the projectile's path tied to reinforced-concrete shells over the
/// rest of the slab (docs/impact.md, "Coupled slabs"). Library
/// impact_coupled_case (DOLFINx, Gmsh).

#include "slab_coupling.h"

#include "dembridge/bridge/slab.h"
#include "dembridge/shell/model.h"

namespace dembridge::demo
{

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

} // namespace dembridge::demo
