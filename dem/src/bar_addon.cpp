// The reinforcing bars as an add-on of the DE step (addons.h): their nodes
// kicked and moved with the spheres, their forces, bonds and contacts, the
// nodes with a prescribed velocity and their reaction, their energies and
// their checkpoint group.
#include "addons.h"

#include "checkpoint_read.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace dembridge::dem::impl
{
using checkpoint::Group;

BarAddOn::BarAddOn(Bars b, std::size_t spheres) : bars(std::move(b))
{
  for (std::size_t k = 0; k < bars.bonds(); ++k)
    if (bars.sphere[k] < 0 || static_cast<std::size_t>(bars.sphere[k]) >= spheres)
      throw std::runtime_error("bars: bond " + std::to_string(k) + " names sphere " + std::to_string(bars.sphere[k])
                               + ", not one of this assembly's " + std::to_string(spheres));
}

std::size_t BarAddOn::move_nodes(std::span<const std::int32_t> nodes, const std::array<double, 3>& velocity)
{
  const auto group = static_cast<std::int32_t>(reaction.size());
  for (auto n : nodes)
  {
    if (n < 0 || static_cast<std::size_t>(n) >= bars.nodes())
      throw std::runtime_error("bar node " + std::to_string(n) + " out of range (the bars have "
                               + std::to_string(bars.nodes()) + " nodes)");
    if (bars.held[n])
      throw std::runtime_error("bar node " + std::to_string(n) + " is moved already");
    _moved.push_back(n);
    _group.push_back(group);
    bars.held[n] = 1;
    for (int k = 0; k < 3; ++k)
      bars.v[3 * n + k] = velocity[k];
  }
  reaction.push_back({0, 0, 0});
  _fold.assign(3 * _moved.size(), 0.0);
  return static_cast<std::size_t>(group);
}

void BarAddOn::bar_body_forces_all()
{
  if (_bodies)
    for (auto& b : *_bodies)
      bar_body_forces(bars, b);
}

void BarAddOn::start(const StepView& s)
{
  bar_forces(bars, s.p, false);
  refresh_bar_contacts(bars, s.p, _contacts, s.nl, s.removed);
  bar_contact_forces(bars, s.p, _contacts, s.mat, s.removed);
  bar_body_forces_all();
}

void BarAddOn::begin(const StepView&)
{
  for (std::size_t q = 0; q < _moved.size(); ++q)
    for (int k = 0; k < 3; ++k)
      _fold[3 * q + k] = bars.f[3 * _moved[q] + k];
}

void BarAddOn::kick(const StepView& s, double h)
{
  const double ch = s.damping * h;
  for (std::size_t n = 0; n < bars.nodes(); ++n)
    if (!bars.held[n])
      for (int k = 0; k < 3; ++k)
        bars.v[3 * n + k] += bars.f[3 * n + k] * h / bars.m[n] - ch * bars.v[3 * n + k];
}

double BarAddOn::drift(const StepView& s)
{
  double wd = 0.0;
  for (std::size_t n = 0; n < bars.nodes(); ++n)
  {
    double v2 = 0.0;
    for (int k = 0; k < 3; ++k)
    {
      bars.x[3 * n + k] += s.dt * bars.v[3 * n + k];
      v2 += bars.v[3 * n + k] * bars.v[3 * n + k];
    }
    wd += s.dt * s.damping * bars.m[n] * v2;
  }
  return wd;
}

void BarAddOn::forces(const StepView& s, DemEnergy& booked)
{
  _open_old.assign(bars.open.begin(), bars.open.end());
  _broken_old.assign(bars.broken.begin(), bars.broken.end());
  const BarWork bw = bar_forces(bars, s.p, true, s.removed);
  booked.bar_slip += bw.slip;
  booked.bar_broken += bw.broken;
  refresh_bar_contacts(bars, s.p, _contacts, s.nl, s.removed);
  if (bw.changed)
    booked.bar_broken += contact_jump(s);
  bar_contact_forces(bars, s.p, _contacts, s.mat, s.removed);
  bar_body_forces_all();
}

double BarAddOn::reactions(const StepView& s)
{
  // constant velocity: 0 = m dv = dt/2 (F_old + F_new) + dt R, the
  // damping's force -c m v counted in F as for the spheres
  std::fill(reaction.begin(), reaction.end(), std::array<double, 3>{0, 0, 0});
  double work = 0.0;
  for (std::size_t q = 0; q < _moved.size(); ++q)
  {
    const std::int32_t n = _moved[q];
    for (int k = 0; k < 3; ++k)
    {
      const double damp = -s.damping * bars.m[n] * bars.v[3 * n + k];
      const double R = -0.5 * (_fold[3 * q + k] + bars.f[3 * n + k]) - damp;
      reaction[_group[q]][k] += R;
      work += s.dt * bars.v[3 * n + k] * R;
    }
  }
  return work;
}

double BarAddOn::contact_jump(const StepView& s)
{
  // a bond that opens hands its sphere to the contact, perhaps already
  // overlapping the bar; an element that breaks drops the contacts on it:
  // the contacts' energy changes at fixed positions, booked as released
  std::swap(bars.open, _open_old);
  std::swap(bars.broken, _broken_old);
  const double before = bar_contact_energy(bars, s.p, _contacts, s.mat, s.removed);
  std::swap(bars.open, _open_old);
  std::swap(bars.broken, _broken_old);
  return before - bar_contact_energy(bars, s.p, _contacts, s.mat, s.removed);
}

void BarAddOn::check_finite(double t, std::int64_t steps) const
{
  for (std::size_t q = 0; q < bars.nodes(); ++q)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(bars.x[3 * q + k]) || !std::isfinite(bars.v[3 * q + k]))
      {
        std::ostringstream s;
        s << "non-finite position or velocity of bar node " << q << " at t = " << t << " s (step " << steps
          << "): the run is unstable; reduce the time step";
        throw std::runtime_error(s.str());
      }
}

