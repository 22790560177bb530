#include "dembridge/shell/explicit.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace dembridge::shell
{

std::vector<std::int32_t>
select_nodes(std::span<const double> x,
             const std::function<bool(const std::array<double, 3>&)>& pred,
             const std::string& what)
{
  std::vector<std::int32_t> nodes;
  const std::size_t n = x.size() / 3;
  for (std::size_t i = 0; i < n; ++i)
    if (pred({x[3 * i], x[3 * i + 1], x[3 * i + 2]}))
      nodes.push_back(static_cast<std::int32_t>(i));
  if (nodes.empty())
    throw std::runtime_error("the selection '" + what
                             + "' contains no node: check its region against the mesh");
  return nodes;
}

std::vector<std::int32_t> node_dofs(std::span<const std::int32_t> nodes, int bs,
                                    std::span<const int> components)
{
  std::vector<std::int32_t> dofs;
  dofs.reserve(nodes.size() * components.size());
  for (auto n : nodes)
    for (int c : components)
    {
      if (c < 0 || c >= bs)
        throw std::runtime_error("dof component " + std::to_string(c)
                                 + " outside [0, " + std::to_string(bs) + ")");
      dofs.push_back(n * bs + c);
    }
  return dofs;
}

ExplicitSolver::ExplicitSolver(std::vector<double> mass, InternalForceFn f_int,
                               double dt, double damping)
    : _m(std::move(mass)), _f_int(std::move(f_int)), _dt(dt), _c(damping)
{
  if (!(dt > 0.0) || !std::isfinite(dt))
    throw std::runtime_error("time step " + std::to_string(dt) + " s: must be > 0");
  set_damping(damping);
  for (std::size_t i = 0; i < _m.size(); ++i)
    if (!(_m[i] > 0.0))
      throw std::runtime_error("lumped mass of dof " + std::to_string(i)
                               + " is " + std::to_string(_m[i]) + ": must be > 0");
  const std::size_t n = _m.size();
  _u.assign(n, 0.0);
  _v.assign(n, 0.0);
  _a.assign(n, 0.0);
  _fint.assign(n, 0.0);
  _fext.assign(n, 0.0);
  _fext_new.assign(n, 0.0);
  _r.assign(n, 0.0);
  _v_old.assign(n, 0.0);
  _prescribed.assign(n, 0);
}

void ExplicitSolver::set_damping(double c)
{
  if (!(c >= 0.0) || !std::isfinite(c))
    throw std::runtime_error("damping " + std::to_string(c) + " 1/s: must be >= 0");
  _c = c;
}

void ExplicitSolver::add_motion(PrescribedMotion m)
{
  if (m.dofs.empty())
    throw std::runtime_error("prescribed motion '" + m.name + "' has no dof");
  if (m.kind != MotionKind::fixed && !m.value)
    throw std::runtime_error("prescribed motion '" + m.name + "' needs a history");
  for (auto d : m.dofs)
  {
    if (d < 0 || static_cast<std::size_t>(d) >= _m.size())
      throw std::runtime_error("prescribed motion '" + m.name + "': dof "
                               + std::to_string(d) + " out of range");
    _prescribed[d] = 1;
  }
  _motions.push_back(std::move(m));
}

void ExplicitSolver::remove_motion(const std::string& name)
{
  const auto it = std::find_if(_motions.begin(), _motions.end(),
                               [&](const PrescribedMotion& m) { return m.name == name; });
  if (it == _motions.end())
    throw std::runtime_error("remove_motion: no prescribed motion named '" + name + "'");
  const std::vector<std::int32_t> freed = it->dofs;
  _motions.erase(it);
  for (auto d : freed)
    _prescribed[d] = 0;
  for (const auto& m : _motions)
    for (auto d : m.dofs)
      _prescribed[d] = 1;
  for (auto d : freed)
    if (!_prescribed[d])
    {
      _a[d] = (_fext[d] - _fint[d] - _c * _m[d] * _v[d]) / _m[d];
      _r[d] = 0.0;
    }
}

void ExplicitSolver::add_load(NodalLoad l)
{
  if (l.dofs.empty())
    throw std::runtime_error("load '" + l.name + "' has no dof");
  if (l.weights.size() != l.dofs.size())
    throw std::runtime_error("load '" + l.name + "': weights and dofs differ in size");
  if (!l.value)
    throw std::runtime_error("load '" + l.name + "' needs a history");
  for (auto d : l.dofs)
    if (d < 0 || static_cast<std::size_t>(d) >= _m.size())
      throw std::runtime_error("load '" + l.name + "': dof " + std::to_string(d)
                               + " out of range");
  _loads.push_back(std::move(l));
}

void ExplicitSolver::external_forces(double t, std::span<double> f) const
{
  std::fill(f.begin(), f.end(), 0.0);
  for (const auto& l : _loads)
  {
    const double val = l.value(t);
    for (std::size_t k = 0; k < l.dofs.size(); ++k)
      f[l.dofs[k]] += l.weights[k] * val;
  }
}

void ExplicitSolver::set_state(std::span<const double> u, std::span<const double> v)
{
  if (u.size() != _m.size() || v.size() != _m.size())
    throw std::runtime_error("set_state: size mismatch with the mass vector");
  std::copy(u.begin(), u.end(), _u.begin());
  std::copy(v.begin(), v.end(), _v.begin());
  for (const auto& m : _motions)
    for (auto d : m.dofs)
    {
      if (m.kind == MotionKind::fixed)
        _u[d] = _v[d] = 0.0;
      else if (m.kind == MotionKind::displacement)
        _u[d] = m.value(_t);
      else
        _v[d] = m.value(_t);
    }
  _f_int(_u, _fint);
  external_forces(_t, _fext);
  for (std::size_t i = 0; i < _m.size(); ++i)
    _a[i] = _prescribed[i] ? 0.0 : (_fext[i] - _fint[i] - _c * _m[i] * _v[i]) / _m[i];
  _e = EnergyBudget{};
  const auto e = energy();
  _e.initial = e.kinetic + e.strain;
}

void ExplicitSolver::begin_step()
{
  const std::size_t n = _m.size();
  const double dt = _dt, t_new = _t + dt;
  // net force at the old time (for reactions: m a = f + R) and v(n)
  for (std::size_t i = 0; i < n; ++i)
  {
    _r[i] = _fext[i] - _fint[i];
    _v_old[i] = _v[i];
  }
  // half-step velocity on free dofs, then the motions
  for (std::size_t i = 0; i < n; ++i)
    _v[i] = _prescribed[i] ? 0.0 : _v[i] + 0.5 * dt * _a[i];
  for (const auto& m : _motions)
    for (auto d : m.dofs)
      switch (m.kind)
      {
      case MotionKind::fixed:
        _v[d] = 0.0;
        break;
      case MotionKind::velocity:
        _v[d] = m.value(_t + 0.5 * dt);
        break;
      case MotionKind::displacement:
        _v[d] = (m.value(t_new) - _u[d]) / dt;
        break;
      }
  _in_step = true;
}

void ExplicitSolver::end_step()
{
  if (!_in_step)
    throw std::runtime_error("ExplicitSolver::end_step without begin_step");
  _in_step = false;
  const std::size_t n = _m.size();
  const double dt = _dt, t_new = _t + dt;
  double w_ext = 0.0, w_damp = 0.0;
  external_forces(t_new, _fext_new);
  for (std::size_t i = 0; i < n; ++i)
  {
    const double vh = _v[i];
    const double du = dt * vh;
    _u[i] += du;
    w_ext += du * 0.5 * (_fext[i] + _fext_new[i]);
    w_damp += dt * _c * _m[i] * vh * vh;
  }
  _f_int(_u, _fint);
  std::swap(_fext, _fext_new);

  double w_presc = 0.0;
  for (std::size_t i = 0; i < n; ++i)
  {
    const double vh = _v[i];
    const double fnet = _fext[i] - _fint[i] - _c * _m[i] * vh;
    if (!_prescribed[i])
    {
      _a[i] = fnet / _m[i];
      _v[i] = vh + 0.5 * dt * _a[i];
      _r[i] = 0.0;
    }
    else
    {
      // reaction: m (v_new - v_old) = dt/2 (f_old + f_new) + dt R
      const double r = _m[i] * (vh - _v_old[i]) / dt - 0.5 * (_r[i] - _c * _m[i] * vh + fnet);
      w_presc += dt * vh * r;
      _r[i] = r;
      _a[i] = 0.0;
    }
  }
  for (const auto& m : _motions)
    if (m.kind == MotionKind::velocity)
      for (auto d : m.dofs)
        _v[d] = m.value(t_new);

  _t = t_new;
  ++_steps;
  _e.external_work += w_ext;
  _e.damping += w_damp;
  _e.prescribed_work += w_presc;

  double check = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    check += _u[i] + _v[i];
  if (!std::isfinite(check))
  {
    std::size_t bad = 0;
    while (bad < n && std::isfinite(_u[bad]) && std::isfinite(_v[bad]))
      ++bad;
    std::ostringstream msg;
    msg << "non-finite displacement or velocity at dof " << bad << " at t = " << _t
        << " s (step " << _steps
        << "): the run is unstable; reduce the time step or check the loads";
    throw std::runtime_error(msg.str());
  }
  if (_guard.due(_steps))
  {
    const EnergyBudget e = energy();
    const double work = e.external_work + e.prescribed_work;
    const double scale = e.initial + std::abs(e.external_work) + std::abs(e.prescribed_work) + e.kinetic + e.strain;
    _guard.check({_t, _steps, "the energy", "kinetic + strain", e.kinetic + e.strain, e.initial, work, e.imbalance(),
                  scale});
  }
}

void ExplicitSolver::set_energy_guard(double margin, std::int64_t every)
{
  _guard.set(margin, every);
}

void ExplicitSolver::step()
{
  begin_step();
  end_step();
}

EnergyBudget ExplicitSolver::energy() const
{
  EnergyBudget e = _e;
  e.kinetic = 0.0;
  e.strain = 0.0;
  for (std::size_t i = 0; i < _m.size(); ++i)
  {
    e.kinetic += 0.5 * _m[i] * _v[i] * _v[i];
    e.strain += 0.5 * _u[i] * _fint[i];
  }
  return e;
}

} // namespace dembridge::shell
