#pragma once
// Internal to dem/: the force loop's kernels (docs/architecture.md, "One
// coupled step"). compute_forces (force_loop.cpp) resolves the step's law
// once (StepLaw: which parts of the concrete law are on, from the material,
// the arrays' sizes and dt), then sweeps the links with LinkKernel and the
// contact pairs with ContactKernel. A kernel's prepare(i, k0, k1, g) fills
// the `prepared` values of sphere i's items at once; force(i, k, g_k, out)
// then computes item k's force on b and torque factors (sweep, in
// force_loop.cpp), from the pure laws of law.h.
#include "force_loop.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <omp.h>
#include <span>

namespace dembridge::dem::kernel
{
using impl::ContactFactors;
using impl::ContactSpring;
using impl::contact_spring;
using impl::dot3;

/// How many items ahead a sweep prefetches what item k's sphere b needs:
/// sphere b lies anywhere along the curve, so its record, force and torque
/// are rarely in the core's caches when its item comes.
constexpr std::int32_t ahead = 16;
/// Sphere b of the item `ahead` items after k (the last item near the end).
inline std::int32_t b_ahead(std::span<const std::int32_t> b, std::int32_t k)
{
  return b[std::min<std::size_t>(static_cast<std::size_t>(k + ahead), b.size() - 1)];
}

/// The `count` items' prepared values g[0..3] from the branch (d, |d|^2) to
/// the unit normal and the length (d / |d|, |d|); items marked with g[3] < 0
/// are left as they are.
inline void unit_normals(double* g, std::int32_t count)
{
  for (std::int32_t m = 0; m < count; ++m)
  {
    double* gk = g + prepared * m;
    if (gk[3] < 0.0)
      continue;
    const double D = std::sqrt(gk[3]);
    const double inv = 1.0 / D;
    gk[0] *= inv;
    gk[1] *= inv;
    gk[2] *= inv;
    gk[3] = D;
  }
}

/// Unit normal a -> b and branch length of the items [k0, k1) of sphere i,
/// into g[0..3] of each item's `prepared` values: done for a sphere's items
/// together, so that the square roots and divisions of successive items
/// overlap (the loop bodies are short and independent).
inline void branches(const double* rec, std::size_t i, std::span<const std::int32_t> b, std::int32_t k0,
                     std::int32_t k1, double* g)
{
  const double* xi = rec + record * i;
  for (std::int32_t k = k0; k < k1; ++k)
  {
    __builtin_prefetch(rec + record * b_ahead(b, k));
    const double* xj = rec + record * b[k];
    double* gk = g + prepared * (k - k0);
    gk[0] = xj[0] - xi[0];
    gk[1] = xj[1] - xi[1];
    gk[2] = xj[2] - xi[2];
    gk[3] = gk[0] * gk[0] + gk[1] * gk[1] + gk[2] * gk[2];
  }
  unit_normals(g, k1 - k0);
}

/// The smallest strength factor that keeps a link as it stands (Material::
/// rate_current, docs/method.md 1.6b), and at least 1: elastic at its largest
/// elongation so far, K_n delta_max <= S_int T f; with the factor on C0 too,
/// its stored shear force within the Mohr-Coulomb cap S_int C0 f - F_t tan(phi_i)
/// (the tension F_t taken at delta_max: the largest it has been, so the floor
/// is on the safe side)
inline double held_factor(const Links& l, std::int32_t k, const LinkLaw& law, bool cohesion)
{
  const double stretch = std::max(l.delta_max[k], 0.0) * law.kn;
  double f = 1.0;
  if (law.tensile > 0.0)
    f = std::max(f, stretch / (law.s_int * law.tensile));
  if (cohesion && law.cohesion > 0.0)
  {
    const double* fs = &l.fs[3 * k];
    const double shear = std::sqrt(fs[0] * fs[0] + fs[1] * fs[1] + fs[2] * fs[2]);
    f = std::max(f, (shear + stretch * law.tan_phi_i) / (law.s_int * law.cohesion));
  }
  return f;
}

inline StepRotation load_rotation(const double* rec)
{
  return {{rec[4], rec[5], rec[6]}, rec[7]};
}

/// Writes the force on b (fb, N) and the torque factor q (torque on either
/// sphere = its radius times q, N m / m) of a pair with unit normal n, normal
/// force fn (tension > 0), shear force fs on b, branch length D and radius
/// sum rs (given as 1 / rs): the contact point is R_a D / rs from a, so t_a = -l_a n x fs =
/// R_a q with q = -(D / rs) n x fs, and t_b = R_b q likewise.
inline void pair_output(double* out, const double* n, double fn, const Vec3& fs, double D, double inv_rs)
{
  const Vec3 nxf = detail::cross({n[0], n[1], n[2]}, fs);
  const double s = -D * inv_rs;
  for (int q = 0; q < 3; ++q)
  {
    out[q] = -fn * n[q] + fs[q];
    out[3 + q] = s * nxf[q];
  }
}

/// The law of one step, resolved once by compute_forces: which parts of the
/// concrete law are on (they depend on the material, on which per-link
/// arrays are sized, and on dt) and the constants every item reads.
struct StepLaw
{
  const Material& mat;
  LinkLaw base;      ///< the material's link law with unit surface and stiffnesses
  ContactFactors cf; ///< equation [1]'s factors for contacts
  double dt;         ///< [s]; 0 outside a step (no rate effect)
  bool weighted_links, weighted_spheres; ///< the coupling's weights are set
  /// the links' strength factors apply whenever they are sized; they follow
  /// the strain rate only over a step (dt > 0: the velocities are v(n+1/2))
  bool factored, rated;
  bool filtered;        ///< the rate goes through the filter (Material::rate_filter)
  double filter_weight; ///< the filter's weight per step
  bool gated;           ///< the rate effect needs the sphere's links stretched on the whole
  bool compacting, pressure_gated; ///< compaction on; under a pressure gate
  bool track;           ///< the cohesion demand is tracked (ForceCounters)
  double demand_before; ///< the cohesion demand at the step's start [Pa]
};

inline StepLaw step_law(const Particles& p, const Links& l, const Material& mat, double dt, const ForceCounters& c)
{
  const bool factored = l.strength.size() == l.size() && !l.strength.empty();
  const bool rated = factored && mat.rate_fc > 0.0 && dt > 0.0;
  const bool filtered = rated && l.rate.size() == l.size();
  const bool compacting = mat.compaction.on() && l.compaction.size() == l.size();
  return {.mat = mat,
          .base = mat.law(1.0, 1.0, 1.0),
          .cf = impl::contact_factors(mat),
          .dt = dt,
          .weighted_links = !l.weight.empty(),
          .weighted_spheres = !p.weight.empty(),
          .factored = factored,
          .rated = rated,
          .filtered = filtered,
          .filter_weight = filtered ? std::min(1.0, dt / mat.rate_filter) : 1.0,
          .gated = rated && mat.rate_mean_tension,
          .compacting = compacting,
          .pressure_gated = compacting && mat.compaction.gated() && l.compaction_onset.size() == l.size(),
          .track = c.track_cohesion,
          .demand_before = c.cohesion_demand};
}

} // namespace dembridge::dem::kernel
