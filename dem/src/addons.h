#pragma once
// The two add-ons of the DE step that dem provides (addon.h): the rigid
// bodies (projectiles and walls) and the reinforcing bars. Internal to dem:
// DemSolver's add_body, add_bars and their accessors reach them.
#include "dembridge/dem/addon.h"
#include "dembridge/dem/bars.h"
#include "dembridge/dem/body.h"

#include <array>
#include <span>
#include <vector>

namespace dembridge::dem::impl
{

/// Rigid bodies: each moves with the spheres' step (Newton-Euler, the
/// orientation by Rodrigues' formula), its contacts with the spheres in
/// BodyContacts (body.h).
class BodyAddOn final : public AddOn
{
public:
  /// @throws std::runtime_error on a bad shape or mass, or a name in use.
  std::size_t add(RigidBody b);
  std::string name() const override { return "bodies"; }
  double DemTimings::*time_slot() const override { return &DemTimings::bodies; }
  void start(const StepView& s) override;
  void kick(const StepView& s, double h) override;
  double drift(const StepView& s) override;
  void stored_energy(const StepView& s, double& e) const override;
  void spheres_removed(const StepView& s) override;
  void forces(const StepView& s, DemEnergy& booked) override;
  void check_finite(double t, std::int64_t steps) const override;
  void energy(const StepView& s, DemEnergy& e) const override;
  void save(const checkpoint::Group& g) const override;
  void load(const checkpoint::Group& g, const StepView& s) override;

  std::vector<RigidBody> bodies;
  std::vector<BodyContacts> contacts; // one per body
};

/// Reinforcing bars with their bonds to the spheres (bars.h): their nodes
/// move with the spheres' step, damped like them; nodes may be moved at a
/// constant velocity (a bar pulled at its end), with their reaction. They
/// touch the rigid bodies given to touch().
class BarAddOn final : public AddOn
{
public:
  /// @throws std::runtime_error naming a bond whose sphere is not one of `spheres`.
  BarAddOn(Bars bars, std::size_t spheres);
  std::size_t move_nodes(std::span<const std::int32_t> nodes, const std::array<double, 3>& velocity);
  /// The bodies the bar nodes may touch (null: none); kept until the run ends.
  void touch(std::vector<RigidBody>* bodies) { _bodies = bodies; }
  std::string name() const override { return "bars"; }
  double DemTimings::*time_slot() const override { return &DemTimings::bars; }
  void start(const StepView& s) override;
  void begin(const StepView& s) override;
  void kick(const StepView& s, double h) override;
  double drift(const StepView& s) override;
  void forces(const StepView& s, DemEnergy& booked) override;
  double reactions(const StepView& s) override;
  void check_finite(double t, std::int64_t steps) const override;
  void energy(const StepView& s, DemEnergy& e) const override;
  void save(const checkpoint::Group& g) const override;
  void load(const checkpoint::Group& g, const StepView& s) override;

  Bars bars;
  std::vector<std::array<double, 3>> reaction; // per group of moved nodes

private:
  void bar_body_forces_all();
  // the contacts' energy lost when bonds open or elements break
  double contact_jump(const StepView& s);
  void load_contacts(const checkpoint::Group& g, std::size_t spheres);
  BarContacts _contacts; // spheres on the bars beyond their bonds
  std::vector<std::uint8_t> _open_old, _broken_old; // the bonds' and elements' state before the step's forces
  std::vector<std::int32_t> _moved;  // nodes with a prescribed velocity
  std::vector<std::int32_t> _group;  // the group of each (move_nodes' call)
  std::vector<double> _fold;         // their force at the step's start (3 per node)
  std::vector<RigidBody>* _bodies = nullptr;
};

} // namespace dembridge::dem::impl
