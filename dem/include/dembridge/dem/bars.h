#pragma once
/// @file bars.h
/// Reinforcing bars in the DE zone (docs/method.md section 1.15): each bar a
/// chain of two-node axial elements of elastic-plastic steel with elastic
/// bending springs at the nodes between them (a rotation-free rod), its
/// nodes moved by the spheres' velocity Verlet step, and tied to the
/// surrounding spheres by bonds: a bond stress-slip law along the bar (fib
/// Model Code 2010, pull-out) and a radial spring that opens in tension.
/// Structure of arrays; the laws are pure functions.

#include "dembridge/dem/assembly.h"
#include "dembridge/dem/body.h"
#include "dembridge/dem/neighbours.h"
#include "dembridge/dem/packing.h"

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace dembridge::dem
{

/// Bar steel: elastic, then plastic with linear isotropic hardening, broken
/// at a rupture strain (SI units).
struct Steel
{
  double youngs_modulus = 200e9; ///< E_s [Pa], > 0
  double density = 7850.0;       ///< [kg/m^3], > 0
  double yield = 500e6;          ///< f_y [Pa], > 0
  double hardening = 1e9;        ///< H = d sigma / d (plastic strain) [Pa], >= 0
  double rupture_strain = 0.08;  ///< eps_u: a bar element breaks when its strain reaches it [-], > f_y / E_s
  /// @throws std::runtime_error naming the value and its allowed range.
  void validate() const;
};

/// The bond between a bar and the concrete around it.
/// Along the bar, the bond stress follows the fib Model Code 2010 envelope of
/// the slip s (pull-out failure):
///   tau = K0 s                                  s <= s0 (linear start)
///   tau = tau_max (s / s1)^alpha                s0 < s <= s1
///   tau = tau_max                               s1 < s <= s2
///   tau = tau_max - (tau_max - tau_f)(s - s2) / (s3 - s2)   s2 < s <= s3
///   tau = tau_f = tau_f_ratio tau_max           s > s3
/// with K0 = tau_max (s0 / s1)^alpha / s0 (the power law's slope is infinite
/// at s = 0). Unloading and reloading follow K0 (bond_shear).
/// Across it, a radial spring of stiffness k_r per unit bar surface:
/// linear in compression; in tension the concrete's law of a link (law.h:
/// link_normal_force) with the peak stress `opening` and a linear softening
/// to zero at the radial gap `opening_gap`, unloading on the secant. At
/// that gap the bond opens: no force any more, along the bar either.
struct BondLaw
{
  double tau_max = 13.7e6;   ///< [Pa] (fib: 2.5 sqrt(f_cm[MPa]), good bond)
  double s0 = 0.01e-3;       ///< end of the linear start [m], in (0, s1)
  double s1 = 1e-3;          ///< [m]
  double s2 = 2e-3;          ///< [m], >= s1
  double s3 = 10e-3;         ///< [m] (fib: the clear rib spacing), > s2
  double alpha = 0.4;        ///< [-], in (0, 1]
  double tau_f_ratio = 0.4;  ///< tau_f / tau_max [-], in [0, 1]
  double radial_stiffness = 1e13; ///< k_r [Pa/m], > 0
  double opening = 3e6;      ///< radial tensile strength of the interface [Pa], > 0
  double opening_gap = 0.1e-3; ///< radial gap at which the bond opens [m], > opening / k_r
  /// @throws std::runtime_error naming the value and its allowed range.
  void validate() const;
  double k0() const; ///< K0 [Pa/m]
};

/// The envelope tau(|s|) of the bond law, >= 0 [Pa].
double bond_envelope(double slip, const BondLaw& b);

/// State of a steel element after a strain update.
struct SteelState
{
  double stress = 0.0;  ///< [Pa] (tension > 0)
  double plastic = 0.0; ///< plastic strain eps_p [-]
  double alpha = 0.0;   ///< accumulated plastic strain [-]
  bool broken = false;  ///< the strain reached the rupture strain
};
/// Return mapping of the steel law at total strain eps from the plastic
/// strain eps_p and accumulated plastic strain alpha of the last step:
/// sigma = E (eps - eps_p), |sigma| <= f_y + H alpha.
SteelState steel_update(double strain, double plastic, double alpha, const Steel& s);
/// Plastic work per unit volume, f_y alpha + H alpha^2 / 2 [J/m^3] (a state
/// of alpha: the return mapping's sigma d eps_p = (f_y + H alpha) d alpha).
double steel_plastic_work(double alpha, const Steel& s);

/// Bond stress after a slip increment: the trial tau + K0 (s - s_old),
/// capped at +-envelope(largest |s| so far, this step's included). Returns
/// {tau, largest |s|, energy dissipated per unit area: the mean stress's
/// work less the elastic gain, (tau_old + tau) (s - s_old) / 2 - (tau^2 -
/// tau_old^2) / (2 K0)}.
std::array<double, 3> bond_shear(double tau_old, double slip_old, double slip, double slip_max,
                                 const BondLaw& b);

/// A bar as given: a polyline, its diameter and its laws.
struct BarLine
{
  std::vector<std::array<double, 3>> points; ///< >= 2 points [m]
  double diameter = 0.0;                     ///< [m], > 0
  std::uint8_t steel = 0;                    ///< index into Bars::steels
  std::uint8_t bond = 0;                     ///< index into Bars::bond_laws
};

/// Bars and their bonds, as structure of arrays.
struct Bars
{
  std::vector<Steel> steels;      ///< table of steels
  std::vector<BondLaw> bond_laws; ///< table of bond laws
  // nodes: (n, 3) row-major
  std::vector<double> x, x0, v, f, m;
  std::vector<std::uint8_t> held; ///< 1: the node keeps its velocity (a prescribed motion)
  std::vector<double> node_radius, node_k; ///< a node's bar radius [m] and its body-contact stiffness [N/m]
  // elements
  std::vector<std::int32_t> a, b, line;   ///< end nodes; the polyline it belongs to
  std::vector<double> area, l0;           ///< cross-section [m^2], rest length [m]
  std::vector<double> plastic, alpha;     ///< eps_p, accumulated plastic strain
  std::vector<double> force, length;      ///< axial force [N] and length [m] at the last step
  std::vector<std::uint8_t> steel, bond_law, broken; ///< indices into the tables; 1 once broken
  // bending springs at the nodes inside a straight run of a bar: energy
  // k (1 - t1 . t2), t1 and t2 the unit directions of the elements
  // (a -> b) and (b -> c), k = E I / ((l1 + l2) / 2)
  std::vector<std::int32_t> bend_a, bend_b, bend_c, bend_e1, bend_e2;
  std::vector<double> bend_k;
  std::vector<std::uint8_t> bend_kept; ///< 0 once an element of the spring broke and its energy was released
  // bonds: sphere to a material point of an element
  std::vector<std::int32_t> sphere, element;
  std::vector<double> xi;                 ///< the point's place along the element, in [0, 1]
  std::vector<double> surface;            ///< bar surface the bond carries, pi d l [m^2]
  std::vector<double> axial0, radial0;    ///< the sphere's axial and radial offsets at creation [m]
  std::vector<double> tau, slip, slip_max; ///< bond stress [Pa], slip [m] (sphere along the bar), largest |slip|
  std::vector<double> gap, gap_max;        ///< radial gap [m] (> 0 apart) at the last step, the largest so far
  std::vector<std::uint8_t> open;          ///< 1: the bond opened (no force any more)
  /// true: spheres beyond their bonds are pushed off the bars (BarContacts;
  /// the packing leaves the bars room). false: embedded bars, whose
  /// cylinders the concrete's spheres fill: the bars meet the spheres only
  /// through their bonds (create_bonds bonds each sphere within reach, those
  /// a bar crosses among them, to its nearest element). In the checkpoint.
  bool sphere_contacts = true;
  std::size_t nodes() const { return m.size(); }
  std::size_t elements() const { return a.size(); }
  std::size_t bonds() const { return sphere.size(); }
};

/// Lays out the bars: each polyline cut into elements no longer than
/// `element_length`, nodes with lumped masses (rho A l / 2 per element end).
/// @throws std::runtime_error naming the bar: fewer than 2 points, a zero
///   segment, a diameter <= 0, an unknown steel or bond index, bad laws,
///   element_length <= 0; and two bars closer than the sum of their radii.
Bars make_bars(std::span<const BarLine> lines, std::vector<Steel> steels,
               std::vector<BondLaw> bond_laws, double element_length);

/// Distance from point x to the axis of element e (clamped to the segment),
/// and the place of the nearest point, xi in [0, 1].
std::array<double, 2> distance_to_element(const Bars& bars, std::size_t e, const double* x);

/// 1 for each sphere (centre c, radius r) that overlaps a bar: closer to an
/// axis than r + the bar's radius - tolerance. A packing drops them to leave
/// the bars room.
std::vector<std::uint8_t> spheres_on_bars(const Bars& bars, std::span<const double> centres,
                                          std::span<const double> radii, double tolerance = 0.0);

/// The region less the bars' cylinders, for generate_packing: its signed
/// distance is max(region's, -(distance to the nearest axis - bar radius)),
/// the bars found through a grid of cells; farther than 6 rmax + the bar
/// radius from every bar (rmax: the packing's largest radius), the bars'
/// part is a lower bound of at least 6 rmax, which no packing step looks
/// past. For fill_boundary (packing.h) after the spheres on the bars are
/// removed: the spheres it adds line the bars.
Region region_without_bars(const Region& region, const Bars& bars, double rmax);

/// Makes room for the bars in a packing of `region`: removes the spheres
/// that overlap a bar (spheres_on_bars) and lines the bars' surfaces with
/// spheres tangent to them (fill_boundary on region_without_bars, radii in
/// the packing's range). Returns {removed, added}.
std::array<std::size_t, 2> make_room_for_bars(Packing& packing, const Region& region, const Bars& bars);

/// A packing of the concrete round the bars and its solid fraction.
struct ConcretePacking
{
  Packing packing;
  std::size_t removed = 0;   ///< spheres left on a bar, removed (make_room_for_bars)
  std::size_t added = 0;     ///< spheres added tangent to the bars
  double solid_fraction = 0; ///< the spheres' volume over the concrete's: the region's less the bars' inside it
};

/// Packs `region` round the bars (docs/method.md 1.15): generate_packing on
/// the region less the bars' cylinders, so that the packing's relaxation
/// fills up to the bars' surfaces, then make_room_for_bars for the few
/// spheres left on a bar. The solid fraction is taken over the concrete's
/// volume (concrete_fraction). options.mean_radius must be > 0 (it bounds
/// the largest radius, the reach of region_without_bars).
ConcretePacking pack_around_bars(const Region& region, const Bars& bars, const PackingOptions& options);

/// The spheres' volume over the concrete's: the region's volume less the
/// bars' elements whose midpoint lies inside it (area x length).
double concrete_fraction(const Packing& packing, const Region& region, const Bars& bars);

/// Bonds every sphere whose surface lies within `reach` of a bar's surface
/// (centre closer to the axis than radius + bar radius + reach) to the
/// nearest point of the nearest element. Each element's surface pi d l0 is
/// shared equally among its bonds. Returns the number of bonds.
std::size_t create_bonds(Bars& bars, const Particles& p, double reach);

/// Energies of the bars [J].
struct BarEnergy
{
  double kinetic = 0.0; ///< of the nodes
  double elastic = 0.0; ///< steel sigma^2 / (2 E) A l0, bond tau^2 / (2 K0) and k_r g^2 / 2 per surface
  double plastic = 0.0; ///< steel plastic work (a state of alpha)
  double opening = 0.0; ///< the bonds' radial softening (a state of the largest gap)
};

/// The radial law of bond law b on a bond of surface S as a link's law
/// (kn = k_r S, S_int = S, T = opening, zeta from opening_gap).
LinkLaw radial_law(const BondLaw& b, double surface);
BarEnergy bar_energy(const Bars& bars, const Particles& p);

/// What one force call dissipated or released [J].
struct BarWork
{
  double slip = 0.0;   ///< bond slip beyond the envelope
  double broken = 0.0; ///< released by elements that broke and bonds that opened
  bool changed = false; ///< an element broke or a bond opened (the contacts may change: BarContacts)
};

/// Axial forces of the elements and the bonds' forces, from the positions:
/// adds to bars.f (zeroed first) and p.f. With advance the histories move
/// on (plastic strain, rupture, bond stress, opening); without, the forces
/// of the current state are evaluated (start of a run). A bond whose sphere
/// is flagged in `gone` (removed from the computation; may be empty) opens.
BarWork bar_forces(Bars& bars, Particles& p, bool advance, std::span<const std::uint8_t> gone = {});

/// The contact of the bar nodes with a rigid body (body.h): a node is a
/// sphere of its bar's radius r, its overlap delta = r - phi(x) gives the
/// normal force K delta along the body's outward normal, K = E_s pi r (the
/// sphere-wall stiffness of body.h with the steel's modulus); frictionless.
/// The body takes the opposite force and its moment about its centre of
/// mass. Adds to bars.f and to b.f, b.t (call after body_forces and
/// bar_forces, which reset them).
void bar_body_forces(Bars& bars, RigidBody& b);
/// The elastic energy of those contacts, K delta^2 / 2 summed [J].
double bar_body_energy(const Bars& bars, const RigidBody& b);

/// The contacts of spheres with the bars beyond their bonds: a sphere with
/// no intact bond whose surface overlaps a bar, delta = r + r_b - rho > 0
/// (rho: its centre's distance to the axis of the bar's nearest unbroken
/// element, r_b the bar's radius), is pushed out along the normal from the
/// axis through its centre with K delta. K is the stiffness of a sphere on a
/// rigid body (body_contact_stiffness: the steel is far stiffer than the
/// concrete). Frictionless, so no history. The element's nodes take the
/// opposite force in the shares 1 - xi and xi of the nearest point, so the
/// forces sum to zero with zero moment and are the gradient of K delta^2 / 2.
/// Per sphere and bar (polyline) only the nearest element acts: a sphere
/// at a node between two elements is pushed once. A sphere with an intact
/// bond is left to its bond's radial spring on that bar, and touches the
/// others. Embedded bars (Bars::sphere_contacts false) have no such
/// contacts: the functions below find none, add nothing and count zero,
/// whatever pairs BarContacts holds.
struct BarGridCache; // the elements' grid (bar_contacts.cpp)
struct BarContacts
{
  std::vector<std::int32_t> sphere, element; ///< candidate pairs, by sphere then element
  std::vector<double> x_refresh;             ///< the bar nodes at the last refresh (3 per node)
  std::vector<double> x_spheres;             ///< the spheres then (3 per sphere)
  bool refreshed = false;
  std::vector<std::int32_t> bonded;          ///< scratch: 1 + the bar a sphere has an intact bond to, or 0
  /// The elements' grid for the refresh, kept while no node has moved more
  /// than its margin since it was built (derived: not in the checkpoint).
  std::shared_ptr<const BarGridCache> grid;
};
/// Refreshes the candidate pairs, every sphere not `gone` whose centre
/// lies within r + r_b + 2 skin of an element's axis (skin: the neighbour
/// list's), when the largest move of a sphere since the last refresh plus
/// the largest move of a bar node reaches 2 skin: until then no other pair
/// can touch.
void refresh_bar_contacts(const Bars& bars, const Particles& p, BarContacts& c, const NeighbourList& nl,
                          std::span<const std::uint8_t> gone = {});
/// Adds the contacts' forces to p.f and bars.f (after bar_forces, which
/// resets bars.f; the bonds' state of this step decides which spheres are
/// bonded).
void bar_contact_forces(Bars& bars, Particles& p, BarContacts& c, const Material& m,
                        std::span<const std::uint8_t> gone = {});
/// The contacts' elastic energy, K delta^2 / 2 summed [J].
double bar_contact_energy(const Bars& bars, const Particles& p, const BarContacts& c, const Material& m,
                          std::span<const std::uint8_t> gone = {});
/// Adds the bars' Gershgorin rows (of M^-1/2 K M^-1/2, [1/s^2]) to the
/// spheres' translation rows (their bonds) and fills the nodes' (elements
/// and bonds, and one body contact per node): critical_time_step(p, l, m,
/// bars) takes 2 / sqrt(largest). A bond counts with the larger of its own
/// stiffness and its sphere's contact with the bar (BarContacts), which
/// takes over once the bond opens.
void add_bar_rows(const Bars& bars, const Particles& p, const Material& m, std::vector<double>& sphere_rows,
                  std::vector<double>& node_rows);

} // namespace dembridge::dem
