#pragma once
// Internal to dem/: the link kernel of the force loop (kernels.h): the
// force of a cohesive link on its spheres under the step's law, its
// compaction, rate effect and breakage (docs/method.md 1.5-1.6c).
#include "kernels.h"

namespace dembridge::dem::kernel
{

class LinkKernel
{
public:
  /// `rec`: the spheres' records (force_loop.h, `record`)
  LinkKernel(const StepLaw& w, const Particles& p, Links& l, ForceScratch& s, const double* rec)
      : _w(w), _p(p), _l(l), _s(s), _rec(rec)
  {
  }

  /// Per sphere: the branches, then the trial shear forces of its intact
  /// links (the stored force and the shear increment carried by the pair's
  /// rotation) into g[4..6], and 1 / (R_a + R_b) into g[7].
  __attribute__((always_inline)) void prepare(std::size_t i, std::int32_t k0, std::int32_t k1, double* g) const
  {
    branches(_rec, i, _l.b, k0, k1, g);
    const double* ri = _rec + record * i;
    const Mat3 qa = rotation_minus_identity(load_rotation(ri));
    for (std::int32_t k = k0; k < k1; ++k)
    {
      if (_l.state[k] != LinkState::intact)
        continue;
      double* gk = g + prepared * (k - k0);
      const double* rj = _rec + record * _l.b[k];
      const double inv_rs = 1.0 / (ri[3] + rj[3]);
      const Vec3 tr = trial_shear({_l.fs[3 * k], _l.fs[3 * k + 1], _l.fs[3 * k + 2]},
                                  {_l.n[3 * k], _l.n[3 * k + 1], _l.n[3 * k + 2]}, {gk[0], gk[1], gk[2]}, qa,
                                  load_rotation(rj), ri[3] * inv_rs, _l.ks[k] * gk[3]);
      gk[7] = inv_rs;
      gk[4] = tr[0];
      gk[5] = tr[1];
      gk[6] = tr[2];
    }
  }

  /// Link k of sphere i, its prepared values n: the force on b and the
  /// torque factor into out[6]; false (out zeroed) if it is broken or
  /// breaks now.
  __attribute__((always_inline)) bool force(std::size_t i, std::int32_t k, const double* n, double* out) const
  {
    if (_l.state[k] != LinkState::intact)
    {
      std::fill(out, out + 6, 0.0);
      return false;
    }
    const double D = n[3];
    LinkLaw law = _w.base;
    law.kn = _l.kn[k];
    law.ks = _l.ks[k];
    // the radii from the records (= link_surface): p.r[b] would be one more
    // cache line per link (measured: 5 % slower at 200k spheres)
    law.s_int = pair_surface(_rec[record * i + 3], _rec[record * _l.b[k] + 3]);
    const Compacted c = compact(i, k, D - _l.d0[k]);
    if (_w.factored)
      strengthen(i, k, n, law);
    const double delta_max_old = _l.delta_max[k];
    const NormalForce nf = link_normal_force(c.delta, delta_max_old, law);
    double* fs_old = &_l.fs[3 * k];
    const double wk = _w.weighted_links ? _l.weight[k] : 1.0;
    _l.delta_max[k] = nf.delta_max;
    const Vec3 trial{n[4], n[5], n[6]};
    if (nf.state == NormalState::broken)
    {
      // A link that breaks in this step: its force is zero at the step's
      // end, so the energy it releases is what it stored at the start plus
      // the work of its force over the step, trapezoidal as the
      // velocity-Verlet kicks apply it (zero at the end): for the shear
      // spring, |fs_old|^2 / (2 K_s) + fs_old . du / 2 = fs_old . fs_trial / (2 K_s).
      _l.state[k] = LinkState::broken_tension;
      release(k, wk * 0.5 * dot3(fs_old, trial.data()) / law.ks, fs_old, out);
      return false;
    }
    const ShearForce sf = link_shear_cap(trial, nf.fn, law);
    if (_w.track)
      track_demand(k, trial, nf.fn, law);
    if (sf.exceeded)
    {
      // Mohr-Coulomb reached: the link breaks and its elastic energy is
      // released; if the spheres touch, a contact takes over from zero shear.
      _l.state[k] = LinkState::broken_shear;
      const double normal = shear_break_normal_energy(i, k, n, c, delta_max_old, law);
      release(k, wk * (normal + 0.5 * dot3(fs_old, trial.data()) / law.ks), fs_old, out);
      return false;
    }
    for (int q = 0; q < 3; ++q)
    {
      fs_old[q] = sf.fs[q];
      _l.n[3 * k + q] = n[q];
    }
    pair_output(out, n, wk * nf.fn, {wk * sf.fs[0], wk * sf.fs[1], wk * sf.fs[2]}, D, n[7]);
    return true;
  }

private:
  /// The elongation counted from the compaction's set, and the compaction
  /// state at the step's start (put back if the link breaks in shear).
  struct Compacted
  {
    double delta, e_max_old = 0.0, onset_old = 0.0;
  };

