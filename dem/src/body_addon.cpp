// The rigid bodies as an add-on of the DE step (addons.h): their kicks,
// drift, contacts with the spheres, energies and checkpoint group.
#include "addons.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "force_loop.h"

namespace dembridge::dem::impl
{
using checkpoint::Group;

std::size_t BodyAddOn::add(RigidBody b)
{
  if (b.name.empty() || b.name[0] == '.' || b.name.find('/') != std::string::npos)
    throw std::runtime_error("rigid body '" + b.name + "': a name must be non-empty, without '/', not starting with '.'");
  b.shape.validate();
  for (const auto& o : bodies)
    if (o.name == b.name)
      throw std::runtime_error("rigid body '" + b.name + "': the name is in use");
  if (!b.fixed && (!(b.mass > 0.0) || !(b.inertia[0] > 0.0 && b.inertia[1] > 0.0 && b.inertia[2] > 0.0)))
    throw std::runtime_error("rigid body '" + b.name + "': a moving body needs a mass and inertias > 0");
  if (!(b.friction >= 0.0) || !std::isfinite(b.friction))
    throw std::runtime_error("rigid body '" + b.name + "': friction " + std::to_string(b.friction) + " must be >= 0");
  if (b.shape.kind != Shape::Kind::projectile)
    b.fixed = true; // planes and boxes are walls
  bodies.push_back(std::move(b));
  contacts.emplace_back();
  return bodies.size() - 1;
}

void BodyAddOn::start(const StepView& s)
{
  for (std::size_t k = 0; k < bodies.size(); ++k)
    body_forces(s.p, bodies[k], contacts[k], s.nl, s.mat, 0.0);
  for (auto& c : contacts)
    c.friction_work = 0.0;
}

void BodyAddOn::kick(const StepView&, double h)
{
  for (auto& b : bodies)
    if (!b.fixed)
      for (int k = 0; k < 3; ++k)
      {
        b.v[k] += h * b.f[k] / b.mass;
        b.L[k] += h * b.t[k];
      }
}

double BodyAddOn::drift(const StepView& s)
{
  // x += dt v; R <- exp(dt [omega]) R (Rodrigues), omega from L(n+1/2)
  for (auto& b : bodies)
  {
    if (b.fixed)
      continue;
    const auto w = b.omega();
    for (int k = 0; k < 3; ++k)
      b.x[k] += s.dt * b.v[k];
    const double wn = std::sqrt(dot3(w.data(), w.data())), th = wn * s.dt;
    if (!(th > 0.0))
      continue;
    const double u[3] = {w[0] / wn, w[1] / wn, w[2] / wn}, sn = std::sin(th), c = 1.0 - std::cos(th);
    const double K[9] = {0, -u[2], u[1], u[2], 0, -u[0], -u[1], u[0], 0};
    double Q[9];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
      {
        double kk = 0.0;
        for (int q = 0; q < 3; ++q)
          kk += K[3 * i + q] * K[3 * q + j];
        Q[3 * i + j] = (i == j ? 1.0 : 0.0) + sn * K[3 * i + j] + c * kk;
      }
    std::array<double, 9> R{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int q = 0; q < 3; ++q)
          R[3 * i + j] += Q[3 * i + q] * b.R[3 * q + j];
    b.R = R;
  }
  return 0.0;
}

void BodyAddOn::stored_energy(const StepView& s, double& e) const
{
  for (std::size_t k = 0; k < bodies.size(); ++k)
    e += body_contact_energy(s.p, bodies[k], contacts[k], s.mat);
}

void BodyAddOn::spheres_removed(const StepView& s)
{
  // their contacts with the bodies end (and they are examined no more)
  for (auto& c : contacts)
  {
    std::size_t kept = 0;
    for (std::size_t h = 0; h < c.ids.size(); ++h)
      if (!s.removed[c.ids[h]])
      {
        c.ids[kept] = c.ids[h];
        for (int k = 0; k < 3; ++k)
          c.fs[3 * kept + k] = c.fs[3 * h + k];
        ++kept;
      }
    c.ids.resize(kept);
    c.fs.resize(3 * kept);
    std::erase_if(c.near, [&](std::int32_t i) { return s.removed[i] != 0; });
  }
}

void BodyAddOn::forces(const StepView& s, DemEnergy&)
{
  for (std::size_t k = 0; k < bodies.size(); ++k)
    body_forces(s.p, bodies[k], contacts[k], s.nl, s.mat, s.dt);
}

void BodyAddOn::check_finite(double t, std::int64_t steps) const
{
  for (const auto& b : bodies)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(b.x[k]) || !std::isfinite(b.v[k]) || !std::isfinite(b.L[k]))
      {
        std::ostringstream s;
        s << "non-finite position or velocity of the rigid body '" << b.name << "' at t = " << t << " s (step "
          << steps << "): the run is unstable; reduce the time step";
        throw std::runtime_error(s.str());
      }
}

