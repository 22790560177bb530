#pragma once
// Internal to dem/: the contact kernel of the force loop (kernels.h): the
// frictional contact of two spheres without an intact link, with rolling
// resistance in a sweep of width 9 (docs/method.md 1.7-1.7d).
#include "kernels.h"

#include <type_traits>

namespace dembridge::dem::kernel
{

class ContactKernel
{
public:
  /// `reach`: how far beyond R_a + R_b a listed pair can touch (the broken
  /// links' closing reach, ForceScratch::contact_reach)
  ContactKernel(const StepLaw& w, const Particles& p, const Links& l, NeighbourList& nl, ForceScratch& s,
                const double* rec)
      : _w(w), _p(p), _l(l), _nl(nl), _s(s), _rec(rec), _rad(p.r.data())
  {
  }

  /// Per sphere: the branches of its pairs. A pair that was apart at the
  /// last step and is farther apart now than any pair can touch (R_a + R_b
  /// + the broken links' closing reach, with a margin over the rounding)
  /// stays apart: it is marked (g[3] = -1) and skipped, its shear and
  /// rolling springs at zero as they were (a pair apart holds no history);
  /// most listed pairs are such, in a perforation.
  void prepare(std::size_t i, std::int32_t k0, std::int32_t k1, double* g) const
  {
    constexpr double reach_margin = 1.0 + 1e-9;
    const double* xi = _rec + record * i;
    for (std::int32_t k = k0; k < k1; ++k)
    {
      __builtin_prefetch(_rec + record * b_ahead(_nl.b, k));
      const double* xj = _rec + record * _nl.b[k];
      double* gk = g + prepared * (k - k0);
      gk[0] = xj[0] - xi[0];
      gk[1] = xj[1] - xi[1];
      gk[2] = xj[2] - xi[2];
      const double d2 = gk[0] * gk[0] + gk[1] * gk[1] + gk[2] * gk[2];
      const double far = (xi[3] + xj[3] + _s.contact_reach) * reach_margin;
      gk[3] = !_nl.touching[k] && d2 > far * far ? -1.0 : d2;
    }
    unit_normals(g, k1 - k0);
  }

  /// Pair q of sphere i, its prepared values n: the force on b and the
  /// torque factor (W = 6), or the torque factors of a and b (W = 9, with
  /// the rolling moment), into out[W]; false (out zeroed) if apart.
  template <int W>
  __attribute__((always_inline)) bool force(std::size_t i, std::int32_t q, const double* n, double* out) const
  {
    _s.pair_slip[q] = 0.0;
    if (n[3] < 0.0) // apart, and was (prepare)
    {
      std::fill(out, out + W, 0.0);
      return false;
    }
    const std::int32_t j = _nl.b[q];
    const double D = n[3];
    const double rs = _rad[i] + _rad[j];
    // where the spheres touch, and the springs (impl::contact_spring)
    const ContactSpring cs = contact_spring(_w.mat, _w.cf, _l, _nl.link[q], _rad[i], _rad[j], _w.compacting);
    double* fs_old = &_nl.fs[3 * q];
    // the rolling spring: k_r = K_s R*^2 (method.md 1.7d)
    const double r_star = _rad[i] * _rad[j] / rs;
    if (D >= cs.touch) // (a listed pair never has an intact link: NeighbourList)
    {
      open<W>(i, q, cs, r_star, fs_old, out);
      return false;
    }
    LinkLaw law = _w.base;
    law.s_int = pair_surface(_rad[i], _rad[j]);
    law.kn = cs.kn;
    law.ks = cs.ks;
    const double fn = contact_normal_force(D, cs.touch, law.kn);
    const bool touched = _nl.touching[q];
    const double* n_old = touched ? &_nl.n[3 * q] : n;
    const Vec3 fs_prev = touched ? Vec3{fs_old[0], fs_old[1], fs_old[2]} : Vec3{0, 0, 0};
    const Mat3 qa = rotation_minus_identity(load_rotation(_rec + record * i));
    const StepRotation qb = load_rotation(_rec + record * j);
    const Vec3 trial = trial_shear(fs_prev, {n_old[0], n_old[1], n_old[2]}, {n[0], n[1], n[2]}, qa, qb,
                                   _rad[i] / rs, law.ks * D);
    const ShearForce sf = contact_shear_cap(trial, fn, law, fs_prev);
    const double wq = pair_weight(i, j);
    _s.pair_slip[q] = wq * sf.slip_energy;
    for (int k = 0; k < 3; ++k)
    {
      fs_old[k] = sf.fs[k];
      _nl.n[3 * q + k] = n[k];
    }
    _nl.touching[q] = 1;
    pair_output(out, n, wq * fn, {wq * sf.fs[0], wq * sf.fs[1], wq * sf.fs[2]}, D, 1.0 / rs);
    if constexpr (W == 9)
      roll(i, q, n, qa, qb, touched, fn, law.ks * r_star * r_star, r_star, wq, out);
    return true;
  }

private:
  /// The coupling's weight of a pair: the mean of its spheres' (1 without).
  double pair_weight(std::size_t i, std::int32_t j) const
  {
    return _w.weighted_spheres ? 0.5 * (_p.weight[i] + _p.weight[j]) : 1.0;
  }

