#pragma once
// Internal to dem/: how the force loop shares its items between threads, and
// the scratch space it keeps between calls.
#include "dembridge/dem/forces.h"
#include "pairs.h"

#include <climits>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace dembridge::dem
{

/// The most values an item's output has (a sweep of width 9: force on b, then
/// the torque factors of a and b).
constexpr int max_out = 9;
/// Values per item that a sweep prepares for a whole sphere at once.
constexpr int prepared = 8;
/// Doubles per sphere record of the force loop: centre (3), radius, the
/// rotation over the step as a StepRotation (u (3), k): 64 bytes, one cache
/// line, all that a link reads of its sphere b.
constexpr int record = 8;

/// How the items of the force loop (links, or neighbour pairs; sorted by
/// (a, b)) are shared between T threads: thread t owns a contiguous range
/// of spheres, with an equal share of items plus spheres, and computes the
/// items whose a it owns, adding each item's force to both spheres. Items
/// whose b belongs to a later thread ("cross" items) are computed first into
/// a buffer, which their b sphere reads before its own items: every sphere
/// then sums its items in the same order (b side in item order, then a side)
/// whatever T is.
struct SweepIndex
{
  std::vector<std::int32_t> first;      ///< items with a = i: [first[i], first[i + 1])
  std::vector<std::size_t> bounds;      ///< spheres of thread t: [bounds[t], bounds[t + 1]) (T + 1)
  std::vector<std::int32_t> cross_first; ///< first buffer slot of each thread (T + 1)
  std::vector<std::int32_t> in_first, in; ///< slots of the cross items into sphere b (CSR)
  std::vector<std::int32_t> cross_i, cross_k; ///< per slot: the cross item's sphere a and item
  /// per cross item (max_out values each, a sweep of width W uses W): force
  /// on b (3), torque factor q (3) or q_a (3) and q_b (3)
  std::vector<double> out;
  std::vector<std::vector<double>> geometry; ///< per thread: branches of one sphere's items
  int threads = 0;
  /// @throws std::runtime_error if the items are not sorted or out of range
  void build(std::size_t np, std::span<const std::int32_t> a, std::span<const std::int32_t> b,
             int threads);
  std::size_t bytes() const;
};

/// Scratch space and index structures of the force loop, kept between calls
/// so that a step allocates nothing (once sized). Rebuilt by compute_forces
/// when the links, the neighbour pairs or the thread count change.
struct ForceScratch
{
  /// per sphere, 64-byte aligned: centre (3), radius, rotation over the step
  /// (StepRotation: u (3), k), what a link reads of its spheres
  std::vector<double> records;
  SweepIndex links, pairs;
  std::vector<double> pair_slip; ///< per pair: energy dissipated by friction in the step [J]
  std::vector<std::vector<std::pair<std::int32_t, double>>> broken; ///< per thread
  std::vector<std::pair<std::int32_t, double>> broken_all;
  std::vector<std::int32_t> broken_ids;
  std::vector<double> demand;    ///< per thread: ForceCounters::cohesion_demand
  /// per sphere: sum of K_n (D - D_init) D over its intact links
  /// (Material::rate_mean_tension)
  std::vector<double> stretch;
  std::vector<double> link_stretch; ///< per link: its terms of `stretch` and `pressure`
  /// per sphere: its links' mean pressure [Pa] (CompactionLaw::pressure)
  std::vector<double> pressure;
  const std::int32_t* links_for = nullptr; ///< the link array the index was built for
  std::size_t links_size = 0, pairs_version = SIZE_MAX;
  /// the most a pair's touching distance exceeds R_a + R_b [m], for the
  /// links and the crack closure `closure_for` (-1: not yet known)
  double contact_reach = 0.0, closure_for = -1.0;
  std::size_t bytes() const;
};

/// compute_forces with the caller's scratch space (DemSolver's, kept
/// between steps so that a step allocates nothing once sized).
void compute_forces(Particles& p, Links& l, NeighbourList& nl, const Material& mat, double dt,
                    ForceCounters& c, ForceScratch& scratch);

/// The part of elastic_energy() held by the given links and neighbour-list
/// pairs [J], summed in the order given (energy.cpp): what leaves with
/// removed spheres, without a sum over the whole assembly.
double elastic_energy_of(const Particles& p, const Links& l, const NeighbourList& nl, const Material& mat,
                         std::span<const std::size_t> links, std::span<const std::size_t> pairs);

namespace impl
{
inline double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross3(const double* a, const double* b)
{
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

/// Equation [1] factors for contacts: K_n = E S / (R_a + R_b) * cn, K_s = K_n * cs.
struct ContactFactors
{
  double cn, cs;
};
inline ContactFactors contact_factors(const Material& m)
{
  const auto k = link_stiffness(m.youngs_modulus, m.poisson_ratio, 1.0, 1.0, m.micro);
  return {k.kn / m.youngs_modulus, k.ks / k.kn};
}
/// A contact's springs: the distance from which its spheres push each other
/// apart, and its normal and shear stiffnesses. Spheres touch from R_a + R_b,
/// with the contacts' stiffnesses (equation [1] with the factors cf); with
/// Material::crack_closure = c > 0 the spheres of a broken link touch from
/// R_a + R_b + c (D_init - R_a - R_b), with the link's K_n and K_s
/// (method.md 1.7). A broken compacted link's spheres touch closer by its
/// set (1.6c).
struct ContactSpring
{
  double touch, kn, ks;
};
inline ContactSpring contact_spring(const Material& mat, const ContactFactors& cf, const Links& l, std::int32_t link,
                                    double ra, double rb, bool compacting)
{
  const double rs = ra + rb;
  const bool closing = mat.crack_closure > 0.0 && link >= 0;
  double touch = closing ? closing_distance(l.d0[link], rs, mat.crack_closure) : rs;
  if (compacting && link >= 0)
    touch += compaction_set(l.compaction[link], l.d0[link], link_compaction(l, link, mat.compaction));
  if (closing)
    return {touch, l.kn[link], l.ks[link]};
  const double kn = mat.youngs_modulus * pair_surface(ra, rb) / rs * cf.cn;
  return {touch, kn, kn * cf.cs};
}
} // namespace impl

} // namespace dembridge::dem
