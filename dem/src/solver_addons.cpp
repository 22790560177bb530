// DemSolver's add-ons (addon.h): the list, the rigid bodies' and bars'
// entry points, and the add-ons' part of a checkpoint.
#include "dembridge/dem/solver.h"

#include "addons.h"

#include <stdexcept>
#include <string>

namespace dembridge::dem
{

StepView DemSolver::view() const { return {_p, _l, _nl, _mat, _removed, _dt, _c}; }

AddOn& DemSolver::add_addon(std::unique_ptr<AddOn> a) { return insert_addon(std::move(a), false); }

AddOn& DemSolver::insert_addon(std::unique_ptr<AddOn> a, bool first)
{
  const std::string name = a ? a->name() : std::string();
  if (_started)
    throw std::runtime_error("add-on '" + name + "': add-ons are added before start()");
  // (the solver's own groups and datasets share the checkpoint group)
  if (name.empty() || name.find('/') != std::string::npos || name == "addons" || name == "particles"
      || name == "links" || name == "neighbours")
    throw std::runtime_error("add-on '" + name
                             + "': a name must be non-empty, without '/', not addons, particles, links or neighbours");
  for (const auto& o : _addons)
    if (o->name() == name)
      throw std::runtime_error("add-on '" + name + "': the name is in use");
  auto at = _addons.insert(first ? _addons.begin() : _addons.end(), std::move(a));
  return **at;
}

std::size_t DemSolver::add_body(RigidBody b)
{
  if (_started)
    throw std::runtime_error("rigid body '" + b.name + "': bodies are added before start()");
  if (!_bodies)
    // the bodies come first: the bars' forces act on them after their contacts
    _bodies = static_cast<impl::BodyAddOn*>(&insert_addon(std::make_unique<impl::BodyAddOn>(), true));
  return _bodies->add(std::move(b));
}

std::size_t DemSolver::bodies() const { return _bodies ? _bodies->bodies.size() : 0; }

const RigidBody& DemSolver::body(std::size_t k) const
{
  if (k >= bodies())
    throw std::out_of_range("rigid body " + std::to_string(k) + ": the solver has " + std::to_string(bodies()));
  return _bodies->bodies[k];
}

const BodyContacts& DemSolver::body_contacts(std::size_t k) const
{
  body(k); // the range check
  return _bodies->contacts[k];
}

void DemSolver::add_bars(Bars bars)
{
  if (_started)
    throw std::runtime_error("bars: they are added before start()");
  if (_bars)
    throw std::runtime_error("bars: added once (give every bar to one call)");
  _bars = static_cast<impl::BarAddOn*>(&add_addon(std::make_unique<impl::BarAddOn>(std::move(bars), _p.size())));
}

const Bars& DemSolver::bars() const
{
  static const Bars none;
  return _bars ? _bars->bars : none;
}

Bars& DemSolver::bars_for_coupling()
{
  if (!_bars)
    throw std::runtime_error("bars: the solver has none");
  return _bars->bars;
}

std::size_t DemSolver::move_bar_nodes(std::span<const std::int32_t> nodes, const std::array<double, 3>& velocity)
{
  if (_started)
    throw std::runtime_error("bar nodes: their motion is set before start()");
  if (!_bars)
  {
    if (nodes.empty())
      throw std::runtime_error("bar nodes: none given, and the solver has no bars");
    throw std::runtime_error("bar node " + std::to_string(nodes[0]) + " out of range (the solver has no bars)");
  }
  return _bars->move_nodes(nodes, velocity);
}

std::array<double, 3> DemSolver::bar_reaction(std::size_t g) const
{
  if (!_bars || g >= _bars->reaction.size())
    throw std::out_of_range("bar node group " + std::to_string(g) + ": move_bar_nodes made "
                            + std::to_string(_bars ? _bars->reaction.size() : 0));
  return _bars->reaction[g];
}

namespace
{
std::string names_of(const std::vector<std::unique_ptr<AddOn>>& addons)
{
  std::string names;
  for (const auto& a : addons)
  {
    if (!names.empty())
      names += ' ';
    names += a->name();
  }
  return names;
}
} // namespace

void DemSolver::save_addons(const checkpoint::Group& g) const
{
  g.write("addons", names_of(_addons));
  for (const auto& a : _addons)
    a->save(g.group(a->name()));
}

void DemSolver::load_addons(const checkpoint::Group& g)
{
  const std::string names = names_of(_addons);
  if (!g.has("addons"))
    g.fail("addons", "missing: the checkpoint was written by an earlier dembridge (restart it with that version)");
  if (g.read_string("addons") != names)
    g.fail("addons", "the add-ons (rigid bodies, bars, ...) differ from this run's (another set-up): the checkpoint's are ["
                         + g.read_string("addons") + "], this run's [" + names + "]");
  for (const auto& a : _addons)
    a->load(g.group(a->name()), view());
}

} // namespace dembridge::dem
