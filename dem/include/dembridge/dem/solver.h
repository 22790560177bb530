#pragma once
/// @file solver.h
/// The explicit DEM integrator (velocity Verlet: half kick, drift, forces,
/// half kick) with the boundary conditions of conditions.h, velocity-
/// proportional damping and the energy budget. The force loop it calls each
/// step is in forces.h.

#include "dembridge/core/stepping.h"
#include "dembridge/dem/addon.h"
#include "dembridge/dem/assembly.h"
#include "dembridge/dem/bars.h"
#include "dembridge/dem/body.h"
#include "dembridge/dem/conditions.h"
#include "dembridge/dem/forces.h"
#include "dembridge/dem/neighbours.h"
#include "dembridge/core/checkpoint.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace dembridge::dem
{

struct ForceScratch;
namespace impl
{
class BodyAddOn;
class BarAddOn;
} // namespace impl

/// What the spheres that left the domain carried away.
struct Removed
{
  std::size_t count = 0;
  double mass = 0.0;                       ///< [kg]
  std::array<double, 3> momentum{0, 0, 0}; ///< [kg m/s]
  double kinetic = 0.0;                    ///< translation and rotation [J]
  double elastic = 0.0;                    ///< in their links and contacts [J]
};

class DemSolver
{
public:
  /// @param dt time step [s], > 0; @param damping c [1/s] (force -c m v,
  /// torque -c I omega), >= 0; @param skin neighbour skin [m], > 0
  DemSolver(Particles& p, Links& l, const Material& mat, double dt, double damping, double skin);
  ~DemSolver();
  DemSolver(const DemSolver&) = delete;
  DemSolver& operator=(const DemSolver&) = delete;

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
  /// Adds a rigid body (before start()): a projectile the solver moves with
  /// the spheres' step, or a fixed wall. Returns its index.
  /// @throws std::runtime_error on a bad shape or mass, or a name in use.
  std::size_t add_body(RigidBody b);
  std::size_t bodies() const;
  /// The domain: a sphere whose centre leaves the box [lo, hi] at the end of
  /// a step is removed from the computation (fragments flying off): its
  /// links (state `removed`) and contacts end, it is held where it is, left
  /// out of the neighbour grid, and its mass, momentum and energy are booked
  /// (removed(), DemEnergy::removed). Spheres of a condition are never
  /// removed. @throws std::runtime_error unless lo < hi on every axis.
  void set_domain(const std::array<double, 3>& lo, const std::array<double, 3>& hi);
  const Removed& removed() const { return _gone; }
  /// 1 for each sphere removed from the computation.
  const std::vector<std::uint8_t>& removed_flags() const { return _removed; }
  /// Adds the reinforcing bars with their bonds (bars.h; before start(),
  /// once): their nodes move with the spheres' step (damped like them), their
  /// forces join the spheres', their energies the budget. Bonds whose sphere
  /// leaves the domain open. @throws std::runtime_error after start() or on
  /// a second call.
  void add_bars(Bars bars);
  const Bars& bars() const;
  /// The bars, to change: for a coupler that ties their nodes to another
  /// model (it corrects their velocities between begin_step and end_step,
  /// as those of the spheres). @throws std::runtime_error if there are none.
  Bars& bars_for_coupling();
  /// The listed bar nodes move at a constant velocity [m/s] (a bar pulled
  /// at its end; zero holds them); before start(). Returns the group's
  /// index for bar_reaction(). @throws naming a node out of range or moved
  /// already, or after start().
  std::size_t move_bar_nodes(std::span<const std::int32_t> nodes, const std::array<double, 3>& velocity);
  /// The force that keeps the velocity of the nodes of group `g` [N].
  /// @throws std::out_of_range for a group not made by move_bar_nodes.
  std::array<double, 3> bar_reaction(std::size_t g) const;
  /// @throws std::out_of_range for k >= bodies().
  const RigidBody& body(std::size_t k) const;
  const BodyContacts& body_contacts(std::size_t k) const;
  /// Adds an add-on (addon.h; before start()): it is called at the step's
  /// fixed points after those added before it (the rigid bodies always
  /// before the bars). @throws std::runtime_error after start(), on an
  /// empty name or one with '/', or a name in use.
  AddOn& add_addon(std::unique_ptr<AddOn> a);
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
  /// The energy guard: every `every` steps, the run stops (std::runtime_error
  /// naming the time, the step and the energies) when the energy not
  /// accounted for by the initial energy and the work done exceeds `margin`
  /// times the energy scale, initial + |work| + kinetic + elastic: an
  /// unstable integration creates energy from nothing. Stable runs keep the
  /// share below about 0.2 (the start of a loading ramp; 0.005 once under
  /// way). Every step, too, the kinetic energy (at the half step) must stay
  /// below 10 x (initial + |work|), which the budget never allows past 1 (up
  /// to the booking of prescribed velocities' work after an impulsive start,
  /// within 2). Margin 0 turns the guard off (a coupler does, and guards the
  /// coupled system's total). Default 0.5, every 100 steps.
  void set_energy_guard(double margin, std::int64_t every = 100);
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

  /// Writes the whole state at the end of a step (particles, links,
  /// neighbour pairs and their contact history, time, energies, reactions)
  /// into checkpoint group `g` (sub-groups particles, links, neighbours).
  void save(const checkpoint::Group& g) const;
  /// Reads a state written by save() into a solver set up as the one that
  /// wrote it (same assembly, conditions, time step; after start()): the
  /// run then continues bit for bit. @throws std::runtime_error naming
  /// what differs (sphere radii, link ends, conditions, time step).
  void load(const checkpoint::Group& g);

private:
  void kick(double h);
  /// What the drift sums, over the step [J].
  struct Drift
  {
    double external_work = 0.0, damping = 0.0;
    double kinetic = 0.0; ///< at the half-step velocities
  };
  /// x += dt v(n+1/2) (by multiples of the position quantum); returns the
  /// work of the external forces and of the damping over the step, and the
  /// kinetic energy.
  Drift drift();
  /// The reactions on held translations at n+1; returns their work.
  double held_reactions();
  /// @throws std::runtime_error naming the sphere if a value is not finite.
  void check_finite() const;
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
  std::unique_ptr<ForceScratch> _scratch; // the force loop's (force_loop.h, internal)
  // the add-ons in the order they are called; two of them reached by type
  std::vector<std::unique_ptr<AddOn>> _addons;
  impl::BodyAddOn* _bodies = nullptr;
  impl::BarAddOn* _bars = nullptr;
  StepView view() const; // (_p and _l are references: the view may change them)
  AddOn& insert_addon(std::unique_ptr<AddOn> a, bool first); // add_addon's checks; first: ahead of the others
  void save_addons(const checkpoint::Group& g) const;
  void load_addons(const checkpoint::Group& g);
  double _dt, _c, _t = 0.0;
  std::int64_t _steps = 0;
  core::EnergyGuard _guard;
  void check_energy() const; // the energy guard
  [[noreturn]] void energy_runaway(double kinetic, double budget) const;
  bool _in_step = false;
  bool _started = false; // start() called: no more bodies
  // the domain and the spheres that left it
  bool _domain_set = false;
  std::array<double, 3> _domain_lo{0, 0, 0}, _domain_hi{0, 0, 0};
  std::vector<std::uint8_t> _removed, _in_condition;
  Removed _gone;
  void remove_escaped();
  DemEnergy _e;
  DemTimings _time;
};

} // namespace dembridge::dem
