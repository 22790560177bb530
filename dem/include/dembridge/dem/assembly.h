#pragma once
/// @file assembly.h
/// A bonded sphere assembly: particles (structure of arrays), cohesive links
/// and the concrete material. docs/method.md sections 1.1-1.4.

#include "dembridge/dem/law.h"
#include "dembridge/dem/stiffness.h"

#include <algorithm>
#include <cstdint>
#include <numbers>
#include <span>
#include <vector>

namespace dembridge::dem
{

/// Concrete as the DE model sees it (SI units; angles in degrees).
struct Material
{
  double youngs_modulus = 30e9;  ///< macroscopic target E [Pa] (enters eq. [1])
  double poisson_ratio = 0.2;    ///< macroscopic target nu [-] (enters eq. [1])
  double density = 2400.0;       ///< bulk density of the concrete [kg/m^3]
  MicroMacro micro{0.2, 1.0, 1.0}; ///< alpha, beta, gamma of eq. [1] (identify them!)
  double tensile = 3.3e6;        ///< local tensile strength T [Pa]
  double cohesion = 4.4e6;       ///< cohesion C0 [Pa]
  double zeta = 10.0;            ///< softening factor [-]
  double phi_i_deg = 30.0;       ///< internal friction angle [degree]
  double phi_c_deg = 30.0;       ///< contact friction angle [degree]
  /// Tresca limit of the contacts' friction (docs/method.md section 1.7):
  /// the largest shear stress a contact carries, over its S_int [Pa]; 0 =
  /// none (Coulomb friction at any pressure).
  double contact_shear_limit = 0.0;
  /// Crack closure (docs/method.md 1.7): the share c in [0, 1] of a broken
  /// link's gap at rest, D_init - (R_a + R_b), at which its spheres meet
  /// again: they touch from R_a + R_b + c (D_init - R_a - R_b), with the
  /// link's K_n and K_s. 1: where the link was at rest (a link that breaks
  /// in shear while compressed keeps its normal force, as a contact); 0, the
  /// default: off (they touch at R_a + R_b, with the contacts' stiffnesses).
  double crack_closure = 0.0;
  /// Rolling resistance of the contacts (docs/method.md section 1.7d): the
  /// coefficient mu_r of the cap |M| <= mu_r R* F_c on the rolling moment,
  /// R* = R_a R_b / (R_a + R_b) [-]; 0 = none (the spheres roll freely).
  double rolling_friction = 0.0;
  /// Strain-rate effect on the links' strength (docs/method.md section
  /// 1.6b): 0 = none; else the concrete's compressive strength f_c [Pa] of
  /// the Malvar-Ross law, whose factor of the link's own tensile strain rate
  /// multiplies its T and C0 while it is elastic.
  double rate_fc = 0.0;
  /// The strain rate above which the rate factor stops growing [1/s]; 0 =
  /// no cap. Malvar and Ross fitted their law to data up to ~100 /s; the
  /// links near a projectile see 1e3-1e4 /s, where the law's cube root
  /// would give factors above 15.
  double rate_max = 0.0;
  /// Whether the rate factor multiplies C0 as well as T (true), or T alone
  /// (false: the shear strength stays the quasi-static one).
  bool rate_cohesion = true;
  /// Time constant of the low-pass filter on each link's strain rate before
  /// the factor is taken from it [s], in [0, 1]: r_f += min(1, dt / tau)
  /// (r - r_f); 0 = no filter (the factor follows the rate of every step).
  double rate_filter = 0.0;
  /// Whether a link's factor grows only while its spheres are, on the whole,
  /// stretched: the sum of K_n (D - D_init) D over both spheres' intact
  /// links, at the step's positions, is positive (docs/method.md 1.6b). So
  /// the tensile rate law acts where the material is pulled, not where it
  /// fails under compression.
  bool rate_mean_tension = false;
  /// Whether a link's factor follows the factor of its current rate (true)
  /// instead of the largest one so far (false), while the link is elastic
  /// (docs/method.md 1.6b): with rate_mean_tension it falls back to 1 while
  /// the spheres are compressed. It never falls below what the link already
  /// holds: its largest elongation so far (K_n delta_max <= S_int T factor)
  /// and, with rate_cohesion, its stored shear force (|F_s| <= S_int C0
  /// factor). So a fast wave lifts a link's strength only while it lasts.
  bool rate_current = false;
  /// Compaction of the links in compression (docs/method.md section 1.6c):
  /// off while compaction.onset is 0.
  CompactionLaw compaction;
  /// @throws std::runtime_error naming the value and its allowed range.
  void validate() const;
  /// The law's parameters for a pair of radii at initial distance d_init.
  LinkLaw law(double ra, double rb, double d_init) const;
};

/// Particles as structure of arrays; vectors are (n, 3) row-major.
struct Particles
{
  std::vector<double> x;        ///< position [m]
  std::vector<double> x0;       ///< reference position (displacement = x - x0) [m]
  std::vector<double> v;        ///< velocity [m/s]
  std::vector<double> w;        ///< angular velocity [rad/s]
  std::vector<double> f;        ///< force [N]
  std::vector<double> t;        ///< torque [N m]
  std::vector<double> r;        ///< radius [m]
  std::vector<double> m;        ///< mass [kg]
  std::vector<double> inertia;  ///< moment of inertia 2/5 m r^2 [kg m^2]
  /// Energy weight of each sphere (1 - eta of the coupling); contacts use the
  /// mean of their two spheres'. Empty: 1 everywhere.
  std::vector<double> weight;
  /// Position quantum q [m] (make_particles): every coordinate is a
  /// multiple of q, twice the ulp of the largest coordinate (2.2e-16 m
  /// when it is in [0.5, 1) m), and the solver moves spheres by
  /// multiples of q. Differences of positions
  /// are then exact, so a uniform translation changes no branch between
  /// spheres by even one bit (rounding x + v dt sphere by sphere would, each
  /// position in its own binade). 0: positions as given, ordinary rounding.
  double quantum = 0.0;
  std::size_t size() const { return r.size(); }
};

/// The position quantum of a set of coordinates: 2^(e - 52) with 2^e >
/// max |x|. Sums of multiples of it stay exact while |x| < 2^(e+1), more
/// than twice the largest coordinate (room for the assembly to move as far
/// again); 0 if every coordinate is 0.
double position_quantum(std::span<const double> x);

/// Spheres of solid density rho_s = rho_bulk / packing_fraction (docs/method.md section 1.1).
/// The centres are rounded to multiples of position_quantum(x) (each moves
/// by at most q/2, an ulp of the largest coordinate).
/// @param x centres (n, 3) [m]; @param r radii (n) [m], > 0
/// @throws std::runtime_error on a radius <= 0 or a non-finite coordinate.
Particles make_particles(std::span<const double> x, std::span<const double> r, double rho_bulk,
                         double packing_fraction);

/// State of a link.
enum class LinkState : std::uint8_t
{
  intact = 0,
  broken_tension = 1,
  broken_shear = 2,
  removed = 3 ///< one of its spheres left the domain (DemSolver::set_domain)
};

/// Cohesive links as structure of arrays, each pair ordered a < b, the list
/// sorted by (a, b).
struct Links
{
  std::vector<std::int32_t> a, b;
  std::vector<double> d0;         ///< initial distance D_init [m]
  std::vector<double> kn, ks;     ///< stiffnesses [N/m]
  std::vector<double> fs;         ///< shear force on b, (n, 3) [N]
  std::vector<double> n;          ///< unit normal a -> b at the last step, (n, 3)
  std::vector<double> delta_max;  ///< largest elongation reached [m]
  std::vector<LinkState> state;
  /// Energy weight of each link (1 - eta at its mid-point, bridging domain):
  /// it multiplies the link's forces and energies. Empty: 1 everywhere.
  std::vector<double> weight;
  /// Strength factor of each link (the rate effect, Material::rate_fc): its
  /// T (and C0, Material::rate_cohesion) are multiplied by it; >= 1, the largest dynamic increase
  /// factor of the link's strain rate while elastic, then fixed. Empty: 1
  /// everywhere (DemSolver sizes it when the material has a rate effect).
  std::vector<double> strength;
  /// Filtered tensile strain rate of each link [1/s] (Material::rate_filter
  /// > 0; empty otherwise): the rate its strength factor is taken from.
  std::vector<double> rate;
  /// Largest compressive strain -delta / D_init each link reached (the
  /// compaction's history, Material::compaction). Empty: no compaction
  /// (DemSolver sizes it when the material compacts).
  std::vector<double> compaction;
  /// Each link's compaction onset strain under a pressure gate
  /// (CompactionLaw::pressure > 0; empty otherwise): the law's onset, raised
  /// with the link's compressive strain while the gate is shut and the link
  /// has not started compacting.
  std::vector<double> compaction_onset;
  std::size_t size() const { return a.size(); }
  std::size_t count(LinkState s) const;
};

/// Link k's compaction law: the material's, from the link's own onset
/// under a pressure gate (Links::compaction_onset).
inline CompactionLaw link_compaction(const Links& l, std::size_t k, const CompactionLaw& c)
{
  return l.compaction_onset.empty() ? c : c.from(l.compaction_onset[k]);
}

/// Interaction surface S_int = pi min(R_a, R_b)^2 of two valid radii [m^2]
/// (interaction_surface without its checks, for the force loop).
inline double pair_surface(double ra, double rb)
{
  const double r = std::min(ra, rb);
  return std::numbers::pi * r * r;
}

/// S_int of link k (not stored: the radii give it, 8 bytes less per link).
inline double link_surface(const Particles& p, const Links& l, std::size_t k)
{
  return pair_surface(p.r[l.a[k]], p.r[l.b[k]]);
}

/// Links between every pair with D_init <= lambda (R_a + R_b), lambda >= 1,
/// stiffnesses from equation [1]. @throws std::runtime_error if lambda < 1.
Links create_links(const Particles& p, double lambda, const Material& mat);

/// Spheres whose intact links leave them a motion of zero energy: a link
/// acts at one contact point (forces only, no moment), so a sphere whose
/// contact points all lie on one line can turn about that line -- one link
/// (turning about its point), two links (about the line through their two
/// points), or more on one line -- with its neighbours at rest, and, once set
/// turning, drifts steadily. (A free-surface sphere left with two close
/// neighbours is the usual case.) No sphere has none: ids of those with no
/// intact link are included. Contact points are at l_a = D R_a / (R_a + R_b)
/// from the centre; "on one line" within `tol` of the largest distance
/// between them, relative.
std::vector<std::int32_t> floppy_spheres(const Particles& p, const Links& l, double tol = 1e-6);

/// Number of pairs with D <= lambda (R_a + R_b) for each lambda in `lambdas`.
std::vector<std::size_t> count_pairs(std::span<const double> x, std::span<const double> r,
                                     std::span<const double> lambdas);

/// Smallest lambda (to 1e-4) giving a mean number of links per sphere of at
/// least `target` (2 x pairs / spheres). With `counted` (one flag per
/// sphere), the mean is over the flagged spheres only, their links to any
/// sphere counted: flag the bulk (e.g. spheres 2 Rmax or more inside the
/// boundary, see dem::inside) so that the spheres at a face, which miss
/// neighbours, do not raise lambda, and packings of any size get the same
/// bulk coordination. @throws if target is unreachable with lambda <= 2 or
/// no sphere is flagged.
double lambda_for_mean_links(std::span<const double> x, std::span<const double> r, double target,
                             std::span<const std::uint8_t> counted = {});

} // namespace dembridge::dem