void BodyAddOn::energy(const StepView& s, DemEnergy& e) const
{
  e.body_kinetic = e.body_contact = e.body_friction = 0.0;
  for (std::size_t k = 0; k < bodies.size(); ++k)
  {
    e.body_kinetic += bodies[k].kinetic_energy();
    e.body_contact += body_contact_energy(s.p, bodies[k], contacts[k], s.mat);
    e.body_friction += contacts[k].friction_work;
  }
}

namespace
{
std::string names_of(const std::vector<RigidBody>& bodies)
{
  std::string names;
  for (const auto& b : bodies)
    names += b.name + '\n';
  return names;
}
} // namespace

void BodyAddOn::save(const Group& g) const
{
  g.write("names", names_of(bodies));
  for (std::size_t k = 0; k < bodies.size(); ++k)
  {
    const RigidBody& b = bodies[k];
    const BodyContacts& c = contacts[k];
    const Group h = g.group(b.name);
    h.write("mass", b.mass);
    for (auto [name, v] : {std::pair{"x", &b.x}, {"v", &b.v}, {"L", &b.L}, {"f", &b.f}, {"t", &b.t},
                           {"x_refresh", &c.x_refresh}})
      h.write(name, std::span<const double>(v->data(), 3));
    h.write("R", std::span<const double>(b.R.data(), 9));
    h.write("R_refresh", std::span<const double>(c.R_refresh.data(), 9));
    h.write("contacts", c.ids);
    h.write("shear", c.fs);
    h.write("near", c.near);
    h.write_int("version", static_cast<std::int64_t>(c.version));
    h.write_int("refreshed", c.refreshed ? 1 : 0);
    h.write("friction_work", c.friction_work);
  }
}

void BodyAddOn::load(const Group& g, const StepView&)
{
  if (g.read_string("names") != names_of(bodies))
    g.fail("names", "the rigid bodies differ from this run's (another set-up)");
  for (std::size_t k = 0; k < bodies.size(); ++k)
  {
    RigidBody& b = bodies[k];
    BodyContacts& c = contacts[k];
    const Group h = g.group(b.name);
    if (h.read_double("mass") != b.mass)
      h.fail("mass", "differs from this run's body '" + b.name + "'");
    for (auto [name, v] : {std::pair{"x", &b.x}, {"v", &b.v}, {"L", &b.L}, {"f", &b.f}, {"t", &b.t},
                           {"x_refresh", &c.x_refresh}})
      h.read_exact(name, std::span<double>(v->data(), 3));
    h.read_exact("R", std::span<double>(b.R.data(), 9));
    h.read_exact("R_refresh", std::span<double>(c.R_refresh.data(), 9));
    h.read("contacts", c.ids);
    h.read("shear", c.fs);
    h.read("near", c.near);
    if (c.fs.size() != 3 * c.ids.size())
      h.fail("shear", "not 3 values per contact (file damaged?)");
    c.version = static_cast<std::size_t>(h.read_int("version"));
    c.refreshed = h.read_int("refreshed") != 0;
    c.friction_work = h.read_double("friction_work");
  }
}

} // namespace dembridge::dem::impl
