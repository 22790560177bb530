// The reinforcing bars in the DEM step (bars.h): their nodes kicked and
// moved with the spheres, the nodes with a prescribed velocity and their
// reaction, and their part of a checkpoint.
#include "dembridge/dem/solver.h"

#include "checkpoint_read.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace dembridge::dem
{

void DemSolver::add_bars(Bars bars)
{
  if (_started)
    throw std::runtime_error("bars: they are added before start()");
  if (_has_bars)
    throw std::runtime_error("bars: added once (give every bar to one call)");
  for (std::size_t k = 0; k < bars.bonds(); ++k)
    if (bars.sphere[k] < 0 || static_cast<std::size_t>(bars.sphere[k]) >= _p.size())
      throw std::runtime_error("bars: bond " + std::to_string(k) + " names sphere "
                               + std::to_string(bars.sphere[k]) + ", not one of this assembly's "
                               + std::to_string(_p.size()));
  _bars = std::move(bars);
  _has_bars = true;
}

std::size_t DemSolver::move_bar_nodes(std::span<const std::int32_t> nodes, const std::array<double, 3>& velocity)
{
  if (_started)
    throw std::runtime_error("bar nodes: their motion is set before start()");
  const auto group = static_cast<std::int32_t>(_bar_reac.size());
  for (auto n : nodes)
  {
    if (n < 0 || static_cast<std::size_t>(n) >= _bars.nodes())
      throw std::runtime_error("bar node " + std::to_string(n) + " out of range (the bars have "
                               + std::to_string(_bars.nodes()) + " nodes)");
    if (_bars.held[n])
      throw std::runtime_error("bar node " + std::to_string(n) + " is moved already");
    _bar_moved.push_back(n);
    _bar_group.push_back(group);
    _bars.held[n] = 1;
    for (int k = 0; k < 3; ++k)
      _bars.v[3 * n + k] = velocity[k];
  }
  _bar_reac.push_back({0, 0, 0});
  _bar_fold.assign(3 * _bar_moved.size(), 0.0);
  return static_cast<std::size_t>(group);
}

void DemSolver::kick_bars(double h)
{
  const double ch = _c * h;
  for (std::size_t n = 0; n < _bars.nodes(); ++n)
    if (!_bars.held[n])
      for (int k = 0; k < 3; ++k)
        _bars.v[3 * n + k] += _bars.f[3 * n + k] * h / _bars.m[n] - ch * _bars.v[3 * n + k];
}

double DemSolver::drift_bars()
{
  double wd = 0.0;
  for (std::size_t n = 0; n < _bars.nodes(); ++n)
  {
    double v2 = 0.0;
    for (int k = 0; k < 3; ++k)
    {
      _bars.x[3 * n + k] += _dt * _bars.v[3 * n + k];
      v2 += _bars.v[3 * n + k] * _bars.v[3 * n + k];
    }
    wd += _dt * _c * _bars.m[n] * v2;
  }
  return wd;
}

double DemSolver::bar_reactions()
{
  // constant velocity: 0 = m dv = dt/2 (F_old + F_new) + dt R, the
  // damping's force -c m v counted in F as for the spheres
  std::fill(_bar_reac.begin(), _bar_reac.end(), std::array<double, 3>{0, 0, 0});
  double work = 0.0;
  for (std::size_t q = 0; q < _bar_moved.size(); ++q)
  {
    const std::int32_t n = _bar_moved[q];
    for (int k = 0; k < 3; ++k)
    {
      const double damp = -_c * _bars.m[n] * _bars.v[3 * n + k];
      const double R = -0.5 * (_bar_fold[3 * q + k] + _bars.f[3 * n + k]) - damp;
      _bar_reac[_bar_group[q]][k] += R;
      work += _dt * _bars.v[3 * n + k] * R;
    }
  }
  return work;
}

double DemSolver::bar_contact_jump()
{
  // a bond that opens hands its sphere to the contact, perhaps already
  // overlapping the bar; an element that breaks drops the contacts on it:
  // the contacts' energy changes at fixed positions, booked as released
  std::swap(_bars.open, _bar_open_old);
  std::swap(_bars.broken, _bar_broken_old);
  const double before = bar_contact_energy(_bars, _p, _bar_contacts, _mat, _removed);
  std::swap(_bars.open, _bar_open_old);
  std::swap(_bars.broken, _bar_broken_old);
  return before - bar_contact_energy(_bars, _p, _bar_contacts, _mat, _removed);
}

void DemSolver::save_bars(const checkpoint::Group& g) const
{
  const Bars& b = _bars;
  for (auto [name, v] : {std::pair{"x", &b.x}, {"v", &b.v}, {"f", &b.f}, {"plastic", &b.plastic},
                         {"alpha", &b.alpha}, {"force", &b.force}, {"length", &b.length}, {"tau", &b.tau},
                         {"slip", &b.slip}, {"slip_max", &b.slip_max}, {"gap", &b.gap}, {"gap_max", &b.gap_max}, {"m", &b.m},
                         {"surface", &b.surface}, {"fold", &_bar_fold}})
    g.write(name, *v);
  for (auto [name, v] : {std::pair{"broken", &b.broken}, {"open", &b.open}, {"held", &b.held},
                         {"bend_kept", &b.bend_kept}})
    g.write(name, *v);
  g.write("moved", _bar_moved);
  g.write("moved_group", _bar_group);
  g.write("bond_spheres", b.sphere);
  std::vector<double> reac;
  for (const auto& r : _bar_reac)
    reac.insert(reac.end(), r.begin(), r.end());
  g.write("reaction", reac);
  g.write("contact_spheres", _bar_contacts.sphere);
  g.write("contact_elements", _bar_contacts.element);
  g.write("contact_x_refresh", _bar_contacts.x_refresh);
  g.write("contact_x_spheres", _bar_contacts.x_spheres);
  g.write_int("contact_refreshed", _bar_contacts.refreshed ? 1 : 0);
  g.write_int("sphere_contacts", b.sphere_contacts ? 1 : 0);
}

void DemSolver::load_bars(const checkpoint::Group& g)
{
  Bars& b = _bars;
  impl::check_same(g, "bond_spheres", b.sphere);
  impl::check_same(g, "m", b.m);
  for (auto [name, v] : {std::pair{"x", &b.x}, {"v", &b.v}, {"f", &b.f}, {"plastic", &b.plastic},
                         {"alpha", &b.alpha}, {"force", &b.force}, {"length", &b.length}, {"tau", &b.tau},
                         {"slip", &b.slip}, {"slip_max", &b.slip_max}, {"gap", &b.gap}, {"gap_max", &b.gap_max},
                         {"surface", &b.surface}})
    impl::read_same_size(g, name, *v);
  for (auto [name, v] : {std::pair{"broken", &b.broken}, {"open", &b.open}, {"held", &b.held},
                         {"bend_kept", &b.bend_kept}})
    impl::read_same_size(g, name, *v);
  impl::check_same(g, "moved", _bar_moved);
  impl::check_same(g, "moved_group", _bar_group);
  impl::read_same_size(g, "fold", _bar_fold);
  std::vector<double> reac;
  g.read("reaction", reac);
  if (reac.size() != 3 * _bar_reac.size())
    g.fail("reaction", "not 3 values per group of moved nodes (another set-up)");
  for (std::size_t q = 0; q < _bar_reac.size(); ++q)
    for (int k = 0; k < 3; ++k)
      _bar_reac[q][k] = reac[3 * q + k];
  if (g.has("sphere_contacts") && (g.read_int("sphere_contacts") != 0) != b.sphere_contacts)
    g.fail("sphere_contacts", b.sphere_contacts ? "the checkpoint's bars are embedded, these are not (another set-up)"
                                                : "these bars are embedded, the checkpoint's are not (another set-up)");
  BarContacts& c = _bar_contacts;
  if (!g.has("contact_spheres"))
    return; // written before the contacts: they are found at the first step
  g.read("contact_spheres", c.sphere);
  g.read("contact_elements", c.element);
  if (c.sphere.size() != c.element.size())
    g.fail("contact_elements", "not one per contact sphere");
  for (std::size_t q = 0; q < c.sphere.size(); ++q)
    if (c.sphere[q] < 0 || static_cast<std::size_t>(c.sphere[q]) >= _p.size() || c.element[q] < 0
        || static_cast<std::size_t>(c.element[q]) >= b.elements())
      g.fail("contact_spheres", "a pair names a sphere or element out of range (another set-up)");
  g.read("contact_x_refresh", c.x_refresh);
  if (!c.x_refresh.empty() && c.x_refresh.size() != b.x.size())
    g.fail("contact_x_refresh", "not 3 values per bar node (another set-up)");
  g.read("contact_x_spheres", c.x_spheres);
  if (!c.x_spheres.empty() && c.x_spheres.size() != _p.x.size())
    g.fail("contact_x_spheres", "not 3 values per sphere (another set-up)");
  std::vector<std::int64_t> refreshed;
  g.read("contact_refreshed", refreshed);
  if (refreshed.size() != 1)
    g.fail("contact_refreshed", "not one value");
  c.refreshed = refreshed[0] != 0;
}

} // namespace dembridge::dem
