#pragma once
/// @file solver.h
/// The DEM force loop (it only calls the laws of law.h) and the explicit
/// integrator (velocity Verlet: half kick, drift, forces, half kick) with
/// boundary conditions on particle sets, velocity-proportional damping and
/// the energy budget. OpenMP threads over links and spheres; results do not
/// depend on the thread count.

#include "dembridge/dem/assembly.h"
#include "dembridge/dem/neighbours.h"

#include <array>
#include <climits>
#include <cstdint>
#include <utility>
#include <vector>
#include <functional>
#include <span>
#include <string>

namespace dembridge::dem
{

/// Energy dissipated or stored in the force loop since the start [J].
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
};

/// How the items of the force loop (links, or neighbour pairs; sorted by
/// (a, b)) are shared between T threads: thread t owns the spheres
/// [n t / T, n (t + 1) / T) and computes the items whose a it owns, adding
/// each item's force to both spheres. Items whose b belongs to a later
/// thread ("cross" items) are computed first into a buffer, which their b
/// sphere reads before its own items: every sphere then sums its items in the
/// same order (b side in item order, then a side) whatever T is.
struct SweepIndex
{
  std::vector<std::int32_t> first;      ///< items with a = i: [first[i], first[i + 1])
  std::vector<std::size_t> bounds;      ///< spheres of thread t: [bounds[t], bounds[t + 1]) (T + 1)
  std::vector<std::int32_t> cross_first; ///< first buffer slot of each thread (T + 1)
  std::vector<std::int32_t> in_first, in; ///< slots of the cross items into sphere b (CSR)
  std::vector<std::int32_t> cross_i, cross_k; ///< per slot: the cross item's sphere a and item
  std::vector<double> out;              ///< per cross item: force on b (3), torque factor q (3)
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
  const std::int32_t* links_for = nullptr; ///< the link array the index was built for
  std::size_t links_size = 0, pairs_version = SIZE_MAX;
  std::size_t bytes() const;
};

/// Computes forces and torques on all particles from the intact links and
/// the contacts, using p.w as the angular velocity over the step (the
/// spheres' rotations R = exp(omega dt), for the incremental shear). Updates
/// link and contact history, breaks links (a link broken now hands over to a
/// contact in the same call). Each link's force is computed once; each
/// sphere gathers its links' forces in a fixed order, so the result is the
/// same bit for bit whatever the number of OpenMP threads.
void compute_forces(Particles& p, Links& l, NeighbourList& nl, const Material& mat, double dt,
                    ForceCounters& c, ForceScratch& scratch);
/// Same, with its own scratch space.
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
/// assembly (links and current contacts; translations and rotations), by
/// block Gershgorin on M^-1/2 K M^-1/2; the critical step is 2/sqrt(bound).
double critical_time_step(const Particles& p, const Links& l);

using History = std::function<double(double)>;

enum class MotionKind
{
  fixed,        ///< translations and rotations held at zero velocity
  velocity,     ///< the chosen components follow value(t) [m/s]
  displacement  ///< the chosen components follow x0 + value(t) [m]
};

/// A kinematic condition on a set of particles.
struct ParticleMotion
{
  std::string name;
  std::vector<std::int32_t> ids;
  MotionKind kind = MotionKind::fixed;
  std::array<bool, 3> components{true, true, true}; ///< for velocity/displacement
  History value;
  /// For velocity/displacement: the set follows value(t) as a plate hinged
  /// at its centroid: for each chosen component, the set's mass-weighted mean
  /// follows value(t) and its rotations normal to that component stay free
  /// (the component is an affine function of position, its slopes fitted to
  /// the spheres' own velocities as for ParticleForce::plate_rotates).
  /// Its spheres are kicked by their forces like free ones, then moved as
  /// the plate; its reaction is the force on the plate's mean motion. It
  /// shares no sphere with another condition or a loading plate. Without it
  /// each sphere follows value(t): the set cannot rotate.
  bool rotates = false;
  /// A hinged set: it rotates and moves (a fixed set holds everything).
  bool hinged() const { return rotates && kind != MotionKind::fixed; }
};

/// External force on each particle of a set: direction * value(t) [N].
struct ParticleForce
{
  std::string name;
  std::vector<std::int32_t> ids;
  std::array<double, 3> direction{1.0, 0.0, 0.0};
  History value;
  /// Load through a rigid plate: the spheres' velocity components along
  /// `direction` are made equal (their mass-weighted mean, so momentum is
  /// kept) after every kick, so the set moves as one along the load and the
  /// total force spreads as a stiff loading plate spreads it, whatever each
  /// sphere's bonds (an equal share per sphere would push a loosely bonded
  /// surface sphere far out). Other components stay free. The set must not
  /// share spheres with a kinematic condition.
  bool plate = false;
  /// With `plate`: the plate may also rotate, as one loaded through a ball
  /// joint: the velocity components along `direction` are made an affine
  /// function of position, v_d = V + g . (x - c) with g normal to the load
  /// (the rigid rotations' share of v_d), fitted by mass-weighted least
  /// squares (so momentum and the moments about the centroid c are kept).
  /// The plate then carries the load and no moment. Without it, the plate
  /// only translates: it holds its own rotation, and so the end of a bent
  /// bar (a plate of end spheres a centimetre deep in x clamps that layer's
  /// rotation and takes ~2 % of the moment).
  bool plate_rotates = false;
};