  /// Compaction (law.h): the largest compressive strain so far, and the set
  /// it left, from which the rest of the law counts; under a pressure gate,
  /// a link not yet compacting whose spheres' mean pressure is below the
  /// gate moves its onset up to its strain (it stays elastic).
  __attribute__((always_inline)) Compacted compact(std::size_t i, std::int32_t k, double delta) const
  {
    Compacted c{delta};
    if (!_w.compacting)
      return c;
    const double e = -delta / _l.d0[k];
    double& e_max = _l.compaction[k];
    c.e_max_old = e_max;
    if (_w.pressure_gated)
      c.onset_old = _l.compaction_onset[k];
    if (e > e_max)
    {
      if (_w.pressure_gated)
      {
        double& onset = _l.compaction_onset[k];
        if (e > onset && e_max <= onset
            && 0.5 * (_s.pressure[i] + _s.pressure[_l.b[k]]) < _w.mat.compaction.pressure)
          onset = e;
      }
      e_max = e;
    }
    c.delta -= compaction_set(e_max, _l.d0[k], link_compaction(_l, k, _w.mat.compaction));
    return c;
  }

  /// The rate effect: while the link is elastic, its strength factor
  /// follows the largest Malvar-Ross factor of its tensile strain rate
  /// (v(n+1/2) of its spheres along the normal, over D_init), or with
  /// rate_current the factor of its current rate, floored at what the link
  /// holds; the factor scales T (and C0 with rate_cohesion) in `law`.
  __attribute__((always_inline)) void strengthen(std::size_t i, std::int32_t k, const double* n, LinkLaw& law) const
  {
    double& factor = _l.strength[k];
    const bool elastic = _w.rated && _l.delta_max[k] * law.kn <= law.s_int * law.tensile * factor;
    const bool stretched = !_w.gated || _s.stretch[i] + _s.stretch[_l.b[k]] > 0.0;
    if (elastic && _w.mat.rate_current)
      factor = held_factor(_l, k, law, _w.mat.rate_cohesion);
    if (elastic && stretched)
    {
      const double* va = &_p.v[3 * i];
      const double* vb = &_p.v[3 * _l.b[k]];
      double rate = ((vb[0] - va[0]) * n[0] + (vb[1] - va[1]) * n[1] + (vb[2] - va[2]) * n[2]) / _l.d0[k];
      if (_w.filtered)
      {
        double& rf = _l.rate[k];
        rf += _w.filter_weight * (rate - rf);
        rate = rf;
      }
      factor = std::max(factor,
                        malvar_ross_dif(_w.mat.rate_max > 0.0 ? std::min(rate, _w.mat.rate_max) : rate, _w.mat.rate_fc));
    }
    law.tensile *= factor;
    if (_w.mat.rate_cohesion)
      law.cohesion *= factor;
  }