void BarAddOn::energy(const StepView& s, DemEnergy& e) const
{
  if (_bodies)
    for (const auto& b : *_bodies)
      e.body_contact += bar_body_energy(bars, b);
  const BarEnergy be = bar_energy(bars, s.p);
  e.bar_kinetic = be.kinetic;
  e.bar_elastic = be.elastic + bar_contact_energy(bars, s.p, _contacts, s.mat, s.removed);
  e.bar_plastic = be.plastic;
  e.bar_opening = be.opening;
}

void BarAddOn::save(const Group& g) const
{
  const Bars& b = bars;
  for (auto [name, v] : {std::pair{"x", &b.x}, {"v", &b.v}, {"f", &b.f}, {"plastic", &b.plastic},
                         {"alpha", &b.alpha}, {"force", &b.force}, {"length", &b.length}, {"tau", &b.tau},
                         {"slip", &b.slip}, {"slip_max", &b.slip_max}, {"gap", &b.gap}, {"gap_max", &b.gap_max}, {"m", &b.m},
                         {"surface", &b.surface}, {"fold", &_fold}})
    g.write(name, *v);
  for (auto [name, v] : {std::pair{"broken", &b.broken}, {"open", &b.open}, {"held", &b.held},
                         {"bend_kept", &b.bend_kept}})
    g.write(name, *v);
  g.write("moved", _moved);
  g.write("moved_group", _group);
  g.write("bond_spheres", b.sphere);
  std::vector<double> reac;
  for (const auto& r : reaction)
    reac.insert(reac.end(), r.begin(), r.end());
  g.write("reaction", reac);
  g.write("contact_spheres", _contacts.sphere);
  g.write("contact_elements", _contacts.element);
  g.write("contact_x_refresh", _contacts.x_refresh);
  g.write("contact_x_spheres", _contacts.x_spheres);
  g.write_int("contact_refreshed", _contacts.refreshed ? 1 : 0);
  g.write_int("sphere_contacts", b.sphere_contacts ? 1 : 0);
}

void BarAddOn::load(const Group& g, const StepView& s)
{
  Bars& b = bars;
  check_same(g, "bond_spheres", b.sphere);
  check_same(g, "m", b.m);
  for (auto [name, v] : {std::pair{"x", &b.x}, {"v", &b.v}, {"f", &b.f}, {"plastic", &b.plastic},
                         {"alpha", &b.alpha}, {"force", &b.force}, {"length", &b.length}, {"tau", &b.tau},
                         {"slip", &b.slip}, {"slip_max", &b.slip_max}, {"gap", &b.gap}, {"gap_max", &b.gap_max},
                         {"surface", &b.surface}})
    read_same_size(g, name, *v);
  for (auto [name, v] : {std::pair{"broken", &b.broken}, {"open", &b.open}, {"held", &b.held},
                         {"bend_kept", &b.bend_kept}})
    read_same_size(g, name, *v);
  check_same(g, "moved", _moved);
  check_same(g, "moved_group", _group);
  read_same_size(g, "fold", _fold);
  std::vector<double> reac;
  g.read("reaction", reac);
  if (reac.size() != 3 * reaction.size())
    g.fail("reaction", "not 3 values per group of moved nodes (another set-up)");
  for (std::size_t q = 0; q < reaction.size(); ++q)
    for (int k = 0; k < 3; ++k)
      reaction[q][k] = reac[3 * q + k];
  if (g.has("sphere_contacts") && (g.read_int("sphere_contacts") != 0) != b.sphere_contacts)
    g.fail("sphere_contacts", b.sphere_contacts ? "the checkpoint's bars are embedded, these are not (another set-up)"
                                                : "these bars are embedded, the checkpoint's are not (another set-up)");
  load_contacts(g, s.p.size());
}

void BarAddOn::load_contacts(const Group& g, std::size_t spheres)
{
  BarContacts& c = _contacts;
  if (!g.has("contact_spheres"))
    return; // written before the contacts: they are found at the first step
  g.read("contact_spheres", c.sphere);
  g.read("contact_elements", c.element);
  if (c.sphere.size() != c.element.size())
    g.fail("contact_elements", "not one per contact sphere");
  for (std::size_t q = 0; q < c.sphere.size(); ++q)
    if (c.sphere[q] < 0 || static_cast<std::size_t>(c.sphere[q]) >= spheres || c.element[q] < 0
        || static_cast<std::size_t>(c.element[q]) >= bars.elements())
      g.fail("contact_spheres", "a pair names a sphere or element out of range (another set-up)");
  g.read("contact_x_refresh", c.x_refresh);
  if (!c.x_refresh.empty() && c.x_refresh.size() != bars.x.size())
    g.fail("contact_x_refresh", "not 3 values per bar node (another set-up)");
  g.read("contact_x_spheres", c.x_spheres);
  if (!c.x_spheres.empty() && c.x_spheres.size() != 3 * spheres)
    g.fail("contact_x_spheres", "not 3 values per sphere (another set-up)");
  std::vector<std::int64_t> refreshed;
  g.read("contact_refreshed", refreshed);
  if (refreshed.size() != 1)
    g.fail("contact_refreshed", "not one value");
  c.refreshed = refreshed[0] != 0;
}

} // namespace dembridge::dem::impl