/// Energy budget [J]: kinetic + elastic + softening + breakage + friction +
/// damping = initial + external_work + prescribed_work.
struct DemEnergy
{
  double initial = 0.0, kinetic = 0.0, elastic = 0.0, softening = 0.0, breakage = 0.0,
         friction = 0.0, damping = 0.0, external_work = 0.0, prescribed_work = 0.0;
  double imbalance() const
  {
    return kinetic + elastic + softening + breakage + friction + damping - initial
           - external_work - prescribed_work;
  }
};

/// Wall time spent in each part of the steps so far [s].
struct DemTimings
{
  double forces = 0.0;      ///< compute_forces
  double neighbours = 0.0;  ///< neighbour-list checks and rebuilds
  double integration = 0.0; ///< kicks, drift, conditions, reactions, checks
};

class DemSolver
{
public:
  /// @param dt time step [s], > 0; @param damping c [1/s] (force -c m v,
  /// torque -c I omega), >= 0; @param skin neighbour skin [m], > 0
  DemSolver(Particles& p, Links& l, const Material& mat, double dt, double damping, double skin);

  /// Selects particles whose centre satisfies pred. @throws naming `what` if none.
  static std::vector<std::int32_t>
  select(const Particles& p, const std::function<bool(const std::array<double, 3>&)>& pred,
         const std::string& what);

  void add_motion(ParticleMotion m);
  /// Releases the condition `name` (e.g. a loaded end let go): its spheres
  /// move freely from the next step on, unless another condition holds them.
  /// @throws std::runtime_error if no condition has that name.
  void remove_motion(const std::string& name);
  void add_force(ParticleForce f);
  /// Computes the initial forces and energy (call after the conditions).
  void start();
  /// One step (begin_step then end_step). @throws std::runtime_error naming
  /// the particle and time if a position or velocity becomes NaN or infinite.
  void step();
  /// First half of a step: velocities become v(n+1/2) (those that move the
  /// spheres); a coupling may correct them (Particles::v) before end_step().
  void begin_step();
  /// Second half: positions, neighbours, forces, v(n+1), bookkeeping.
  void end_step();

  DemEnergy energy() const;
  /// Sum of the reaction forces the condition `name` applies [N].
  std::array<double, 3> reaction(const std::string& name) const;
  double time() const { return _t; }
  std::int64_t steps() const { return _steps; }
  double dt() const { return _dt; }
  void set_damping(double c);
  double damping() const { return _c; } ///< [1/s]
  /// From now on, track the cohesion demand (ForceCounters::cohesion_demand).
  void track_cohesion_demand() { _counters.track_cohesion = true; }
  /// The cohesion demand so far [Pa] (0 unless tracked).
  double cohesion_demand() const { return _counters.cohesion_demand; }
  const NeighbourList& neighbours() const { return _nl; }
  /// Bytes held by the solver's own arrays and scratch (the neighbour list
  /// included; the particles and links are the caller's).
  std::size_t bytes() const;
  const DemTimings& timings() const { return _time; }

private:
  void kick(double h);
  void update_held();
  void tie_plates(); // loading plates: one velocity along the load (and rotations, if free)
  Particles& _p;
  Links& _l;
  Material _mat;
  NeighbourList _nl;
  ForceCounters _counters;
  std::vector<ParticleMotion> _motions;
  std::vector<ParticleForce> _forces;
  std::vector<std::uint8_t> _held;      // per particle and component: 1 if prescribed
  std::vector<std::int32_t> _held_dofs; // 3 i + k of held translations (sorted); _fold,
                                        // _vold, _reac: one value per held dof
  std::vector<double> _fext, _fext_old, _reac, _fold, _vold, _part;
  // per motion: a hinged plate's reaction and its last half-step mean velocity
  std::vector<std::array<double, 3>> _motion_reac, _motion_vprev;
  // a hinged condition's spheres moved as a plate whose mean follows the
  // history: at the half step (begin, with its reaction and work), or at
  // the full step
  void move_hinged(std::size_t motion, double t_half, double t_new, bool begin);
  ForceScratch _scratch;
  double _dt, _c, _t = 0.0;
  std::int64_t _steps = 0;
  bool _in_step = false;
  DemEnergy _e;
  DemTimings _time;
};

} // namespace dembridge::dem
