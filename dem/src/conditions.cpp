// DemSolver's boundary conditions: kinematic conditions, external forces,
// loading plates and hinged sets (conditions.h).
#include "dembridge/dem/solver.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "force_loop.h"

namespace dembridge::dem
{
using impl::dot3;

void DemSolver::update_held()
{
  // the spheres of a condition or load (never removed from the domain)
  _in_condition.assign(_p.size(), 0);
  for (const auto& m : _motions)
    for (auto i : m.ids)
      _in_condition[i] = 1;
  for (const auto& f : _forces)
    for (auto i : f.ids)
      _in_condition[i] = 1;
  std::fill(_held.begin(), _held.end(), 0);
  for (const auto& m : _motions)
    if (!m.hinged()) // a hinged set moves as a plate
      for (auto i : m.ids)
        for (int k = 0; k < 6; ++k)
          if (m.kind == MotionKind::fixed || (k < 3 && m.components[k]))
            _held[6 * i + k] = 1;
  _held_dofs.clear();
  for (std::size_t i = 0; i < _p.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (_held[6 * i + k])
        _held_dofs.push_back(static_cast<std::int32_t>(3 * i + k));
  // spheres removed from the computation are held too (no reaction: they
  // have no link nor contact left)
  for (std::size_t i = 0; i < _removed.size(); ++i)
    if (_removed[i])
      std::fill(&_held[6 * i], &_held[6 * i] + 6, 1);
  _fold.assign(_held_dofs.size(), 0.0);
  _vold.assign(_held_dofs.size(), 0.0);
  _reac.assign(_held_dofs.size(), 0.0);
}

std::vector<std::int32_t>
DemSolver::select(const Particles& p, const std::function<bool(const std::array<double, 3>&)>& pred,
                  const std::string& what)
{
  std::vector<std::int32_t> ids;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (pred({p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]}))
      ids.push_back(static_cast<std::int32_t>(i));
  if (ids.empty())
    throw std::runtime_error("the region '" + what + "' selects no sphere");
  return ids;
}

void DemSolver::add_motion(ParticleMotion m)
{
  if (m.ids.empty())
    throw std::runtime_error("condition '" + m.name + "' has no sphere");
  if (m.kind != MotionKind::fixed && !m.value)
    throw std::runtime_error("condition '" + m.name + "' needs a history");
  for (auto i : m.ids)
    if (i < 0 || static_cast<std::size_t>(i) >= _p.size())
      throw std::runtime_error("condition '" + m.name + "': sphere index out of range");
  const bool has_axis = m.axis[0] != 0.0 || m.axis[1] != 0.0 || m.axis[2] != 0.0;
  if (has_axis && !(std::isfinite(m.axis[0]) && std::isfinite(m.axis[1]) && std::isfinite(m.axis[2])))
    throw std::runtime_error("condition '" + m.name + "': the hinge axis must be finite");
  if (has_axis && !m.hinged())
    throw std::runtime_error("condition '" + m.name
                             + "': a hinge axis needs a rotating velocity or displacement condition");
  for (const auto& f : _forces)
    if (f.plate)
      for (auto i : m.ids)
        if (std::find(f.ids.begin(), f.ids.end(), i) != f.ids.end())
          for (int k = 0; k < 3; ++k)
            if (f.direction[k] != 0.0 && (m.kind == MotionKind::fixed || m.hinged() || m.components[k]))
              throw std::runtime_error("condition '" + m.name + "' holds sphere " + std::to_string(i)
                                       + " of the loading plate '" + f.name
                                       + "' along the load: a plate's spheres must move freely along it");
  for (const auto& o : _motions)
  {
    if (!m.hinged() && !o.hinged())
      continue;
    for (auto i : m.ids)
      if (std::find(o.ids.begin(), o.ids.end(), i) != o.ids.end())
        throw std::runtime_error("condition '" + m.name + "' and condition '" + o.name + "' share sphere "
                                 + std::to_string(i) + ": a hinged (rotating) set shares no sphere");
  }
  // a hinged set's mean velocity, from which its first reaction is taken
  std::array<double, 3> v{0.0, 0.0, 0.0};
  double mass = 0.0;
  for (auto i : m.ids)
  {
    mass += _p.m[i];
    for (int k = 0; k < 3; ++k)
      v[k] += _p.m[i] * _p.v[3 * i + k];
  }
  for (int k = 0; k < 3; ++k)
    v[k] /= mass;
  _motions.push_back(std::move(m));
  _motion_reac.push_back({0.0, 0.0, 0.0});
  _motion_vprev.push_back(v);
  update_held();
}

void DemSolver::remove_motion(const std::string& name)
{
  const auto it = std::find_if(_motions.begin(), _motions.end(),
                               [&](const ParticleMotion& m) { return m.name == name; });
  if (it == _motions.end())
    throw std::runtime_error("remove_motion: no condition named '" + name + "'");
  _motion_reac.erase(_motion_reac.begin() + (it - _motions.begin()));
  _motion_vprev.erase(_motion_vprev.begin() + (it - _motions.begin()));
  _motions.erase(it);
  update_held();
}

void DemSolver::add_force(ParticleForce f)
{
  if (f.ids.empty())
    throw std::runtime_error("force '" + f.name + "' has no sphere");
  if (!f.value)
    throw std::runtime_error("force '" + f.name + "' needs a history");
  for (auto i : f.ids)
    if (i < 0 || static_cast<std::size_t>(i) >= _p.size())
      throw std::runtime_error("force '" + f.name + "': sphere index out of range");
  if (f.plate)
  {
    const double len = std::sqrt(dot3(f.direction.data(), f.direction.data()));
    if (!(len > 0.0) || !std::isfinite(len))
      throw std::runtime_error("force '" + f.name + "': a loading plate needs a non-zero, finite direction");
    for (auto i : f.ids)
      for (int k = 0; k < 3; ++k)
        if (_held[6 * i + k] && f.direction[k] != 0.0)
          throw std::runtime_error("force '" + f.name + "': sphere " + std::to_string(i)
                                   + " of the loading plate is held along the load by a condition; a plate's "
                                     "spheres must move freely along it");
    for (const auto& o : _motions)
      if (o.hinged())
        for (auto i : f.ids)
          if (std::find(o.ids.begin(), o.ids.end(), i) != o.ids.end())
            throw std::runtime_error("force '" + f.name + "': sphere " + std::to_string(i)
                                     + " of the loading plate moves with the hinged condition '" + o.name
                                     + "'; a plate's spheres must move freely");
  }
  for (auto i : f.ids)
    _in_condition[i] = 1;
  _forces.push_back(std::move(f));
  // external force arrays only once there is an external force
  _fext.resize(3 * _p.size(), 0.0);
  _fext_old.resize(3 * _p.size(), 0.0);
}

namespace
{
/// The motions of a plate (a set of spheres) along a unit direction d: its
/// translation, and (with `rotates`) its two rotations normal to d, whose
/// component along d is linear in the position across d, or with a
/// non-zero `axis` only the rotation about it (linear along d x axis;
/// none when d is along the axis). The rotation
/// modes are mass-orthonormalised (Gram-Schmidt); one the spheres do not
/// span (all on one line across d, or a single sphere) is dropped, as it
/// moves no sphere.
struct PlateModes
{
  double mass = 0.0;
  int nrot = 0;
  std::vector<std::array<double, 2>> phi; ///< per sphere, the rotation modes' v_d
};

/// e0, e1: an orthonormal pair normal to the unit d, the directions across
/// which a plate's rotations move its d component; with a non-zero axis,
/// e0 = d x axis / |d x axis| alone and e1 = 0 (spans nothing, dropped).
/// False when d lies along the axis: the hinge does not turn it.
bool rotation_directions(const double* d, const std::array<double, 3>& axis, double (&e)[2][3])
{
  auto cross = [](const double* a, const double* b, double* out)
  {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
  };
  const double a2 = dot3(axis.data(), axis.data());
  if (a2 > 0.0)
    cross(d, axis.data(), e[0]);
  else
  {
    double t[3] = {0.0, 0.0, 0.0};
    t[std::abs(d[0]) < 0.9 ? 0 : 1] = 1.0;
    const double td = dot3(t, d);
    for (int k = 0; k < 3; ++k)
      e[0][k] = t[k] - td * d[k];
  }
  const double n0 = std::sqrt(dot3(e[0], e[0]));
  if (!(n0 > 1e-12 * (a2 > 0.0 ? std::sqrt(a2) : 1.0)))
    return false;
  for (int k = 0; k < 3; ++k)
    e[0][k] /= n0;
  if (a2 > 0.0)
    std::fill(&e[1][0], &e[1][0] + 3, 0.0);
  else
    cross(d, e[0], e[1]);
  return true;
}

PlateModes plate_modes(const Particles& p, const std::vector<std::int32_t>& ids, const double* d,
                       bool rotates, const std::array<double, 3>& axis = {0.0, 0.0, 0.0})
{
  PlateModes pm;
  double c[3] = {0.0, 0.0, 0.0};
  for (auto i : ids)
  {
    pm.mass += p.m[i];
    for (int k = 0; k < 3; ++k)
      c[k] += p.m[i] * p.x[3 * i + k];
  }
  if (!rotates)
    return pm;
  for (int k = 0; k < 3; ++k)
    c[k] /= pm.mass;
  double e[2][3];
  if (!rotation_directions(d, axis, e))
    return pm;
  pm.phi.resize(ids.size());
  double s2 = 0.0;
  for (std::size_t q = 0; q < ids.size(); ++q)
  {
    const std::int32_t i = ids[q];
    const double r[3] = {p.x[3 * i] - c[0], p.x[3 * i + 1] - c[1], p.x[3 * i + 2] - c[2]};
    pm.phi[q] = {dot3(r, e[0]), dot3(r, e[1])};
    s2 += p.m[i] * (pm.phi[q][0] * pm.phi[q][0] + pm.phi[q][1] * pm.phi[q][1]);
  }
  const double tol = 1e-12 * s2;
  for (int r = 0; r < 2; ++r)
  {
    if (r == 1 && pm.nrot == 1)
    {
      double p01 = 0.0;
      for (std::size_t q = 0; q < ids.size(); ++q)
        p01 += p.m[ids[q]] * pm.phi[q][0] * pm.phi[q][1];
      for (auto& ph : pm.phi)
        ph[1] -= p01 * ph[0];
    }
    double n2 = 0.0;
    for (std::size_t q = 0; q < ids.size(); ++q)
      n2 += p.m[ids[q]] * pm.phi[q][r] * pm.phi[q][r];
    if (!(n2 > tol))
      continue;
    const double inv = 1.0 / std::sqrt(n2);
    for (auto& ph : pm.phi)
      ph[pm.nrot] = ph[r] * inv;
    ++pm.nrot;
  }
  return pm;
}

/// Sets the spheres' velocity components along d to vbar plus the plate's
/// rotations fitted (mass-weighted least squares) to their present ones.
void move_as_plate(Particles& p, const std::vector<std::int32_t>& ids, const double* d,
                   const PlateModes& pm, double vbar)
{
  double g[2] = {0.0, 0.0};
  for (int r = 0; r < pm.nrot; ++r)
    for (std::size_t q = 0; q < ids.size(); ++q)
      g[r] += p.m[ids[q]] * pm.phi[q][r] * dot3(d, &p.v[3 * ids[q]]);
  for (std::size_t q = 0; q < ids.size(); ++q)
  {
    const std::int32_t i = ids[q];
    double target = vbar;
    for (int r = 0; r < pm.nrot; ++r)
      target += g[r] * pm.phi[q][r];
    const double dv = target - dot3(d, &p.v[3 * i]);
    for (int k = 0; k < 3; ++k)
      p.v[3 * i + k] += dv * d[k];
  }
}
} // namespace

void DemSolver::tie_plates()
{
  for (const auto& f : _forces)
  {
    if (!f.plate)
      continue;
    const double len = std::sqrt(dot3(f.direction.data(), f.direction.data()));
    const double d[3] = {f.direction[0] / len, f.direction[1] / len, f.direction[2] / len};
    const auto pm = plate_modes(_p, f.ids, d, f.plate_rotates);
    double mv = 0.0;
    for (auto i : f.ids)
      mv += _p.m[i] * dot3(d, &_p.v[3 * i]);
    move_as_plate(_p, f.ids, d, pm, mv / pm.mass);
  }
}

void DemSolver::move_hinged(std::size_t motion, double t_half, double t_new, bool begin)
{
  const auto& m = _motions[motion];
  for (int k = 0; k < 3; ++k)
  {
    if (!m.components[k])
      continue;
    const double d[3] = {k == 0 ? 1.0 : 0.0, k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0};
    const auto pm = plate_modes(_p, m.ids, d, true, m.axis);
    double& vprev = _motion_vprev[motion][k];
    double vbar = 0.0;
    if (m.kind == MotionKind::velocity)
      vbar = m.value(t_half);
    else if (!begin)
      vbar = vprev; // at the full step a displacement's mean keeps its half-step
                    // velocity, as held translations do (the kick is not theirs)
    else
    {
      for (auto i : m.ids)
        vbar += _p.m[i] * (_p.x0[3 * i + k] + m.value(t_new) - _p.x[3 * i + k]);
      vbar /= pm.mass * _dt;
    }
    if (begin)
    {
      // the reaction on the plate's mean motion, as for held translations:
      // M (v(n+1/2) - v(n-1/2)) / dt = F(n) - c M v(n+1/2) + R, and its
      // work over the drift R v(n+1/2) dt
      double force = 0.0;
      for (auto i : m.ids)
        force += _p.f[3 * i + k] + (_fext.empty() ? 0.0 : _fext[3 * i + k]);
      const double R = pm.mass * (vbar - vprev) / _dt - force + _c * pm.mass * vbar;
      _motion_reac[motion][k] = R;
      _e.prescribed_work += _dt * R * vbar;
      vprev = vbar;
    }
    move_as_plate(_p, m.ids, d, pm, vbar);
  }
}

} // namespace dembridge::dem