  /// The cohesion demand (ForceCounters::cohesion_demand): the cap with C0
  /// = the demand before this step; beyond it, this thread's demand grows
  /// (in units of the base C0: the link's cap is its factor times C0).
  __attribute__((always_inline)) void track_demand(std::int32_t k, const Vec3& trial, double fn,
                                                   const LinkLaw& law) const
  {
    const double f2 = dot3(trial.data(), trial.data());
    const double factor = _w.factored && _w.mat.rate_cohesion ? _l.strength[k] : 1.0;
    const double room = law.s_int * _w.demand_before * factor - fn * law.tan_phi_i;
    if (f2 > 0.0 && (room < 0.0 || f2 > room * room))
    {
      double& dm = _s.demand[8 * omp_get_thread_num()];
      dm = std::max(dm, (std::sqrt(f2) + fn * law.tan_phi_i) / (law.s_int * factor));
    }
  }

  /// The energy the normal spring of a link broken in shear releases: fn_old
  /// delta / 2 (what it stored, elastic or on the secant, plus the work
  /// fn_old (delta - delta_old) / 2), the elongation at the step's start
  /// from the drift, delta_old = delta - dt (v_b - v_a) . n with v(n+1/2).
  /// All from the state at the step's start: its softening and compaction
  /// (states whose energies count apart) are put back, and the elongations
  /// count from the set it had then.
  double shear_break_normal_energy(std::size_t i, std::int32_t k, const double* n, const Compacted& c,
                                   double delta_max_old, const LinkLaw& law) const
  {
    _l.delta_max[k] = delta_max_old;
    const double D = n[3];
    double from_set = c.delta;
    if (_w.compacting)
    {
      _l.compaction[k] = c.e_max_old;
      if (_w.pressure_gated)
        _l.compaction_onset[k] = c.onset_old;
      from_set = (D - _l.d0[k]) - compaction_set(c.e_max_old, _l.d0[k], link_compaction(_l, k, _w.mat.compaction));
    }
    const double* va = &_p.v[3 * i];
    const double* vb = &_p.v[3 * _l.b[k]];
    const double delta_old =
        from_set - _w.dt * ((vb[0] - va[0]) * n[0] + (vb[1] - va[1]) * n[1] + (vb[2] - va[2]) * n[2]);
    const double fn_old = link_normal_force(delta_old, delta_max_old, law).fn;
    // with crack closure a compressed link's normal spring goes on as the
    // contact's (the same K_n) from the closing distance: the contact keeps
    // the share (its overlap / the link's shortening)^2 of the spring's
    // energy, all of it at c = 1 (the same rest distance); the rest is
    // released
    double normal = 0.5 * fn_old * from_set;
    if (_w.mat.crack_closure > 0.0 && from_set < 0.0)
    {
      // (the set of e_max at the step's start, as from_set's)
      const double set =
          _w.compacting ? compaction_set(_l.compaction[k], _l.d0[k], link_compaction(_l, k, _w.mat.compaction)) : 0.0;
      const double touch =
          contact_spring(_w.mat, _w.cf, _l, k, _rec[record * i + 3], _rec[record * _l.b[k] + 3], _w.compacting).touch;
      const double share = std::clamp(1.0 - (_l.d0[k] + set - touch) / -from_set, 0.0, 1.0);
      normal *= 1.0 - share * share;
    }
    return normal;
  }

  /// A link broken now: its released energy booked (in link order after
  /// the sweep), its shear force and output zeroed.
  void release(std::int32_t k, double energy, double* fs_old, double* out) const
  {
    _s.broken[omp_get_thread_num()].emplace_back(k, energy);
    std::fill(fs_old, fs_old + 3, 0.0);
    std::fill(out, out + 6, 0.0);
  }

  const StepLaw _w; // (a copy: one indirection less per item)
  const Particles& _p;
  Links& _l;
  ForceScratch& _s;
  const double* _rec;
};

} // namespace dembridge::dem::kernel
