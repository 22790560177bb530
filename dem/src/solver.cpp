// DemSolver: the velocity-Verlet step, damping, the energy budget and the
// reactions (solver.h); its conditions are in conditions.cpp.
#include "dembridge/dem/solver.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <omp.h>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "addons.h"
#include "force_loop.h"
#include "threads.h"

namespace dembridge::dem
{
using impl::dot3;

DemSolver::DemSolver(Particles& p, Links& l, const Material& mat, double dt, double damping,
                     double skin)
    : _p(p), _l(l), _mat(mat), _nl(skin), _scratch(std::make_unique<ForceScratch>()), _dt(dt),
      _c(0.0)
{
  mat.validate();
  if (mat.crack_closure > 0.0)
    _nl.close_cracks(mat.crack_closure);
  if (!(dt > 0.0) || !std::isfinite(dt))
    throw std::runtime_error("time step " + std::to_string(dt) + " s: must be > 0");
  set_damping(damping);
  _held.assign(6 * p.size(), 0);
  _removed.assign(p.size(), 0);
  _in_condition.assign(p.size(), 0);
  // the rate effect's per-link factors (none without it: a reused set of
  // links loses factors of an earlier run)
  if (mat.rate_fc > 0.0 && l.strength.size() != l.size())
    l.strength.assign(l.size(), 1.0);
  else if (!(mat.rate_fc > 0.0))
    l.strength.clear();
  if (mat.rate_fc > 0.0 && mat.rate_filter > 0.0 && l.rate.size() != l.size())
    l.rate.assign(l.size(), 0.0);
  else if (!(mat.rate_fc > 0.0 && mat.rate_filter > 0.0))
    l.rate.clear();
  if (mat.compaction.on() && l.compaction.size() != l.size())
    l.compaction.assign(l.size(), 0.0);
  else if (!mat.compaction.on())
    l.compaction.clear();
  if (mat.compaction.gated() && l.compaction_onset.size() != l.size())
    l.compaction_onset.assign(l.size(), mat.compaction.onset);
  else if (!mat.compaction.gated())
    l.compaction_onset.clear();
}

void DemSolver::set_domain(const std::array<double, 3>& lo, const std::array<double, 3>& hi)
{
  for (int k = 0; k < 3; ++k)
    if (!(hi[k] > lo[k]) || !std::isfinite(lo[k]) || !std::isfinite(hi[k]))
      throw std::runtime_error("domain: hi must exceed lo on every axis, both finite (axis " + std::to_string(k)
                               + ": " + std::to_string(lo[k]) + " to " + std::to_string(hi[k]) + " m)");
  _domain_set = true;
  _domain_lo = lo;
  _domain_hi = hi;
}

void DemSolver::remove_escaped()
{
  // the spheres outside the domain at x(n+1): their velocities are the
  // half-step ones, v(n+1/2), those they leave with
  const std::size_t n = _p.size();
  std::vector<std::int32_t> gone;
  for (std::size_t i = 0; i < n; ++i)
  {
    if (_removed[i] || _in_condition[i]) // (_in_condition: set with the conditions, update_held)
      continue;
    const double* x = &_p.x[3 * i];
    for (int k = 0; k < 3; ++k)
      if (x[k] < _domain_lo[k] || x[k] > _domain_hi[k])
      {
        gone.push_back(static_cast<std::int32_t>(i));
        break;
      }
  }
  if (gone.empty())
    return;
  // the energy their links and contacts (with spheres and bodies) hold
  // goes with them: the links and pairs they end, summed alone, and what
  // the add-ons (bodies' contacts) hold before and after
  auto addons_energy = [&]
  {
    double e = 0.0;
    for (const auto& a : _addons)
      a->stored_energy(view(), e);
    return e;
  };
  const double addons_before = addons_energy();
  for (auto i : gone)
    _removed[i] = 1;
  std::vector<std::size_t> links_ended, pairs_ended;
  for (std::size_t k = 0; k < _l.size(); ++k)
    if (_l.state[k] == LinkState::intact && (_removed[_l.a[k]] || _removed[_l.b[k]]))
      links_ended.push_back(k);
  for (std::size_t q = 0; q < _nl.size(); ++q)
    if (_nl.touching[q] && (_removed[_nl.a[q]] || _removed[_nl.b[q]]))
      pairs_ended.push_back(q);
  double stored = elastic_energy_of(_p, _l, _nl, _mat, links_ended, pairs_ended);
  for (const auto& a : _addons)
    a->spheres_removed(view());
  for (auto k : links_ended)
    _l.state[k] = LinkState::removed;
  for (auto q : pairs_ended)
  {
    _nl.touching[q] = 0;
    for (int k = 0; k < 3; ++k)
      _nl.fs[3 * q + k] = 0.0;
    if (_nl.rolling())
      for (int k = 0; k < 3; ++k)
        _nl.mr[3 * q + k] = 0.0;
  }
  stored += addons_before - addons_energy();
  double kinetic = 0.0;
  for (auto i : gone)
  {
    const double* v = &_p.v[3 * i];
    const double* w = &_p.w[3 * i];
    kinetic += 0.5 * _p.m[i] * dot3(v, v) + 0.5 * _p.inertia[i] * dot3(w, w);
    _gone.mass += _p.m[i];
    for (int k = 0; k < 3; ++k)
    {
      _gone.momentum[k] += _p.m[i] * v[k];
      _p.v[3 * i + k] = _p.w[3 * i + k] = 0.0;
    }
  }
  _gone.count += gone.size();
  _gone.kinetic += kinetic;
  _gone.elastic += stored;
  _e.removed += kinetic + stored;
  // held from now on; the held dofs of the conditions (and their
  // histories of this step, for the reactions) are unchanged
  for (auto i : gone)
    std::fill(&_held[6 * i], &_held[6 * i] + 6, 1);
  const double t0 = omp_get_wtime();
  _nl.remove(_p.x, gone, _removed);
  _time.neighbours += omp_get_wtime() - t0;
}

DemSolver::~DemSolver() = default;

std::size_t DemSolver::bytes() const
{
  return _held.capacity() + (_held_dofs.capacity()) * sizeof(std::int32_t)
         + (_fext.capacity() + _fext_old.capacity() + _reac.capacity() + _fold.capacity()
            + _vold.capacity() + _part.capacity())
               * sizeof(double)
         + _scratch->bytes() + _nl.bytes();
}

void DemSolver::set_damping(double c)
{
  if (!(c >= 0.0) || !std::isfinite(c))
    throw std::runtime_error("damping " + std::to_string(c) + " 1/s: must be >= 0");
  _c = c;
}

namespace
{
void external(const std::vector<ParticleForce>& forces, double t, std::vector<double>& fext)
{
  std::fill(fext.begin(), fext.end(), 0.0);
  for (const auto& f : forces)
  {
    const double v = f.value(t);
    for (auto i : f.ids)
      for (int k = 0; k < 3; ++k)
        fext[3 * i + k] += f.direction[k] * v;
  }
}
} // namespace

void DemSolver::start()
{
  _nl.update(_p.x, _p.r, _l, _removed);
  compute_forces(_p, _l, _nl, _mat, 0.0, _counters, *_scratch);
  if (_bars)
    _bars->touch(_bodies ? &_bodies->bodies : nullptr);
  for (const auto& a : _addons)
    a->start(view());
  if (!_forces.empty())
    external(_forces, _t, _fext);
  _e = DemEnergy{};
  const DemEnergy e = energy();
  _e.initial = e.kinetic + e.elastic + e.body_kinetic + e.body_contact + e.bar_kinetic + e.bar_elastic
               + e.bar_plastic + e.bar_opening + e.addons;
  _started = true;
}

void DemSolver::kick(double h)
{
  const std::size_t n = _p.size();
  const double ch = _c * h;
  const double* fext = _fext.empty() ? nullptr : _fext.data();
#pragma omp parallel for schedule(static) num_threads(impl::threads_for(n))
  for (std::size_t i = 0; i < n; ++i)
  {
    const double im = h / _p.m[i], iI = h / _p.inertia[i];
    for (int k = 0; k < 3; ++k)
    {
      if (!_held[6 * i + k])
        _p.v[3 * i + k] += (_p.f[3 * i + k] + (fext ? fext[3 * i + k] : 0.0)) * im - ch * _p.v[3 * i + k];
      if (!_held[6 * i + 3 + k])
        _p.w[3 * i + k] += _p.t[3 * i + k] * iI - ch * _p.w[3 * i + k];
    }
  }
}

void DemSolver::step()
{
  begin_step();
  end_step();
}

void DemSolver::begin_step()
{
  const double t0 = omp_get_wtime();
  const double dt = _dt, t_new = _t + dt;
  // v(n) and F(n) of the held translations, for their reactions
  for (std::size_t q = 0; q < _held_dofs.size(); ++q)
  {
    const std::int32_t d = _held_dofs[q];
    _fold[q] = _p.f[d] + (_fext.empty() ? 0.0 : _fext[d]);
    _vold[q] = _p.v[d];
  }
  for (const auto& a : _addons)
    a->begin(view());
  kick(0.5 * dt);
  for (const auto& a : _addons)
    a->kick(view(), 0.5 * dt);
  tie_plates();
  for (const auto& m : _motions)
  {
    if (m.hinged())
    {
      move_hinged(&m - _motions.data(), _t + 0.5 * dt, t_new, true);
      continue;
    }
    for (auto i : m.ids)
      for (int k = 0; k < 3; ++k)
      {
        double& v = _p.v[3 * i + k];
        if (m.kind == MotionKind::fixed)
        {
          v = 0.0;
          _p.w[3 * i + k] = 0.0;
        }
        else if (m.components[k])
          v = m.kind == MotionKind::velocity
                  ? m.value(_t + 0.5 * dt)
                  : (_p.x0[3 * i + k] + m.value(t_new) - _p.x[3 * i + k]) / dt;
      }
  }
  _in_step = true;
  _time.integration += omp_get_wtime() - t0;
}

DemSolver::Drift DemSolver::drift()
{
  const std::size_t n = _p.size();
  const double dt = _dt;
  const bool loaded = !_forces.empty();
  const std::vector<double>& fext_old = _fext_old;
  // the work of external forces and of damping summed in fixed blocks (the
  // same sums whatever the thread count)
  constexpr std::size_t block = 1024;
  const std::size_t nb = (n + block - 1) / block;
  _part.resize(3 * nb);
  // moves by multiples of the position quantum q (Particles::quantum):
  // (d + C) - C rounds d to a multiple of q for |d| < 2^51 q, C = 1.5 2^52 q,
  // and x + that is exact, so equal velocities move spheres by equal bits
  const double quantum = _p.quantum;
  const double C = quantum > 0.0 ? std::ldexp(1.5, 52) * quantum : 0.0;
#pragma omp parallel for schedule(static) num_threads(impl::threads_for(n))
  for (std::size_t b = 0; b < nb; ++b)
  {
    double we = 0.0, wd = 0.0, ke = 0.0;
    for (std::size_t i = b * block; i < std::min(n, (b + 1) * block); ++i)
    {
      double v2 = 0.0, w2 = 0.0;
      for (int k = 0; k < 3; ++k)
      {
        const double vh = _p.v[3 * i + k];
        const double dx = quantum > 0.0 ? (dt * vh + C) - C : dt * vh;
        _p.x[3 * i + k] += dx;
        if (loaded)
          we += dx * 0.5 * (fext_old[3 * i + k] + _fext[3 * i + k]);
        v2 += vh * vh;
        w2 += _p.w[3 * i + k] * _p.w[3 * i + k];
      }
      wd += dt * _c * (_p.m[i] * v2 + _p.inertia[i] * w2);
      ke += 0.5 * (_p.m[i] * v2 + _p.inertia[i] * w2);
    }
    _part[3 * b] = we;
    _part[3 * b + 1] = wd;
    _part[3 * b + 2] = ke;
  }
  Drift d;
  for (std::size_t b = 0; b < nb; ++b)
  {
    d.external_work += _part[3 * b];
    d.damping += _part[3 * b + 1];
    d.kinetic += _part[3 * b + 2];
  }
  return d;
}

double DemSolver::held_reactions()
{
  // m (v_new - v_old) = dt/2 (F_old + F_new) + dt R
  const double dt = _dt;
  double w_presc = 0.0;
  for (std::size_t q = 0; q < _held_dofs.size(); ++q)
  {
    const std::int32_t d = _held_dofs[q];
    const std::size_t i = static_cast<std::size_t>(d) / 3;
    const double vh = _p.v[d];
    const double F_new = _p.f[d] + (_fext.empty() ? 0.0 : _fext[d]) - _c * _p.m[i] * vh;
    const double F_old = _fold[q] - _c * _p.m[i] * vh;
    const double R = _p.m[i] * (vh - _vold[q]) / dt - 0.5 * (F_old + F_new);
    w_presc += dt * vh * R;
    _reac[q] = R;
  }
  return w_presc;
}

void DemSolver::check_finite() const
{
  // any NaN or infinity makes the sum non-finite, whatever the order
  const std::size_t n = _p.size();
  double check = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : check) num_threads(impl::threads_for(n))
  for (std::size_t i = 0; i < 3 * n; ++i)
    check += _p.x[i] + _p.v[i] + _p.w[i];
  for (const auto& a : _addons)
    a->check_finite(_t, _steps);
  if (std::isfinite(check))
    return;
  std::size_t bad = 0;
  while (bad < 3 * n && std::isfinite(_p.x[bad]) && std::isfinite(_p.v[bad]) && std::isfinite(_p.w[bad]))
    ++bad;
  std::ostringstream s;
  s << "non-finite position or velocity of sphere " << bad / 3 << " at t = " << _t << " s (step "
    << _steps << "): the run is unstable; reduce the time step";
  throw std::runtime_error(s.str());
}

