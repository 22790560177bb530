// Checkpoint and restart of the DEM: the particles, links, neighbour list
// and solver state written to a checkpoint group and read back bit for bit
// (checkpoint.h).
#include "dembridge/dem/solver.h"

#include <array>
#include <stdexcept>

#include "checkpoint_read.h"
#include "force_loop.h"

namespace dembridge::dem
{
namespace
{
using checkpoint::Group;
using impl::check_same;
using impl::read_same_size;

/// The particle arrays a step changes (r is checked, quantum compared).
template <typename P> auto particle_arrays(P& p) // P: Particles or const Particles
{
  using A = decltype(&p.x);
  return std::vector<std::pair<const char*, A>>{{"x", &p.x},  {"x0", &p.x0}, {"v", &p.v},       {"w", &p.w},          {"f", &p.f},
          {"t", &p.t}, {"m", &p.m},   {"inertia", &p.inertia}, {"weight", &p.weight}};
}

void save_particles(const Group& g, const Particles& p)
{
  for (auto [name, v] : particle_arrays(p))
    g.write(name, *v);
  g.write("r", p.r);
  g.write("quantum", p.quantum);
}

void load_particles(const Group& g, Particles& p)
{
  check_same(g, "r", p.r);
  for (auto [name, v] : particle_arrays(p))
    read_same_size(g, name, *v);
  if (g.read_double("quantum") != p.quantum)
    g.fail("quantum", "differs from this run's (another assembly)");
}

void save_links(const Group& g, const Links& l)
{
  g.write("a", l.a);
  g.write("b", l.b);
  g.write("d0", l.d0);
  g.write("kn", l.kn);
  g.write("ks", l.ks);
  g.write("fs", l.fs);
  g.write("n", l.n);
  g.write("delta_max", l.delta_max);
  std::vector<std::uint8_t> state(l.size());
  for (std::size_t k = 0; k < l.size(); ++k)
    state[k] = static_cast<std::uint8_t>(l.state[k]);
  g.write("state", state);
  g.write("weight", l.weight);
  g.write("strength", l.strength);
  g.write("compaction", l.compaction);
  g.write("compaction_onset", l.compaction_onset);
  g.write("rate", l.rate);
}

void load_links(const Group& g, Links& l)
{
  check_same(g, "a", l.a);
  check_same(g, "b", l.b);
  check_same(g, "d0", l.d0);
  for (auto [name, v] : {std::pair{"kn", &l.kn}, {"ks", &l.ks}, {"fs", &l.fs}, {"n", &l.n},
                         {"delta_max", &l.delta_max}, {"weight", &l.weight}, {"strength", &l.strength},
                         {"compaction", &l.compaction}})
    read_same_size(g, name, *v);
  if (g.has("rate")) // (absent from checkpoints without the rate filter)
    read_same_size(g, "rate", l.rate);
  if (g.has("compaction_onset")) // (absent from checkpoints without a pressure gate)
    read_same_size(g, "compaction_onset", l.compaction_onset);
  std::vector<std::uint8_t> state;
  g.read("state", state);
  if (state.size() != l.size())
    g.fail("state", "not one value per link");
  for (std::size_t k = 0; k < l.size(); ++k)
  {
    if (state[k] > static_cast<std::uint8_t>(LinkState::removed))
      g.fail("state", "value " + std::to_string(state[k]) + " is no link state");
    l.state[k] = static_cast<LinkState>(state[k]);
  }
}
} // namespace

// The energies a checkpoint keeps, in its order, for save and load alike
// (compaction is a state: energy() recomputes it).
constexpr std::array booked_energies{
    &DemEnergy::initial,         &DemEnergy::kinetic,      &DemEnergy::elastic,      &DemEnergy::softening,
    &DemEnergy::breakage,        &DemEnergy::friction,     &DemEnergy::damping,      &DemEnergy::external_work,
    &DemEnergy::prescribed_work, &DemEnergy::body_kinetic, &DemEnergy::body_contact, &DemEnergy::body_friction,
    &DemEnergy::removed,         &DemEnergy::bar_slip,     &DemEnergy::bar_broken};

// ---- NeighbourList --------------------------------------------------------------

void NeighbourList::save(const Group& g) const
{
  if (_pending)
    throw std::logic_error("neighbour list: saved with a deferred search not merged (add_broken_links)");
  if (!_dropped.empty())
    throw std::logic_error("neighbour list: saved with removed spheres whose pairs no update() has dropped");
  g.write("a", a);
  g.write("b", b);
  g.write("link", link);
  g.write("fs", fs);
  if (_rolling)
    g.write("mr", mr);
  g.write("n", n);
  g.write("touching", touching);
  g.write("x_build", _x_build);
  g.write("x_grid", _x_grid);
  g.write_int("builds", static_cast<std::int64_t>(_builds));
  g.write_int("partial_builds", static_cast<std::int64_t>(_partial));
  g.write_int("version", static_cast<std::int64_t>(_version));
  g.write("skin", _skin);
  g.write("cell", _cell);
  g.write("skip", _skip);
  g.write_int("stale", _stale ? 1 : 0);
}

void NeighbourList::load(const Group& g)
{
  if (g.read_double("skin") != _skin)
    g.fail("skin", "differs from this run's skin " + std::to_string(_skin) + " m");
  // nothing of a search or removal in progress survives (a step that threw
  // between update() and add_broken_links(), then a reload)
  end_search();
  _pend_a.clear();
  _pend_b.clear();
  _pend_link.clear();
  g.read("a", a);
  g.read("b", b);
  g.read("link", link);
  g.read("fs", fs);
  g.read("n", n);
  g.read("touching", touching);
  g.read("x_build", _x_build);
  // the rolling moments, if the run kept them (a run without rolling
  // resistance writes none)
  _rolling = g.has("mr");
  if (_rolling)
    g.read("mr", mr);
  else
    mr.clear();
  const std::size_t m = a.size();
  if (b.size() != m || link.size() != m || fs.size() != 3 * m || n.size() != 3 * m || touching.size() != m
      || (_rolling && mr.size() != 3 * m))
    g.fail("a", "the pair arrays have inconsistent lengths (file damaged?)");
  // (a checkpoint written before partial updates: its grid was made from x_build)
  if (g.has("x_grid"))
    g.read("x_grid", _x_grid);
  else
    _x_grid = _x_build;
  _builds = static_cast<std::size_t>(g.read_int("builds"));
  _partial = g.has("partial_builds") ? static_cast<std::size_t>(g.read_int("partial_builds")) : 0;
  _version = static_cast<std::size_t>(g.read_int("version"));
  _cell = g.read_double("cell");
  g.read("skip", _skip);
  _stale = g.read_int("stale") != 0;
  if (_x_grid.size() != _x_build.size() || (!_skip.empty() && 3 * _skip.size() != _x_build.size()))
    g.fail("x_grid", "the positions and the skipped spheres have inconsistent lengths (file damaged?)");
  // the grid of the last change, from its positions (the constructor is deterministic)
  if (_builds > 0)
    _grid.emplace(_x_grid, _cell, _skip);
  else
    _grid.reset();
}

// ---- DemSolver ------------------------------------------------------------------

void DemSolver::save(const Group& g) const
{
  if (_in_step)
    throw std::runtime_error("DemSolver::save between begin_step and end_step: save at the end of a step");
  save_particles(g.group("particles"), _p);
  save_links(g.group("links"), _l);
  _nl.save(g.group("neighbours"));
  g.write("time", _t);
  g.write_int("steps", _steps);
  g.write("dt", _dt);
  g.write("damping", _c);
  std::vector<double> e;
  for (auto field : booked_energies)
    e.push_back(_e.*field);
  g.write("energy", e);
  const std::vector<double> c{_counters.friction, _counters.breakage, _counters.cohesion_demand,
                              _counters.track_cohesion ? 1.0 : 0.0};
  g.write("counters", c);
  std::string names;
  for (const auto& m : _motions)
    names += m.name + '\n';
  g.write("motions", names);
  for (auto [name, v] : {std::pair{"fext", &_fext}, {"fext_old", &_fext_old}, {"reactions", &_reac},
                         {"f_old", &_fold}, {"v_old", &_vold}})
    g.write(name, *v);
  std::vector<double> hinged;
  for (std::size_t q = 0; q < _motions.size(); ++q)
    for (int k = 0; k < 3; ++k)
    {
      hinged.push_back(_motion_reac[q][k]);
      hinged.push_back(_motion_vprev[q][k]);
    }
  g.write("hinged", hinged);
  save_addons(g);
  g.write("removed", _removed);
  g.write("removed_totals", std::vector<double>{double(_gone.count), _gone.mass, _gone.momentum[0], _gone.momentum[1],
                                                _gone.momentum[2], _gone.kinetic, _gone.elastic});
}

void DemSolver::load(const Group& g)
{
  if (_in_step)
    throw std::runtime_error("DemSolver::load between begin_step and end_step");
  if (g.read_double("dt") != _dt)
    g.fail("dt", "the time step " + std::to_string(g.read_double("dt")) + " s differs from this run's "
                     + std::to_string(_dt) + " s");
  std::string names;
  for (const auto& m : _motions)
    names += m.name + '\n';
  if (g.read_string("motions") != names)
    g.fail("motions", "the boundary conditions differ from this run's (another set-up, or a condition "
                      "released: load the state once the run's conditions are those of the checkpoint)");
  load_particles(g.group("particles"), _p);
  load_links(g.group("links"), _l);
  // the spheres removed from the computation, held again (before the held
  // dofs' arrays are read: update_held sizes them)
  read_same_size(g, "removed", _removed);
  std::vector<double> gone;
  g.read("removed_totals", gone);
  if (gone.size() != 7)
    g.fail("removed_totals", "unexpected length (file damaged?)");
  _gone = {static_cast<std::size_t>(gone[0]), gone[1], {gone[2], gone[3], gone[4]}, gone[5], gone[6]};
  update_held();
  _nl.load(g.group("neighbours"));
  _t = g.read_double("time");
  _steps = g.read_int("steps");
  _c = g.read_double("damping");
  std::vector<double> e, c;
  g.read("energy", e);
  g.read("counters", c);
  if (e.size() != booked_energies.size() || c.size() != 4)
    g.fail("energy", "unexpected length (file damaged?)");
  _e = DemEnergy{};
  for (std::size_t k = 0; k < booked_energies.size(); ++k)
    _e.*booked_energies[k] = e[k];
  _counters.friction = c[0];
  _counters.breakage = c[1];
  _counters.cohesion_demand = c[2];
  _counters.track_cohesion = c[3] != 0.0;
  for (auto [name, v] : {std::pair{"fext", &_fext}, {"fext_old", &_fext_old}, {"reactions", &_reac},
                         {"f_old", &_fold}, {"v_old", &_vold}})
    read_same_size(g, name, *v);
  std::vector<double> hinged;
  g.read("hinged", hinged);
  if (hinged.size() != 6 * _motions.size())
    g.fail("hinged", "not 6 values per condition");
  for (std::size_t q = 0; q < _motions.size(); ++q)
    for (int k = 0; k < 3; ++k)
    {
      _motion_reac[q][k] = hinged[6 * q + 2 * k];
      _motion_vprev[q][k] = hinged[6 * q + 2 * k + 1];
    }
  load_addons(g);

  // the force loop's index structures are rebuilt for the loaded pairs
  _scratch = std::make_unique<ForceScratch>();
}

} // namespace dembridge::dem
