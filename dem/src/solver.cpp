#include "dembridge/dem/solver.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace dembridge::dem
{
namespace
{
inline double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross3(const double* a, const double* b)
{
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

/// Equation [1] factors for contacts: K_n = E S / (R_a + R_b) * cn, K_s = K_n * cs.
struct ContactFactors
{
  double cn, cs;
};
ContactFactors contact_factors(const Material& m)
{
  const auto k = link_stiffness(m.youngs_modulus, m.poisson_ratio, 1.0, 1.0, m.micro);
  return {k.kn / m.youngs_modulus, k.ks / k.kn};
}

inline void apply(Particles& p, std::int32_t i, std::int32_t j, const double* n, double fn,
                  const Vec3& fs, double la, double lb)
{
  const auto tq = shear_torques({n[0], n[1], n[2]}, fs, la, lb);
  for (int k = 0; k < 3; ++k)
  {
    const double fb = -fn * n[k] + fs[k];
    p.f[3 * j + k] += fb;
    p.f[3 * i + k] -= fb;
    p.t[3 * i + k] += tq[0][k];
    p.t[3 * j + k] += tq[1][k];
  }
}
} // namespace

void compute_forces(Particles& p, Links& l, NeighbourList& nl, const Material& mat, double dt,
                    ForceCounters& c)
{
  std::vector<double> rot;
  compute_forces(p, l, nl, mat, dt, c, rot);
}

void compute_forces(Particles& p, Links& l, NeighbourList& nl, const Material& mat, double dt,
                    ForceCounters& c, std::vector<double>& rot)
{
  // each sphere's rotation over the step, once
  rot.resize(9 * p.size());
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    const Mat3 r = rotation_matrix({p.w[3 * i] * dt, p.w[3 * i + 1] * dt, p.w[3 * i + 2] * dt});
    std::copy(r.begin(), r.end(), rot.begin() + 9 * i);
  }
  auto R = [&](std::int32_t i)
  {
    Mat3 r;
    std::copy(rot.begin() + 9 * i, rot.begin() + 9 * i + 9, r.begin());
    return r;
  };
  std::fill(p.f.begin(), p.f.end(), 0.0);
  std::fill(p.t.begin(), p.t.end(), 0.0);
  const LinkLaw base = mat.law(1.0, 1.0, 1.0);

  // cohesive links
  for (std::size_t k = 0; k < l.size(); ++k)
  {
    if (l.state[k] != LinkState::intact)
      continue;
    const std::int32_t i = l.a[k], j = l.b[k];
    double n[3];
    for (int q = 0; q < 3; ++q)
      n[q] = p.x[3 * j + q] - p.x[3 * i + q];
    const double D = std::sqrt(dot3(n, n));
    for (double& v : n)
      v /= D;
    LinkLaw law = base;
    law.kn = l.kn[k];
    law.ks = l.ks[k];
    law.s_int = l.s_int[k];
    const double delta = D - l.d0[k];
    const NormalForce nf = link_normal_force(delta, l.delta_max[k], law);
    double* fs_old = &l.fs[3 * k];
    const double wk = l.weight.empty() ? 1.0 : l.weight[k];
    if (nf.state == NormalState::broken)
    {
      l.state[k] = LinkState::broken_tension;
      l.delta_max[k] = nf.delta_max;
      c.breakage += wk * 0.5 * dot3(fs_old, fs_old) / law.ks;
      std::fill(fs_old, fs_old + 3, 0.0);
      continue;
    }
    l.delta_max[k] = nf.delta_max;
    const double la = D * p.r[i] / (p.r[i] + p.r[j]), lb = D - la;
    const Mat3 ra = R(i), rb = R(j);
    const double fa = p.r[i] / (p.r[i] + p.r[j]);
    const Vec3 nn{n[0], n[1], n[2]};
    const Vec3 du_s = shear_increment({l.n[3 * k], l.n[3 * k + 1], l.n[3 * k + 2]}, nn, ra, rb, D, fa);
    const Vec3 fs_rot = rotate_shear({fs_old[0], fs_old[1], fs_old[2]}, ra, rb, fa, nn);
    const ShearForce sf = link_shear_force(fs_rot, du_s, nf.fn, law);
    if (sf.exceeded)
    {
      // Mohr-Coulomb reached: the link breaks and its elastic energy is
      // released; if the spheres touch, a contact takes over from zero shear.
      l.state[k] = LinkState::broken_shear;
      c.breakage += wk * (0.5 * nf.fn * delta + 0.5 * (sf.fs[0] * sf.fs[0] + sf.fs[1] * sf.fs[1]
                                                       + sf.fs[2] * sf.fs[2]) / law.ks);
      std::fill(fs_old, fs_old + 3, 0.0);
      continue;
    }
    for (int q = 0; q < 3; ++q)
    {
      fs_old[q] = sf.fs[q];
      l.n[3 * k + q] = n[q];
    }
    if (wk == 1.0)
      apply(p, i, j, n, nf.fn, sf.fs, la, lb);
    else
      apply(p, i, j, n, wk * nf.fn, {wk * sf.fs[0], wk * sf.fs[1], wk * sf.fs[2]}, la, lb);
  }

  // contacts between spheres without an intact link
  const ContactFactors cf = contact_factors(mat);
  for (std::size_t q = 0; q < nl.size(); ++q)
  {
    const std::int32_t lk = nl.link[q];
    if (lk >= 0 && l.state[lk] == LinkState::intact)
      continue;
    const std::int32_t i = nl.a[q], j = nl.b[q];
    double n[3];
    for (int k = 0; k < 3; ++k)
      n[k] = p.x[3 * j + k] - p.x[3 * i + k];
    const double D = std::sqrt(dot3(n, n));
    const double rs = p.r[i] + p.r[j];
    double* fs_old = &nl.fs[3 * q];
    if (D >= rs)
    {
      nl.touching[q] = 0;
      std::fill(fs_old, fs_old + 3, 0.0);
      continue;
    }
    for (double& v : n)
      v /= D;
    LinkLaw law = base;
    law.s_int = interaction_surface(p.r[i], p.r[j]);
    law.kn = mat.youngs_modulus * law.s_int / rs * cf.cn;
    law.ks = law.kn * cf.cs;
    const double fn = contact_normal_force(D, rs, law.kn);
    const double la = D * p.r[i] / rs, lb = D - la;
    const double* n_old = nl.touching[q] ? &nl.n[3 * q] : n;
    const Mat3 ra = R(i), rb = R(j);
    const double fa = p.r[i] / rs;
    const Vec3 nn{n[0], n[1], n[2]};
    const Vec3 du_s = shear_increment({n_old[0], n_old[1], n_old[2]}, nn, ra, rb, D, fa);
    Vec3 fs_rot{0.0, 0.0, 0.0};
    if (nl.touching[q])
      fs_rot = rotate_shear({fs_old[0], fs_old[1], fs_old[2]}, ra, rb, fa, nn);
    const ShearForce sf = contact_shear_force(fs_rot, du_s, fn, law);
    const double wq = p.weight.empty() ? 1.0 : 0.5 * (p.weight[i] + p.weight[j]);
    c.friction += wq * sf.slip_energy;
    for (int k = 0; k < 3; ++k)
    {
      fs_old[k] = sf.fs[k];
      nl.n[3 * q + k] = n[k];
    }
    nl.touching[q] = 1;
    apply(p, i, j, n, wq * fn, {wq * sf.fs[0], wq * sf.fs[1], wq * sf.fs[2]}, la, lb);
  }
}

double elastic_energy(const Particles& p, const Links& l, const NeighbourList& nl,
                      const Material& mat)
{
  double e = 0.0;
  const LinkLaw base = mat.law(1.0, 1.0, 1.0);
  for (std::size_t k = 0; k < l.size(); ++k)
  {
    if (l.state[k] != LinkState::intact)
      continue;
    const std::int32_t i = l.a[k], j = l.b[k];
    double d[3];
    for (int q = 0; q < 3; ++q)
      d[q] = p.x[3 * j + q] - p.x[3 * i + q];
    LinkLaw law = base;
    law.kn = l.kn[k];
    law.ks = l.ks[k];
    law.s_int = l.s_int[k];
    const double delta = std::sqrt(dot3(d, d)) - l.d0[k];
    const double fn = link_normal_force(delta, l.delta_max[k], law).fn;
    const double wk = l.weight.empty() ? 1.0 : l.weight[k];
    e += wk * (0.5 * fn * delta + 0.5 * dot3(&l.fs[3 * k], &l.fs[3 * k]) / law.ks);
  }
  const ContactFactors cf = contact_factors(mat);
  for (std::size_t q = 0; q < nl.size(); ++q)
  {
    if (!nl.touching[q])
      continue;
    const std::int32_t lk = nl.link[q];
    if (lk >= 0 && l.state[lk] == LinkState::intact)
      continue;
    const std::int32_t i = nl.a[q], j = nl.b[q];
    double d[3];
    for (int k = 0; k < 3; ++k)
      d[k] = p.x[3 * j + k] - p.x[3 * i + k];
    const double rs = p.r[i] + p.r[j];
    const double gap = rs - std::sqrt(dot3(d, d));
    const double kn = mat.youngs_modulus * interaction_surface(p.r[i], p.r[j]) / rs * cf.cn;
    const double wq = p.weight.empty() ? 1.0 : 0.5 * (p.weight[i] + p.weight[j]);
    if (gap > 0.0)
      e += wq * 0.5 * kn * gap * gap;
    e += wq * 0.5 * dot3(&nl.fs[3 * q], &nl.fs[3 * q]) / (kn * cf.cs);
  }
  return e;
}

double softening_energy(const Links& l, const Material& mat)
{
  double e = 0.0;
  LinkLaw law = mat.law(1.0, 1.0, 1.0);
  for (std::size_t k = 0; k < l.size(); ++k)
  {
    if (l.delta_max[k] <= 0.0)
      continue;
    law.kn = l.kn[k];
    law.ks = l.ks[k];
    law.s_int = l.s_int[k];
    e += (l.weight.empty() ? 1.0 : l.weight[k]) * softening_dissipation(l.delta_max[k], law);
  }
  return e;
}

void stiffness_action(const Particles& p, const Links& l, std::span<const double> u,
                      std::span<double> f)
{
  const std::size_t n = p.size();
  if (u.size() != 6 * n || f.size() != 6 * n)
    throw std::runtime_error("stiffness_action: u and f need 6 values per particle");
  std::fill(f.begin(), f.end(), 0.0);
  const double* th = u.data() + 3 * n;
  double* t = f.data() + 3 * n;
  for (std::size_t k = 0; k < l.size(); ++k)
  {
    if (l.state[k] != LinkState::intact)
      continue;
    const std::int32_t i = l.a[k], j = l.b[k];
    Vec3 nv{p.x[3 * j] - p.x[3 * i], p.x[3 * j + 1] - p.x[3 * i + 1], p.x[3 * j + 2] - p.x[3 * i + 2]};
    const double D = std::sqrt(dot3(nv.data(), nv.data()));
    for (double& c : nv)
      c /= D;
    const double la = D * p.r[i] / (p.r[i] + p.r[j]), lb = D - la;
    const Vec3 rot{la * th[3 * i] + lb * th[3 * j], la * th[3 * i + 1] + lb * th[3 * j + 1],
                   la * th[3 * i + 2] + lb * th[3 * j + 2]};
    const Vec3 rxn = cross3(rot.data(), nv.data());
    Vec3 d;
    for (int c = 0; c < 3; ++c)
      d[c] = u[3 * j + c] - u[3 * i + c] - rxn[c];
    const double dn = dot3(d.data(), nv.data());
    const double wk = l.weight.empty() ? 1.0 : l.weight[k];
    const double fn = wk * l.kn[k] * dn; // tension positive
    Vec3 fs;                              // shear force on b
    for (int c = 0; c < 3; ++c)
      fs[c] = -wk * l.ks[k] * (d[c] - dn * nv[c]);
    const auto tq = shear_torques(nv, fs, la, lb);
    for (int c = 0; c < 3; ++c)
    {
      // f = K u is the internal force: minus the force the link applies
      const double fb = -fn * nv[c] + fs[c];
      f[3 * j + c] -= fb;
      f[3 * i + c] += fb;
      t[3 * i + c] -= tq[0][c];
      t[3 * j + c] -= tq[1][c];
    }
  }
}

double critical_time_step(const Particles& p, const Links& l)
{
  // Rows of M^-1/2 K M^-1/2 in 3 x 3 blocks: per link, translation blocks of
  // norm <= max(kn, ks), translation-rotation blocks <= ks l, rotation blocks
  // <= ks l_a l_b (and ks l_a^2 on the diagonal).
  const std::size_t n = p.size();
  std::vector<double> rt(n, 0.0), rr(n, 0.0);
  for (std::size_t k = 0; k < l.size(); ++k)
  {
    if (l.state[k] != LinkState::intact)
      continue;
    const std::int32_t i = l.a[k], j = l.b[k];
    const double wk = l.weight.empty() ? 1.0 : l.weight[k];
    const double kt = wk * std::max(l.kn[k], l.ks[k]), ks = wk * l.ks[k];
    const double la = l.d0[k] * p.r[i] / (p.r[i] + p.r[j]), lb = l.d0[k] - la;
    const double mi = p.m[i], mj = p.m[j], Ii = p.inertia[i], Ij = p.inertia[j];
    rt[i] += kt / mi + kt / std::sqrt(mi * mj) + ks * la / std::sqrt(mi * Ii) + ks * lb / std::sqrt(mi * Ij);
    rt[j] += kt / mj + kt / std::sqrt(mi * mj) + ks * lb / std::sqrt(mj * Ij) + ks * la / std::sqrt(mj * Ii);
    rr[i] += ks * la * la / Ii + ks * la * lb / std::sqrt(Ii * Ij) + ks * la / std::sqrt(Ii * mi) + ks * la / std::sqrt(Ii * mj);
    rr[j] += ks * lb * lb / Ij + ks * la * lb / std::sqrt(Ii * Ij) + ks * lb / std::sqrt(Ij * mj) + ks * lb / std::sqrt(Ij * mi);
  }
  double lmax = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    lmax = std::max({lmax, rt[i], rr[i]});
  if (!(lmax > 0.0))
    throw std::runtime_error("critical time step: the assembly has no intact link");
  return 2.0 / std::sqrt(lmax);
}

DemSolver::DemSolver(Particles& p, Links& l, const Material& mat, double dt, double damping,
                     double skin)
    : _p(p), _l(l), _mat(mat), _nl(skin), _dt(dt), _c(0.0)
{
  mat.validate();
  if (!(dt > 0.0) || !std::isfinite(dt))
    throw std::runtime_error("time step " + std::to_string(dt) + " s: must be > 0");
  set_damping(damping);
  _held.assign(6 * p.size(), 0);
  _fext.assign(3 * p.size(), 0.0);
  _fext_old.assign(3 * p.size(), 0.0);
  _reac.assign(3 * p.size(), 0.0);
  _fold.assign(3 * p.size(), 0.0);
}

void DemSolver::set_damping(double c)
{
  if (!(c >= 0.0) || !std::isfinite(c))
    throw std::runtime_error("damping " + std::to_string(c) + " 1/s: must be >= 0");
  _c = c;
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
  {
    if (i < 0 || static_cast<std::size_t>(i) >= _p.size())
      throw std::runtime_error("condition '" + m.name + "': sphere index out of range");
    for (int k = 0; k < 3; ++k)
      if (m.kind == MotionKind::fixed || m.components[k])
        _held[6 * i + k] = 1;
    if (m.kind == MotionKind::fixed)
      for (int k = 3; k < 6; ++k)
        _held[6 * i + k] = 1;
  }
  _motions.push_back(std::move(m));
}

void DemSolver::remove_motion(const std::string& name)
{
  const auto it = std::find_if(_motions.begin(), _motions.end(),
                               [&](const ParticleMotion& m) { return m.name == name; });
  if (it == _motions.end())
    throw std::runtime_error("remove_motion: no condition named '" + name + "'");
  _motions.erase(it);
  std::fill(_held.begin(), _held.end(), 0);
  for (const auto& m : _motions)
    for (auto i : m.ids)
      for (int k = 0; k < 6; ++k)
        if (m.kind == MotionKind::fixed || (k < 3 && m.components[k]))
          _held[6 * i + k] = 1;
}

void DemSolver::add_force(ParticleForce f)
{
  if (f.ids.empty())
    throw std::runtime_error("force '" + f.name + "' has no sphere");
  if (!f.value)
    throw std::runtime_error("force '" + f.name + "' needs a history");
  _forces.push_back(std::move(f));
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
  _nl.update(_p.x, _p.r, _l.a, _l.b);
  compute_forces(_p, _l, _nl, _mat, 0.0, _counters);
  external(_forces, _t, _fext);
  _e = DemEnergy{};
  const DemEnergy e = energy();
  _e.initial = e.kinetic + e.elastic;
}

void DemSolver::kick(double h)
{
  const std::size_t n = _p.size();
  for (std::size_t i = 0; i < n; ++i)
  {
    const double im = h / _p.m[i], iI = h / _p.inertia[i];
    for (int k = 0; k < 3; ++k)
    {
      if (!_held[6 * i + k])
        _p.v[3 * i + k] += (_p.f[3 * i + k] + _fext[3 * i + k]) * im - _c * h * _p.v[3 * i + k];
      if (!_held[6 * i + 3 + k])
        _p.w[3 * i + k] += _p.t[3 * i + k] * iI - _c * h * _p.w[3 * i + k];
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
  const std::size_t n = _p.size();
  const double dt = _dt, t_new = _t + dt;
  std::vector<double>& v_old = _reac; // scratch until end_step: v(n)
  for (std::size_t i = 0; i < 3 * n; ++i)
  {
    _fold[i] = _p.f[i] + _fext[i];
    v_old[i] = _p.v[i];
  }
  kick(0.5 * dt);
  for (const auto& m : _motions)
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
  _in_step = true;
}

void DemSolver::end_step()
{
  if (!_in_step)
    throw std::runtime_error("DemSolver::end_step without begin_step");
  _in_step = false;
  const std::size_t n = _p.size();
  const double dt = _dt, t_new = _t + dt;
  const std::vector<double>& v_old = _reac;
  double w_ext = 0.0, w_damp = 0.0;
  std::swap(_fext_old, _fext); // no allocation in the step loop
  external(_forces, t_new, _fext);
  const std::vector<double>& fext_old = _fext_old;
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k)
    {
      const double vh = _p.v[3 * i + k];
      _p.x[3 * i + k] += dt * vh;
      w_ext += dt * vh * 0.5 * (fext_old[3 * i + k] + _fext[3 * i + k]);
      w_damp += dt * _c * (_p.m[i] * vh * vh + _p.inertia[i] * _p.w[3 * i + k] * _p.w[3 * i + k]);
    }
  _nl.update(_p.x, _p.r, _l.a, _l.b);
  compute_forces(_p, _l, _nl, _mat, dt, _counters, _rot);
  // reactions on held translations: m (v_new - v_old) = dt/2 (F_old + F_new) + dt R
  double w_presc = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k)
    {
      if (!_held[6 * i + k])
        continue;
      const double vh = _p.v[3 * i + k];
      const double F_new = _p.f[3 * i + k] + _fext[3 * i + k] - _c * _p.m[i] * vh;
      const double F_old = _fold[3 * i + k] - _c * _p.m[i] * vh;
      const double R = _p.m[i] * (vh - v_old[3 * i + k]) / dt - 0.5 * (F_old + F_new);
      w_presc += dt * vh * R;
      _reac[3 * i + k] = R;
    }
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k)
      if (!_held[6 * i + k])
        _reac[3 * i + k] = 0.0;
  kick(0.5 * dt);
  for (const auto& m : _motions)
    if (m.kind == MotionKind::velocity)
      for (auto i : m.ids)
        for (int k = 0; k < 3; ++k)
          if (m.components[k])
            _p.v[3 * i + k] = m.value(t_new);
  _t = t_new;
  ++_steps;
  _e.external_work += w_ext;
  _e.damping += w_damp;
  _e.prescribed_work += w_presc;

  double check = 0.0;
  for (std::size_t i = 0; i < 3 * n; ++i)
    check += _p.x[i] + _p.v[i] + _p.w[i];
  if (!std::isfinite(check))
  {
    std::size_t bad = 0;
    while (bad < 3 * n && std::isfinite(_p.x[bad]) && std::isfinite(_p.v[bad]) && std::isfinite(_p.w[bad]))
      ++bad;
    std::ostringstream s;
    s << "non-finite position or velocity of sphere " << bad / 3 << " at t = " << _t
      << " s (step " << _steps << "): the run is unstable; reduce the time step";
    throw std::runtime_error(s.str());
  }
}

DemEnergy DemSolver::energy() const
{
  DemEnergy e = _e;
  e.kinetic = 0.0;
  for (std::size_t i = 0; i < _p.size(); ++i)
    e.kinetic += 0.5 * _p.m[i] * dot3(&_p.v[3 * i], &_p.v[3 * i])
                 + 0.5 * _p.inertia[i] * dot3(&_p.w[3 * i], &_p.w[3 * i]);
  e.elastic = elastic_energy(_p, _l, _nl, _mat);
  e.softening = softening_energy(_l, _mat);
  e.breakage = _counters.breakage;
  e.friction = _counters.friction;
  return e;
}

std::array<double, 3> DemSolver::reaction(const std::string& name) const
{
  for (const auto& m : _motions)
    if (m.name == name)
    {
      std::array<double, 3> r{0, 0, 0};
      for (auto i : m.ids)
        for (int k = 0; k < 3; ++k)
          r[k] += _reac[3 * i + k];
      return r;
    }
  throw std::runtime_error("no boundary condition named '" + name + "'");
}

} // namespace dembridge::dem