  /// A pair apart: if it touched, the contact opens, its caps fell to zero,
  /// so the shear (and rolling) springs' energy went by sliding (friction).
  template <int W>
  __attribute__((always_inline)) void open(std::size_t i, std::int32_t q, const ContactSpring& cs, double r_star,
                                           double* fs_old, double* out) const
  {
    if (_nl.touching[q])
    {
      const double wq = pair_weight(i, _nl.b[q]);
      double e = wq * 0.5 * dot3(fs_old, fs_old) / cs.ks;
      if constexpr (W == 9)
        e += wq * 0.5 * dot3(&_nl.mr[3 * q], &_nl.mr[3 * q]) / (cs.ks * r_star * r_star);
      _s.pair_slip[q] = e;
    }
    _nl.touching[q] = 0;
    std::fill(fs_old, fs_old + 3, 0.0);
    if constexpr (W == 9)
      std::fill(&_nl.mr[3 * q], &_nl.mr[3 * q] + 3, 0.0);
    std::fill(out, out + W, 0.0);
  }

  /// Rolling resistance (law.h, trial_rolling): the moment M on b, -M on
  /// a, capped at mu_r R* F_n; torque factors q_a = q - M / R_a and q_b = q
  /// + M / R_b (torque = radius times factor) into out[3..8].
  void roll(std::size_t i, std::int32_t q, const double* n, const Mat3& qa, const StepRotation& qb, bool touched,
            double fn, double kr, double r_star, double wq, double* out) const
  {
    const std::int32_t j = _nl.b[q];
    const double rs = _rad[i] + _rad[j];
    double* m_old = &_nl.mr[3 * q];
    const Vec3 m_prev = touched ? Vec3{m_old[0], m_old[1], m_old[2]} : Vec3{0, 0, 0};
    const double* wa = &_p.w[3 * i];
    const double* wb = &_p.w[3 * j];
    const double dt = _w.dt;
    const Vec3 mt = trial_rolling(m_prev, {n[0], n[1], n[2]}, qa, qb, _rad[i] / rs,
                                  {(wb[0] - wa[0]) * dt, (wb[1] - wa[1]) * dt, (wb[2] - wa[2]) * dt}, kr);
    const ShearForce rm = contact_rolling_cap(mt, fn, kr, _w.mat.rolling_friction * r_star, m_prev);
    _s.pair_slip[q] += wq * rm.slip_energy;
    for (int k = 0; k < 3; ++k)
    {
      m_old[k] = rm.fs[k];
      out[6 + k] = out[3 + k] + wq * rm.fs[k] / _rad[j];
      out[3 + k] -= wq * rm.fs[k] / _rad[i];
    }
  }

  const StepLaw _w; // (a copy: one indirection less per item)
  const Particles& _p;
  const Links& _l;
  NeighbourList& _nl;
  ForceScratch& _s;
  const double* _rec;
  const double* _rad;
};

} // namespace dembridge::dem::kernel