void DemSolver::end_step()
{
  if (!_in_step)
    throw std::runtime_error("DemSolver::end_step without begin_step");
  _in_step = false;
  const double t0 = omp_get_wtime();
  const double dt = _dt, t_new = _t + dt;
  std::swap(_fext_old, _fext); // no allocation in the step loop
  if (!_forces.empty())
    external(_forces, t_new, _fext);
  const Drift moved = drift();
  double w_damp_addons = 0.0;
  for (const auto& a : _addons)
    w_damp_addons += a->drift(view());
  // fragments leave here, between the drift and the forces: both halves of
  // a kick with a force between a leaving sphere and another then act on
  // both (the first, F(n), before; the second, F(n+1), not at all), so
  // momentum is kept exactly
  if (_domain_set)
    remove_escaped();
  const double w_ext = moved.external_work, w_damp = moved.damping + w_damp_addons;
  const double t1 = omp_get_wtime();
  // the movers' pairs are merged with the pairs of the links the force loop
  // breaks, in one pass (compute_forces: add_broken_links)
  _nl.update(_p.x, _p.r, _l, _removed, true);
  const double t2 = omp_get_wtime();
  const double contacts_before = _counters.contact_seconds, merge_before = _counters.neighbour_seconds;
  compute_forces(_p, _l, _nl, _mat, dt, _counters, *_scratch);
  const double t3 = omp_get_wtime();
  for (const auto& a : _addons)
  {
    const double ta = omp_get_wtime();
    a->forces(view(), _e);
    _time.*(a->time_slot()) += omp_get_wtime() - ta;
  }
  const double t4 = omp_get_wtime();
  const double merge = _counters.neighbour_seconds - merge_before; // the list's merge in the force loop
  _time.neighbours += t2 - t1 + merge;
  _time.forces += t3 - t2 - merge;
  _time.contacts += _counters.contact_seconds - contacts_before;
  double w_presc = held_reactions();
  for (const auto& a : _addons)
    w_presc += a->reactions(view());
  kick(0.5 * dt);
  for (const auto& a : _addons)
    a->kick(view(), 0.5 * dt);
  tie_plates();
  for (const auto& m : _motions)
    if (m.kind == MotionKind::velocity && !m.hinged())
      for (auto i : m.ids)
        for (int k = 0; k < 3; ++k)
          if (m.components[k])
            _p.v[3 * i + k] = m.value(t_new);
  for (std::size_t q = 0; q < _motions.size(); ++q)
    if (_motions[q].hinged())
      move_hinged(q, t_new, t_new, false);
  _t = t_new;
  ++_steps;
  _e.external_work += w_ext;
  _e.damping += w_damp;
  _e.prescribed_work += w_presc;
  check_finite();
  if (_guard.on())
  {
    // every step, the cheap half of the guard: the kinetic energy (at the
    // half step) cannot exceed the initial energy plus the work done, as the
    // stored and dissipated energies are >= 0. The work of prescribed
    // velocities is booked through their reactions, to within a factor 2 of
    // the kinetic energy they impart in the steps after an impulsive start
    // (measured), hence the factor 10.
    const double budget = _e.initial + std::abs(_e.external_work) + std::abs(_e.prescribed_work);
    if (budget > 0.0 && moved.kinetic > 10.0 * budget)
      energy_runaway(moved.kinetic, budget);
    if (_guard.due(_steps))
      check_energy();
  }
  _time.integration += (t1 - t0) + (omp_get_wtime() - t4);
}

