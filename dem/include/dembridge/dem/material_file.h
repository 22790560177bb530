#pragma once
/// @file material_file.h
/// The DE material parameter file (JSON) that the identification writes and
/// every demo reads with --material FILE. Format (SI units, angles in degrees):
///
///     {
///       "format": "dembridge-material-2",   (-1: the same without steel and bond)
///       "youngs_modulus_pa": 3.0e10,      E in equation [1]
///       "poisson_ratio": 0.2,             nu in equation [1]
///       "density_kg_m3": 2400,            bulk density of the concrete
///       "alpha": 3.1, "beta": 1.0, "gamma": 1.0,
///       "tensile_strength_pa": 3.3e6,     T
///       "cohesion_pa": 4.4e6,             C0
///       "softening": 10,                  zeta
///       "phi_i_deg": 30, "phi_c_deg": 30,
///       "links_per_sphere": 12,           how lambda is chosen on a packing
///       "rate_fc_pa": 4.8e7,              optional: the strain-rate effect (docs/method.md 1.6b),
///       "rate_max_1_s": 100,              with its optional cap, "rate_cohesion": true,
///       "rate_mean_tension": true, "rate_filter_s": 1e-5,
///       "rate_current": true,
///       "contact_shear_limit_pa": 1.7e8,  optional: the contacts' Tresca limit (1.7)
///       "rolling_friction": 0.1,          optional: the contacts' rolling resistance mu_r (1.7d)
///       "crack_closure": 1,               optional: where broken links close, in [0, 1] (1.7)
///       "compaction_onset": 0.004,        optional, with the next two: compaction (1.6c)
///       "compaction_stiffness": 0.3,
///       "compaction_lock": 0.04,
///       "compaction_pressure_pa": 1.6e7,  optional, with them: its pressure gate
///       "steel": {...},                   optional: the bars' steel (bars.h: Steel), keys
///                                         youngs_modulus_pa, density_kg_m3, yield_pa,
///                                         hardening_pa, rupture_strain, each optional
///       "bond": {...},                    optional: the bar-concrete bond (BondLaw), keys
///                                         tau_max_pa, s0_m, s1_m, s2_m, s3_m, alpha,
///                                         tau_f_ratio, radial_stiffness_pa_m, opening_pa,
///                                         opening_gap_m, each optional
///       "lambda": 1.49,                   lambda on the calibration packing (information)
///       "macroscopic": {...},             what the parameters reproduce (information)
///       "calibration": {...}              how they were obtained (information)
///     }

#include "dembridge/dem/assembly.h"
#include "dembridge/dem/bars.h"

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

namespace dembridge::dem
{

struct MaterialFile
{
  Material material;
  double links_per_sphere = 12.0;
  std::optional<Steel> steel;   ///< the bars' steel, if the file gives it (format 2)
  std::optional<BondLaw> bond;  ///< the bars' bond, if the file gives it (format 2)
  double lambda = 0.0;          ///< 0 if not given
  nlohmann::json macroscopic;   ///< free-form information
  nlohmann::json calibration;   ///< free-form information
};

/// @throws std::runtime_error naming the file and the missing or bad key.
MaterialFile read_material(const std::filesystem::path& file);
void write_material(const std::filesystem::path& file, const MaterialFile& m);

} // namespace dembridge::dem
