#pragma once
/// @file forces.h
/// The DEM force loop (it only calls the laws of law.h), the energies stored
/// and dissipated in links and contacts, and the linearised stiffness with
/// the critical time step it bounds. OpenMP threads over spheres; results do
/// not depend on the thread count.

#include "dembridge/dem/assembly.h"
#include "dembridge/dem/neighbours.h"

#include <cstddef>
#include <span>

namespace dembridge::dem
{
struct Bars;

/// Energy dissipated or stored in the force loop since the start [J], and
/// the wall time of its contacts' part.
struct ForceCounters
{
  double friction = 0.0;   ///< sliding of contacts
  double breakage = 0.0;   ///< elastic energy released when links break
  /// Set to track cohesion_demand (costs a comparison per link and call).
  bool track_cohesion = false;
  /// The smallest cohesion C0 [Pa] at which no intact link's shear force
  /// would have reached the Mohr-Coulomb cap in the calls so far: the largest
  /// (|F_s| + F_n tan phi_i) / S_int (F_n > 0 in tension) over links and
  /// calls. C0 enters nothing else, so a run with another C0 above it (all
  /// else equal) is the same bit for bit: a test can be reused across C0.
  double cohesion_demand = 0.0;
  /// Wall time of the sphere contacts' part of the calls so far [s]: their
  /// pairs' index and sweep (timing only: not in a checkpoint).
  double contact_seconds = 0.0;
  /// Wall time of the neighbour list's changes in the calls so far [s]: the
  /// broken links' pairs (and a deferred search's) merged into it (timing
  /// only: not in a checkpoint).
  double neighbour_seconds = 0.0;
};

/// Computes forces and torques on all particles from the intact links and
/// the contacts, using p.w as the angular velocity over the step (the
/// spheres' rotations R = exp(omega dt), for the incremental shear). Updates
/// link and contact history, breaks links (a link broken now hands over to a
/// contact in the same call). Each link's force is computed once; each
/// sphere gathers its links' forces in a fixed order, so the result is the
/// same bit for bit whatever the number of OpenMP threads.
/// (DemSolver keeps the force loop's scratch space between its steps; this
/// function sizes its own at each call.)
void compute_forces(Particles& p, Links& l, NeighbourList& nl, const Material& mat, double dt,
                    ForceCounters& c);

/// Assemblies of fewer spheres than this run their step on one thread (the
/// team's start and barriers would cost more than they save); default 2048.
void set_min_spheres_per_thread_team(std::size_t n);
std::size_t min_spheres_per_thread_team();

/// Elastic energy stored in intact links and contacts [J].
double elastic_energy(const Particles& p, const Links& l, const NeighbourList& nl,
                      const Material& mat);

/// Energy dissipated by tensile softening of all links [J].
double softening_energy(const Particles& p, const Links& l, const Material& mat);

/// Energy dissipated by the links' compaction (Material::compaction) [J].
double compaction_energy(const Links& l, const Material& mat);

/// Action of the linearised stiffness of the intact links about the current
/// positions, f = K u (the links' weights included; contacts left out):
/// u and f hold 6 values per particle, translations (n, 3) then rotations
/// (n, 3) [m, rad -> N, N m]. The relative displacement of the link's contact
/// point is (u_b - u_a) - (l_a theta_a + l_b theta_b) x n, its normal part
/// resisted by K_n, its tangential part by K_s, as the law does for small
/// increments. Used for the power-iteration estimates of the critical step.
void stiffness_action(const Particles& p, const Links& l, std::span<const double> u,
                      std::span<double> f);
/// Upper bound of the largest eigenvalue of M^-1 K of the linearised
/// assembly (its intact links, with their weights; translations and
/// rotations), by block Gershgorin on M^-1/2 K M^-1/2; the critical step is
/// 2/sqrt(bound). Contacts are left out: their stiffness is that of a link of
/// the same pair. With `rolling` (Material::rolling_friction > 0), each
/// link's pair also holds the rolling spring of its contact, k_r = K_s R*^2
/// (method.md 1.7d), in the rotation rows.
double critical_time_step(const Particles& p, const Links& l, bool rolling = false);
/// The same bound with one rigid-body contact per sphere on top of its
/// links (body.h: body_contact_stiffness): the step for a run with bodies.
/// A sphere with no intact link but the body contact still counts. The
/// rolling springs count when m.rolling_friction > 0.
double critical_time_step(const Particles& p, const Links& l, const Material& m);
/// The same with the bars' elements and bonds (bars.h: add_bar_rows): the
/// step for a reinforced run, the bar nodes' rows included.
double critical_time_step(const Particles& p, const Links& l, const Material& m, const Bars& bars);
/// The same bound without the rows of the spheres and bar nodes flagged 1
/// in `skip_spheres` and `skip_nodes` (sized as the spheres and the nodes):
/// a coupler's bound on what its multipliers leave free, the tied ones
/// being in its own estimate. Infinity when every row is left out.
double critical_time_step(const Particles& p, const Links& l, const Material& m, const Bars& bars,
                          std::span<const std::uint8_t> skip_spheres, std::span<const std::uint8_t> skip_nodes);
/// The critical time step of the assembly's links [s]: 2 / sqrt(lambda_max)
/// of its linearised link stiffness (stiffness_action: translations and
/// rotations, link weights included) over its masses and inertias, by power
/// iteration (core::max_eigenvalue, relative tolerance rtol on lambda).
/// Sharper than critical_time_step, the Gershgorin bound, which is on the
/// safe side; the coupled step (bridge::CoupledSolver) compares with it.
/// @throws std::runtime_error if no link is intact.
double particle_critical_time_step(const Particles& p, const Links& l, double rtol = 1e-6);

} // namespace dembridge::dem
