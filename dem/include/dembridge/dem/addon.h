#pragma once
/// @file addon.h
/// Add-ons of the DE step: what moves with the spheres or acts on them
/// without being spheres (rigid bodies, reinforcing bars; a coupling or a
/// halo exchange would be others). DemSolver holds a list of them and calls
/// each at fixed points of its velocity-Verlet step, in the order they were
/// added (docs/architecture.md, "Add-ons"):
///
///   start            initial forces (after the spheres')
///   begin            step start, before the first half kick (F(n) kept for reactions)
///   kick(h)          after the spheres' half kicks (both halves)
///   drift            after the spheres' drift; returns the damping's work
///   stored_energy    / spheres_removed: when spheres leave the domain
///   forces           after the spheres' forces at x(n+1)
///   reactions        prescribed motions' reactions; returns their work
///   check_finite     after each step
///   energy           their terms of the budget (DemEnergy)
///   save / load      their checkpoint group, named name()
/// The budget's fields of bodies and bars are DemEnergy's; an add-on with
/// energies of another kind adds its own terms to DemEnergy.

#include "dembridge/core/checkpoint.h"
#include "dembridge/dem/assembly.h"
#include "dembridge/dem/law.h"
#include "dembridge/dem/neighbours.h"

#include <cstdint>
#include <string>
#include <vector>

namespace dembridge::dem
{

/// Energy budget [J]: kinetic + elastic + softening + compaction + breakage + friction +
/// damping + the rigid bodies' kinetic, contact and friction energies + the
/// bars' kinetic, elastic, plastic, bond slip and broken energies + the
/// other add-ons' = initial + external_work + prescribed_work.
struct DemEnergy
{
  double initial = 0.0, kinetic = 0.0, elastic = 0.0, softening = 0.0, breakage = 0.0,
         friction = 0.0, damping = 0.0, external_work = 0.0, prescribed_work = 0.0;
  double compaction = 0.0;    ///< dissipated by the links' compaction (state: recomputed, not booked)
  double body_kinetic = 0.0;  ///< the moving bodies' kinetic energy
  double body_contact = 0.0;  ///< elastic energy of the sphere-body contacts
  double body_friction = 0.0; ///< dissipated by sliding on the bodies
  /// Carried away by the spheres that left the domain: their kinetic
  /// energy and the elastic energy of their links and contacts then.
  double removed = 0.0;
  double bar_kinetic = 0.0; ///< the bar nodes' kinetic energy
  double bar_elastic = 0.0; ///< the bars' steel and bonds (bars.h: BarEnergy) and the spheres' contacts with them
  double bar_plastic = 0.0; ///< the steel's plastic work (a state)
  double bar_opening = 0.0; ///< the bonds' radial softening (a state)
  double bar_slip = 0.0;    ///< dissipated by the bonds' slip beyond their envelope
  double bar_broken = 0.0;  ///< released by bar elements that broke and bonds that opened
  /// Held or dissipated by the other add-ons (what their energy() adds;
  /// recomputed, not booked: an add-on keeps what it dissipated in its state).
  double addons = 0.0;
  double imbalance() const
  {
    return kinetic + elastic + softening + compaction + breakage + friction + damping + body_kinetic
           + body_contact + body_friction + removed + bar_kinetic + bar_elastic + bar_plastic + bar_opening + bar_slip
           + bar_broken + addons - initial - external_work - prescribed_work;
  }
};

/// Wall time spent in each part of the steps so far [s].
struct DemTimings
{
  double forces = 0.0;      ///< compute_forces: links and sphere contacts
  double contacts = 0.0;    ///< of forces: the sphere contacts' part
  double bodies = 0.0;      ///< the rigid bodies' contacts
  double bars = 0.0;        ///< the bars' elements and bonds
  double neighbours = 0.0;  ///< neighbour-list checks and rebuilds
  double integration = 0.0; ///< kicks, drift, conditions, reactions, checks
};

/// What an add-on sees of the DE step (built by the solver at each call).
struct StepView
{
  Particles& p;
  const Links& l;
  const NeighbourList& nl;
  const Material& mat;
  const std::vector<std::uint8_t>& removed; ///< 1 for a sphere that left the domain
  double dt;                                ///< the time step [s]
  double damping;                           ///< c [1/s]: force -c m v on what the add-on moves
};

/// One add-on of the DE step (see the file's comment for when each is called).
class AddOn
{
public:
  virtual ~AddOn() = default;
  /// Its checkpoint group and its name in messages: non-empty, no '/'.
  virtual std::string name() const = 0;
  /// Where the time of its forces is counted.
  virtual double DemTimings::*time_slot() const { return &DemTimings::integration; }
  /// The forces at the start (after the spheres'), before the budget's initial energy.
  virtual void start(const StepView&) {}
  virtual void begin(const StepView&) {}
  /// v += h F / m - c h v for what it moves.
  virtual void kick(const StepView&, double /*h*/) {}
  /// x += dt v(n+1/2); returns the work of the damping over the step [J].
  virtual double drift(const StepView&) { return 0.0; }
  /// Adds the energy stored between it and the spheres [J] (removal books
  /// what leaves with the removed spheres).
  virtual void stored_energy(const StepView&, double& /*e*/) const {}
  /// The spheres newly flagged in view.removed left: their interactions with it end.
  virtual void spheres_removed(const StepView&) {}
  /// Forces at x(n+1) on itself and the spheres (added to p.f, p.t);
  /// books what it dissipates into `booked`.
  virtual void forces(const StepView&, DemEnergy& /*booked*/) {}
  /// The reactions of its prescribed motions; returns their work over the step [J].
  virtual double reactions(const StepView&) { return 0.0; }
  /// @throws std::runtime_error naming what is not finite, the time and the step.
  virtual void check_finite(double /*t*/, std::int64_t /*steps*/) const {}
  /// Sets or adds its terms of the budget.
  virtual void energy(const StepView&, DemEnergy&) const {}
  virtual void save(const checkpoint::Group&) const {}
  /// Reads what save() wrote, into an add-on set up as the one that wrote it.
  /// @throws std::runtime_error naming what differs.
  virtual void load(const checkpoint::Group&, const StepView&) {}
};

} // namespace dembridge::dem
