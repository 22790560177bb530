#pragma once
/// @file skin.h
/// Free-surface correction of the links' stiffness (a choice of the project:
/// the method says nothing of free surfaces; docs/method.md section 1.13).
///
/// A sphere at a free face misses the links it would have to the material
/// beyond the face: the outer layer lies flat on the face with ~7 links per
/// sphere against 12 in the bulk, and the layer under it is looser. The
/// assembly is then soft in a skin about two radii deep, which weighs little
/// in tension but much in bending (z^2): a 0.25 m concrete bar of 1 cm
/// spheres is 5.9-7.9 % more compliant in bending than the E it shows in
/// tension predicts (docs/validation.md, the validation bar). The correction gives each
/// sphere within `depth` of the region's boundary a factor f_i = z_bulk / z_i
/// (at least 1; z_i its links, z_bulk the mean over the bulk spheres) and
/// multiplies each link's K_n and K_s by the mean of its two spheres'
/// factors. Links of two bulk spheres keep their stiffness. The strengths
/// (force thresholds S_int T and S_int C0) are not changed: a compensated
/// link reaches them at a smaller elongation.

#include "dembridge/dem/assembly.h"
#include "dembridge/dem/packing.h"

namespace dembridge::dem
{

struct SkinCompensation
{
  std::size_t spheres = 0;      ///< spheres within the depth with a factor > 1
  std::size_t links = 0;        ///< links whose stiffness changed
  double bulk_links = 0.0;      ///< z_bulk: mean links per bulk sphere
  double max_factor = 1.0;      ///< largest sphere factor
  double mean_link_factor = 1.0;///< mean factor over the changed links
};

/// Applies the correction to `l` (created on `p` in `region`). `depth` [m]:
/// the skin's depth, e.g. 2 Rmax. @throws std::runtime_error if depth is
/// not finite and > 0, if the region has no bulk sphere (dem::bulk_spheres),
/// or if `l` does not belong to `p`.
SkinCompensation compensate_skin(const Particles& p, Links& l, const Region& region, double depth);

} // namespace dembridge::dem