void DemSolver::check_energy() const
{
  const DemEnergy e = energy();
  const double work = e.external_work + e.prescribed_work;
  const double scale = e.initial + std::abs(e.external_work) + std::abs(e.prescribed_work) + e.kinetic + e.elastic
                       + e.body_kinetic + e.body_contact + e.bar_kinetic + e.bar_elastic + std::abs(e.addons);
  _guard.check({_t, _steps, "the energy", "kinetic + elastic", e.kinetic + e.elastic, e.initial, work, e.imbalance(),
                scale});
}

void DemSolver::energy_runaway(double kinetic, double budget) const
{
  std::ostringstream s;
  s << "the energy grows without cause at t = " << _t << " s (step " << _steps << "): kinetic energy "
    << kinetic << " J against initial + work " << budget
    << " J (more than 10 x): the run is unstable; reduce the time step";
  throw std::runtime_error(s.str());
}

void DemSolver::set_energy_guard(double margin, std::int64_t every)
{
  _guard.set(margin, every);
}

DemEnergy DemSolver::energy() const
{
  DemEnergy e = _e;
  e.kinetic = impl::block_sum(_p.size(),
                              [&](std::size_t i)
                              {
                                return 0.5 * _p.m[i] * dot3(&_p.v[3 * i], &_p.v[3 * i])
                                       + 0.5 * _p.inertia[i] * dot3(&_p.w[3 * i], &_p.w[3 * i]);
                              });
  e.elastic = elastic_energy(_p, _l, _nl, _mat);
  e.softening = softening_energy(_p, _l, _mat);
  e.compaction = compaction_energy(_l, _mat);
  e.breakage = _counters.breakage;
  e.friction = _counters.friction;
  for (const auto& a : _addons)
    a->energy(view(), e);
  return e;
}

std::array<double, 3> DemSolver::reaction(const std::string& name) const
{
  for (const auto& m : _motions)
    if (m.name == name)
    {
      if (m.hinged())
        return _motion_reac[&m - _motions.data()];
      std::array<double, 3> r{0, 0, 0};
      for (auto i : m.ids)
        for (int k = 0; k < 3; ++k)
        {
          const auto it = std::lower_bound(_held_dofs.begin(), _held_dofs.end(), 3 * i + k);
          if (it != _held_dofs.end() && *it == 3 * i + k)
            r[k] += _reac[it - _held_dofs.begin()];
        }
      return r;
    }
  throw std::runtime_error("no boundary condition named '" + name + "'");
}

} // namespace dembridge::dem
