#include "force_loop.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <omp.h>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "threads.h"

namespace dembridge::dem
{
using impl::ContactFactors;
using impl::contact_factors;
using impl::ContactSpring;
using impl::contact_spring;
using impl::dot3;

namespace
{
/// How many items ahead the sweep prefetches what item k's sphere b needs:
/// sphere b lies anywhere along the curve, so its record, force and torque
/// are rarely in the core's caches when its item comes.
constexpr std::int32_t ahead = 16;
/// Sphere b of the item `ahead` items after k (the last item near the end).
inline std::int32_t b_ahead(std::span<const std::int32_t> b, std::int32_t k)
{
  return b[std::min<std::size_t>(static_cast<std::size_t>(k + ahead), b.size() - 1)];
}
/// The `count` items' prepared values g[0..3] from the branch (d, |d|^2) to
/// the unit normal and the length (d / |d|, |d|); items marked with g[3] < 0
/// are left as they are.
inline void unit_normals(double* g, std::int32_t count)
{
  for (std::int32_t m = 0; m < count; ++m)
  {
    double* gk = g + prepared * m;
    if (gk[3] < 0.0)
      continue;
    const double D = std::sqrt(gk[3]);
    const double inv = 1.0 / D;
    gk[0] *= inv;
    gk[1] *= inv;
    gk[2] *= inv;
    gk[3] = D;
  }
}
/// Unit normal a -> b and branch length of the items [k0, k1) of sphere i,
/// into g[0..3] of each item's `prepared` values: done for a sphere's items
/// together, so that the square roots and divisions of successive items
/// overlap (the loop bodies are short and independent).
inline void branches(const double* rec, std::size_t i, std::span<const std::int32_t> b,
                     std::int32_t k0, std::int32_t k1, double* g)
{
  const double* xi = rec + record * i;
  for (std::int32_t k = k0; k < k1; ++k)
  {
    __builtin_prefetch(rec + record * b_ahead(b, k));
    const double* xj = rec + record * b[k];
    double* gk = g + prepared * (k - k0);
    gk[0] = xj[0] - xi[0];
    gk[1] = xj[1] - xi[1];
    gk[2] = xj[2] - xi[2];
    gk[3] = gk[0] * gk[0] + gk[1] * gk[1] + gk[2] * gk[2];
  }
  unit_normals(g, k1 - k0);
}

/// One sweep over the items of `ix` by the calling thread (call from every
/// thread of the team; see SweepIndex). compute(i, k, out) writes item k's
/// force on b and torque factor into out[W] and returns false if the item
/// acts no more (out zeroed): W = 6, the force on b and one torque factor q
/// for both spheres (a shear force's torques, t = R q); W = 9, the force on
/// b, then q_a and q_b (a moment pair on top of the shear's torques). f and q receive the sums for this thread's
/// spheres, ix.bounds[t] to ix.bounds[t + 1]; `reset` zeroes them first.
/// The sums are the same bit for bit whatever the thread count: into each
/// sphere, the items of lower spheres in item order, then its own.
/// prepare(i, k0, k1, g) fills the `prepared` values of the items of sphere
/// i (reading state only); compute(i, k, g_k, out) then does item k.
template <int W, typename Prepare, typename Compute>
void sweep(SweepIndex& ix, std::span<const std::int32_t> b, bool reset,
           double* f, double* q, Prepare&& prepare, Compute&& compute)
{
  static_assert(W == 6 || W == 9);
  constexpr int qb = W - 3; // where sphere b's torque factor sits in an output
  const int t = omp_get_thread_num();
  const std::size_t lo = ix.bounds[t], hi = ix.bounds[t + 1];
  const std::int32_t bhi = static_cast<std::int32_t>(hi);
  std::vector<double>& g = ix.geometry[t];
  // a sphere's cross items are the tail of its items (b sorted within i);
  // the team shares all of them out evenly (any thread may compute an item:
  // its output goes to its slot), so that no thread waits for another's
  // at the barrier, then each thread sums its spheres' own items
  auto cross_begin = [&](std::int32_t k0, std::int32_t k1)
  {
    while (k1 > k0 && b[k1 - 1] >= bhi)
      --k1;
    return k1;
  };
  {
    const std::size_t nc = ix.cross_i.size(), nt = static_cast<std::size_t>(ix.threads);
    const std::size_t c0 = nc * static_cast<std::size_t>(t) / nt,
                      c1 = nc * static_cast<std::size_t>(t + 1) / nt;
    for (std::size_t c = c0; c < c1; ++c)
    {
      const std::int32_t i = ix.cross_i[c], k = ix.cross_k[c];
      prepare(static_cast<std::size_t>(i), k, k + 1, g.data());
      compute(static_cast<std::size_t>(i), k, g.data(), &ix.out[W * c]);
    }
  }
  if (reset)
  {
    std::fill(f + 3 * lo, f + 3 * hi, 0.0);
    std::fill(q + 3 * lo, q + 3 * hi, 0.0);
  }
#pragma omp barrier
  // the cross items into this thread's spheres come first in item order
  for (std::size_t j = lo; j < hi; ++j)
    for (std::int32_t e = ix.in_first[j]; e < ix.in_first[j + 1]; ++e)
    {
      const double* o = &ix.out[W * ix.in[e]];
      for (int c = 0; c < 3; ++c)
      {
        f[3 * j + c] += o[c];
        q[3 * j + c] += o[qb + c];
      }
    }
  std::int32_t slot = ix.cross_first[t];
  for (std::size_t i = lo; i < hi; ++i)
  {
    double fi[3] = {0.0, 0.0, 0.0}, qi[3] = {0.0, 0.0, 0.0};
    const std::int32_t k0 = ix.first[i], k1 = ix.first[i + 1];
    if (k0 == k1)
      continue;
    const std::int32_t kc = cross_begin(k0, k1);
    if (kc > k0)
      prepare(i, k0, kc, g.data());
    for (std::int32_t k = k0; k < k1; ++k)
    {
      const std::int32_t j = b[k];
      const std::int32_t jn = b_ahead(b, k);
      __builtin_prefetch(f + 3 * jn, 1);
      __builtin_prefetch(q + 3 * jn, 1);
      double local[W];
      const double* o = local;
      if (j >= bhi)
        o = &ix.out[W * slot++];
      else if (compute(i, k, &g[prepared * (k - k0)], local))
        for (int c = 0; c < 3; ++c)
        {
          f[3 * j + c] += local[c];
          q[3 * j + c] += local[qb + c];
        }
      else
        continue;
      for (int c = 0; c < 3; ++c)
      {
        fi[c] -= o[c];
        qi[c] += o[3 + c];
      }
    }
    for (int c = 0; c < 3; ++c)
    {
      f[3 * i + c] += fi[c];
      q[3 * i + c] += qi[c];
    }
  }
}

// The smallest strength factor that keeps a link as it stands (Material::
// rate_current, docs/method.md 1.6b), and at least 1: elastic at its largest
// elongation so far, K_n delta_max <= S_int T f; with the factor on C0 too,
// its stored shear force within the Mohr-Coulomb cap S_int C0 f - F_t tan(phi_i)
// (the tension F_t taken at delta_max: the largest it has been, so the floor
// is on the safe side)
inline double held_factor(const Links& l, std::int32_t k, const LinkLaw& law, bool cohesion)
{
  const double stretch = std::max(l.delta_max[k], 0.0) * law.kn;
  double f = 1.0;
  if (law.tensile > 0.0)
    f = std::max(f, stretch / (law.s_int * law.tensile));
  if (cohesion && law.cohesion > 0.0)
  {
    const double* fs = &l.fs[3 * k];
    const double shear = std::sqrt(fs[0] * fs[0] + fs[1] * fs[1] + fs[2] * fs[2]);
    f = std::max(f, (shear + stretch * law.tan_phi_i) / (law.s_int * law.cohesion));
  }
  return f;
}

inline StepRotation load_rotation(const double* rec)
{
  return {{rec[4], rec[5], rec[6]}, rec[7]};
}

/// Writes the force on b (fb, N) and the torque factor q (torque on either
/// sphere = its radius times q, N m / m) of a pair with unit normal n, normal
/// force fn (tension > 0), shear force fs on b, branch length D and radius
/// sum rs (given as 1 / rs): the contact point is R_a D / rs from a, so t_a = -l_a n x fs =
/// R_a q with q = -(D / rs) n x fs, and t_b = R_b q likewise.
inline void pair_output(double* out, const double* n, double fn, const Vec3& fs, double D,
                        double inv_rs)
{
  const Vec3 nxf = detail::cross({n[0], n[1], n[2]}, fs);
  const double s = -D * inv_rs;
  for (int q = 0; q < 3; ++q)
  {
    out[q] = -fn * n[q] + fs[q];
    out[3 + q] = s * nxf[q];
  }
}
/// Per sphere, the sums of K_n e_j D over its intact links, for the N
/// elongations e_j = elongations(k, D)[j] of link k at its length D, into
/// *out[j]: each link's terms on the team (w), then the sums in link order
/// by one thread, so that they do not depend on the thread count.
template <std::size_t N, typename Elongations>
void sphere_sums(const Particles& p, const Links& l, int nt, std::vector<double>& w,
                 const std::array<std::vector<double>*, N>& out, Elongations&& elongations)
{
  const auto nl = static_cast<std::int64_t>(l.size());
  w.resize(N * l.size());
#pragma omp parallel for num_threads(nt) schedule(static)
  for (std::int64_t k = 0; k < nl; ++k)
  {
    double* wk = &w[N * static_cast<std::size_t>(k)];
    if (l.state[k] != LinkState::intact)
    {
      std::fill(wk, wk + N, 0.0);
      continue;
    }
    const double* xa = &p.x[3 * l.a[k]];
    const double* xb = &p.x[3 * l.b[k]];
    const double d[3] = {xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]};
    const double D = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const std::array<double, N> e = elongations(static_cast<std::size_t>(k), D);
    for (std::size_t j = 0; j < N; ++j)
      wk[j] = l.kn[k] * e[j] * D;
  }
  for (auto* o : out)
    o->assign(p.size(), 0.0);
  for (std::size_t k = 0; k < l.size(); ++k)
    for (std::size_t j = 0; j < N; ++j)
    {
      (*out[j])[l.a[k]] += w[N * k + j];
      (*out[j])[l.b[k]] += w[N * k + j];
    }
}

/// The per-sphere sums the gates need, in one pass over the links:
/// - with `stretch`, the sum of K_n (D - D_init) D over its intact links:
///   > 0 where its links are on the whole stretched (Material::rate_mean_tension);
/// - with `pressure`, the mean pressure of its share of the intact links,
///   from the virial: p_i = -sum(F_n D) / (6 V_i) over its links (each
///   link's F_n D shared by its two spheres, the trace's third), V_i =
///   m_i / rho the volume the sphere's mass stands for
///   (CompactionLaw::pressure); F_n is the normal spring's
///   K_n (D - D_init - set) at the step's start.
void sphere_gate_sums(const Particles& p, const Links& l, const Material& mat, int nt, ForceScratch& s, bool stretch,
                      bool pressure)
{
  auto set = [&](std::size_t k)
  { return compaction_set(l.compaction[k], l.d0[k], link_compaction(l, k, mat.compaction)); };
  if (stretch && pressure)
    sphere_sums<2>(p, l, nt, s.link_stretch, {&s.stretch, &s.pressure}, [&](std::size_t k, double D)
                   { return std::array<double, 2>{D - l.d0[k], D - l.d0[k] - set(k)}; });
  else if (stretch)
    sphere_sums<1>(p, l, nt, s.link_stretch, {&s.stretch},
                   [&](std::size_t k, double D) { return std::array<double, 1>{D - l.d0[k]}; });
  else if (pressure)
    sphere_sums<1>(p, l, nt, s.link_stretch, {&s.pressure},
                   [&](std::size_t k, double D) { return std::array<double, 1>{D - l.d0[k] - set(k)}; });
  if (pressure)
    for (std::size_t i = 0; i < p.size(); ++i)
      s.pressure[i] *= -mat.density / (6.0 * p.m[i]);
}
} // namespace

void compute_forces(Particles& p, Links& l, NeighbourList& nl, const Material& mat, double dt,
                    ForceCounters& c)
{
  ForceScratch s;
  compute_forces(p, l, nl, mat, dt, c, s);
}

void compute_forces(Particles& p, Links& l, NeighbourList& nl, const Material& mat, double dt,
                    ForceCounters& c, ForceScratch& s)
{
  const std::size_t np = p.size();
  const int nt = impl::threads_for(np);
  if (s.links_for != l.a.data() || s.links_size != l.size() || s.links.first.size() != np + 1
      || s.links.threads != nt)
  {
    s.links.build(np, l.a, l.b, nt);
    s.links_for = l.a.data();
    s.links_size = l.size();
    s.pairs_version = SIZE_MAX;
    s.closure_for = -1.0;
  }
  if (s.closure_for != mat.crack_closure)
  {
    s.contact_reach = impl::closing_reach(p.r, l, mat.crack_closure);
    s.closure_for = mat.crack_closure;
  }
  // the records, 64-byte aligned (one cache line each)
  s.records.resize(record * np + record);
  double* rec = s.records.data();
  rec += (record - (reinterpret_cast<std::uintptr_t>(rec) / sizeof(double)) % record) % record;
  double* f = p.f.data();
  double* t = p.t.data();
  if (s.broken.size() < static_cast<std::size_t>(nt))
    s.broken.resize(nt);
  for (auto& b : s.broken)
    b.clear();
  const bool track = c.track_cohesion;
  const double demand_before = c.cohesion_demand;
  s.demand.assign(8 * nt, demand_before); // a cache line per thread
  const LinkLaw base = mat.law(1.0, 1.0, 1.0);
  const ContactFactors cf = contact_factors(mat);
  const bool weighted_links = !l.weight.empty(), weighted_spheres = !p.weight.empty();
  // the links' strength factors apply whenever they are sized; they follow
  // the strain rate only over a step (dt > 0: the velocities are v(n+1/2))
  const bool factored = l.strength.size() == l.size() && !l.strength.empty();
  const bool rated = factored && mat.rate_fc > 0.0 && dt > 0.0;
  // the filter's weight per step (Material::rate_filter)
  const bool filtered = rated && l.rate.size() == l.size();
  const double filter_weight = filtered ? std::min(1.0, dt / mat.rate_filter) : 1.0;
  const bool gated = rated && mat.rate_mean_tension;
  const bool compacting = mat.compaction.on() && l.compaction.size() == l.size();
  const bool pressure_gated = compacting && mat.compaction.gated() && l.compaction_onset.size() == l.size();
  sphere_gate_sums(p, l, mat, nt, s, gated, pressure_gated);
  const double* rad = p.r.data();
  bool short_team = false;
  std::size_t spinning = np; // a sphere turning by more than 1 rad in the step

  // a cohesive link: force on b and torque factor into out; false once broken
  // per sphere: branches, then the trial shear forces (the stored force and
  // the shear increment carried by the pair's rotation)
  auto link_prepare = [&](std::size_t i, std::int32_t k0, std::int32_t k1, double* g)
                          __attribute__((always_inline))
  {
    branches(rec, i, l.b, k0, k1, g);
    const double* ri = rec + record * i;
    const Mat3 qa = rotation_minus_identity(load_rotation(ri));
    for (std::int32_t k = k0; k < k1; ++k)
    {
      if (l.state[k] != LinkState::intact)
        continue;
      double* gk = g + prepared * (k - k0);
      const double* rj = rec + record * l.b[k];
      const double inv_rs = 1.0 / (ri[3] + rj[3]);
      const Vec3 tr = trial_shear({l.fs[3 * k], l.fs[3 * k + 1], l.fs[3 * k + 2]},
                                  {l.n[3 * k], l.n[3 * k + 1], l.n[3 * k + 2]}, {gk[0], gk[1], gk[2]},
                                  qa, load_rotation(rj), ri[3] * inv_rs, l.ks[k] * gk[3]);
      gk[7] = inv_rs;
      gk[4] = tr[0];
      gk[5] = tr[1];
      gk[6] = tr[2];
    }
  };
  auto link_force = [&](std::size_t i, std::int32_t k, const double* n, double* out)
                        __attribute__((always_inline)) -> bool
  {
    if (l.state[k] != LinkState::intact)
    {
      std::fill(out, out + 6, 0.0);
      return false;
    }
    const double D = n[3];
    LinkLaw law = base;
    law.kn = l.kn[k];
    law.ks = l.ks[k];
    // the radii from the records (= link_surface): p.r[b] would be one more
    // cache line per link (measured: 5 % slower at 200k spheres)
    law.s_int = pair_surface(rec[record * i + 3], rec[record * l.b[k] + 3]);
    double delta = D - l.d0[k];
    double e_max_old = 0.0, onset_old = 0.0; // the compaction at the step's start
    if (compacting)
    {
      // compaction (law.h): the largest compressive strain so far, and the
      // set it left, from which the rest of the law counts; under a pressure
      // gate, a link not yet compacting whose spheres' mean pressure is below
      // the gate moves its onset up to its strain (it stays elastic)
      const double e = -delta / l.d0[k];
      double& e_max = l.compaction[k];
      e_max_old = e_max;
      if (pressure_gated)
        onset_old = l.compaction_onset[k];
      if (e > e_max)
      {
        if (pressure_gated)
        {
          double& onset = l.compaction_onset[k];
          if (e > onset && e_max <= onset
              && 0.5 * (s.pressure[i] + s.pressure[l.b[k]]) < mat.compaction.pressure)
            onset = e;
        }
        e_max = e;
      }
      delta -= compaction_set(e_max, l.d0[k], link_compaction(l, k, mat.compaction));
    }
    if (factored)
    {
      // the rate effect: while the link is elastic, its strength factor
      // follows the largest Malvar-Ross factor of its tensile strain rate
      // (v(n+1/2) of its spheres along the normal, over D_init), or with
      // rate_current the factor of its current rate, floored at what the
      // link holds
      double& factor = l.strength[k];
      const bool elastic = rated && l.delta_max[k] * law.kn <= law.s_int * law.tensile * factor;
      const bool stretched = !gated || s.stretch[i] + s.stretch[l.b[k]] > 0.0;
      if (elastic && mat.rate_current)
        factor = held_factor(l, k, law, mat.rate_cohesion);
      if (elastic && stretched)
      {
        const double* va = &p.v[3 * i];
        const double* vb = &p.v[3 * l.b[k]];
        double rate = ((vb[0] - va[0]) * n[0] + (vb[1] - va[1]) * n[1] + (vb[2] - va[2]) * n[2]) / l.d0[k];
        if (filtered)
        {
          double& rf = l.rate[k];
          rf += filter_weight * (rate - rf);
          rate = rf;
        }
        factor = std::max(factor, malvar_ross_dif(mat.rate_max > 0.0 ? std::min(rate, mat.rate_max) : rate, mat.rate_fc));
      }
      law.tensile *= factor;
      if (mat.rate_cohesion)
        law.cohesion *= factor;
    }
    const double delta_max_old = l.delta_max[k];
    const NormalForce nf = link_normal_force(delta, delta_max_old, law);
    double* fs_old = &l.fs[3 * k];
    const double wk = weighted_links ? l.weight[k] : 1.0;
    l.delta_max[k] = nf.delta_max;
    // A link that breaks in this step: its force is zero at the step's end,
    // so the energy it releases is what it stored at the start plus the work
    // of its force over the step, trapezoidal as the velocity-Verlet kicks
    // apply it (zero at the end): for the shear spring,
    // |fs_old|^2 / (2 K_s) + fs_old . du / 2 = fs_old . fs_trial / (2 K_s).
    const Vec3 trial{n[4], n[5], n[6]};
    if (nf.state == NormalState::broken)
    {
      l.state[k] = LinkState::broken_tension;
      s.broken[omp_get_thread_num()].emplace_back(k, wk * 0.5 * dot3(fs_old, trial.data()) / law.ks);
      std::fill(fs_old, fs_old + 3, 0.0);
      std::fill(out, out + 6, 0.0);
      return false;
    }
    const ShearForce sf = link_shear_cap(trial, nf.fn, law);
    if (track)
    {
      // the cap with C0 = the demand before this call; beyond it, this
      // thread's demand grows
      const double f2 = dot3(trial.data(), trial.data());
      // (in units of the base C0: the link's cap is its factor times C0)
      const double factor = factored && mat.rate_cohesion ? l.strength[k] : 1.0;
      const double room = law.s_int * demand_before * factor - nf.fn * law.tan_phi_i;
      if (f2 > 0.0 && (room < 0.0 || f2 > room * room))
      {
        double& dm = s.demand[8 * omp_get_thread_num()];
        dm = std::max(dm, (std::sqrt(f2) + nf.fn * law.tan_phi_i) / (law.s_int * factor));
      }
    }
    if (sf.exceeded)
    {
      // Mohr-Coulomb reached: the link breaks and its elastic energy is
      // released; if the spheres touch, a contact takes over from zero shear.
      l.state[k] = LinkState::broken_shear;
      // The normal spring likewise releases fn_old delta / 2 (what it
      // stored, elastic or on the secant, plus the work fn_old (delta -
      // delta_old) / 2), the elongation at the step's start from the
      // drift, delta_old = delta - dt (v_b - v_a) . n with v(n+1/2).
      // All from the state at the step's start: its softening and
      // compaction (states whose energies count apart) are put back, and
      // the elongations count from the set it had then.
      l.delta_max[k] = delta_max_old;
      double from_set = delta;
      if (compacting)
      {
        l.compaction[k] = e_max_old;
        if (pressure_gated)
          l.compaction_onset[k] = onset_old;
        from_set = (D - l.d0[k]) - compaction_set(e_max_old, l.d0[k], link_compaction(l, k, mat.compaction));
      }
      const double* va = &p.v[3 * i];
      const double* vb = &p.v[3 * l.b[k]];
      const double delta_old =
          from_set - dt * ((vb[0] - va[0]) * n[0] + (vb[1] - va[1]) * n[1] + (vb[2] - va[2]) * n[2]);
      const double fn_old = link_normal_force(delta_old, delta_max_old, law).fn;
      // with crack closure a compressed link's normal spring goes on as the
      // contact's (the same K_n) from the closing distance: the contact keeps
      // the share (its overlap / the link's shortening)^2 of the spring's
      // energy, all of it at c = 1 (the same rest distance); the rest is
      // released
      double normal = 0.5 * fn_old * from_set;
      if (mat.crack_closure > 0.0 && from_set < 0.0)
      {
        // (the set of e_max at the step's start, as from_set's)
        const double set =
            compacting ? compaction_set(l.compaction[k], l.d0[k], link_compaction(l, k, mat.compaction)) : 0.0;
        const double touch =
            contact_spring(mat, cf, l, k, rec[record * i + 3], rec[record * l.b[k] + 3], compacting).touch;
        const double share = std::clamp(1.0 - (l.d0[k] + set - touch) / -from_set, 0.0, 1.0);
        normal *= 1.0 - share * share;
      }
      s.broken[omp_get_thread_num()].emplace_back(k, wk * (normal + 0.5 * dot3(fs_old, trial.data()) / law.ks));
      std::fill(fs_old, fs_old + 3, 0.0);
      std::fill(out, out + 6, 0.0);
      return false;
    }
    for (int q = 0; q < 3; ++q)
    {
      fs_old[q] = sf.fs[q];
      l.n[3 * k + q] = n[q];
    }
    pair_output(out, n, wk * nf.fn, {wk * sf.fs[0], wk * sf.fs[1], wk * sf.fs[2]}, D, n[7]);
    return true;
  };

#pragma omp parallel num_threads(nt)
  {
    if (omp_get_num_threads() != nt)
    {
#pragma omp atomic write
      short_team = true;
    }
    else
    {
      // each sphere's record: centre, radius, rotation over the step
#pragma omp for schedule(static)
      for (std::size_t i = 0; i < np; ++i)
      {
        const Vec3 th{p.w[3 * i] * dt, p.w[3 * i + 1] * dt, p.w[3 * i + 2] * dt};
        if (detail::dot(th, th) > 1.0)
        {
#pragma omp critical(dem_spinning)
          spinning = std::min(spinning, i);
        }
        const StepRotation q = step_rotation(th);
        double* r = rec + record * i;
        r[0] = p.x[3 * i];
        r[1] = p.x[3 * i + 1];
        r[2] = p.x[3 * i + 2];
        r[3] = rad[i];
        r[4] = q.u[0];
        r[5] = q.u[1];
        r[6] = q.u[2];
        r[7] = q.k;
      }
      sweep<6>(s.links, l.b, true, f, t, link_prepare, link_force);
    }
  }
  if (short_team)
    throw std::runtime_error("force loop: OpenMP gave fewer threads than asked (set OMP_DYNAMIC=false)");
  if (spinning < np)
  {
    std::ostringstream msg;
    msg << "force loop: sphere " << spinning << " turns by "
        << dt * std::sqrt(dot3(&p.w[3 * spinning], &p.w[3 * spinning])) << " rad in one step of "
        << dt << " s (angular velocity |w| dt must stay below 1 rad; the time step is far above "
           "the critical one, or the state diverged)";
    throw std::runtime_error(msg.str());
  }
  if (track)
    for (int k = 0; k < nt; ++k)
      c.cohesion_demand = std::max(c.cohesion_demand, s.demand[8 * k]);

  // links broken now: energy booked in link order, their pairs handed to the
  // contacts within this step
  s.broken_all.clear();
  for (const auto& b : s.broken)
    s.broken_all.insert(s.broken_all.end(), b.begin(), b.end());
  std::sort(s.broken_all.begin(), s.broken_all.end());
  s.broken_ids.clear();
  for (const auto& [k, e] : s.broken_all)
  {
    c.breakage += e;
    s.broken_ids.push_back(k);
  }
  const double merge_start = omp_get_wtime();
  nl.add_broken_links(l, s.broken_ids);
  const double contacts_start = omp_get_wtime();
  c.neighbour_seconds += contacts_start - merge_start;
  if (s.pairs_version != nl.version() || s.pairs.first.size() != np + 1 || s.pairs.threads != nt)
  {
    s.pairs.build(np, nl.a, nl.b, nt);
    s.pair_slip.assign(nl.size(), 0.0);
    s.pairs_version = nl.version();
  }

  // contacts between spheres without an intact link; with rolling
  // resistance (width 9) each also applies a moment pair (law.h,
  // trial_rolling). A list that carries moments keeps the law (with mu_r =
  // 0 its cap is zero: the moments go, their energy booked as friction).
  const bool rolling = mat.rolling_friction > 0.0 || nl.rolling();
  if (rolling)
    nl.keep_rolling();
  auto contact_force = [&](auto width, std::size_t i, std::int32_t q, const double* n, double* out)
                           __attribute__((always_inline)) -> bool
  {
    constexpr int W = decltype(width)::value;
    s.pair_slip[q] = 0.0;
    if (n[3] < 0.0) // apart, and was (contact_prepare)
    {
      std::fill(out, out + W, 0.0);
      return false;
    }
    const std::int32_t j = nl.b[q];
    const double D = n[3];
    const double rs = rad[i] + rad[j];
    // where the spheres touch, and the springs (impl::contact_spring)
    const ContactSpring cs = contact_spring(mat, cf, l, nl.link[q], rad[i], rad[j], compacting);
    const double touch = cs.touch;
    double* fs_old = &nl.fs[3 * q];
    // the rolling spring: k_r = K_s R*^2 (method.md 1.7d)
    const double r_star = rad[i] * rad[j] / rs;
    if (D >= touch) // (a listed pair never has an intact link: NeighbourList)
    {
      if (nl.touching[q])
      {
        // the contact opens: its caps fell to zero, so the shear (and
        // rolling) springs' energy went by sliding (friction)
        const double wq = weighted_spheres ? 0.5 * (p.weight[i] + p.weight[j]) : 1.0;
        double e = wq * 0.5 * dot3(fs_old, fs_old) / cs.ks;
        if constexpr (W == 9)
          e += wq * 0.5 * dot3(&nl.mr[3 * q], &nl.mr[3 * q]) / (cs.ks * r_star * r_star);
        s.pair_slip[q] = e;
      }
      nl.touching[q] = 0;
      std::fill(fs_old, fs_old + 3, 0.0);
      if constexpr (W == 9)
        std::fill(&nl.mr[3 * q], &nl.mr[3 * q] + 3, 0.0);
      std::fill(out, out + W, 0.0);
      return false;
    }
    LinkLaw law = base;
    law.s_int = pair_surface(rad[i], rad[j]);
    law.kn = cs.kn;
    law.ks = cs.ks;
    const double fn = contact_normal_force(D, touch, law.kn);
    const bool touched = nl.touching[q];
    const double* n_old = touched ? &nl.n[3 * q] : n;
    const Vec3 fs_prev = touched ? Vec3{fs_old[0], fs_old[1], fs_old[2]} : Vec3{0, 0, 0};
    const Mat3 qa = rotation_minus_identity(load_rotation(rec + record * i));
    const StepRotation qb = load_rotation(rec + record * j);
    const Vec3 trial = trial_shear(fs_prev, {n_old[0], n_old[1], n_old[2]}, {n[0], n[1], n[2]}, qa, qb,
                                   rad[i] / rs, law.ks * D);
    const ShearForce sf = contact_shear_cap(trial, fn, law, fs_prev);
    const double wq = weighted_spheres ? 0.5 * (p.weight[i] + p.weight[j]) : 1.0;
    s.pair_slip[q] = wq * sf.slip_energy;
    for (int k = 0; k < 3; ++k)
    {
      fs_old[k] = sf.fs[k];
      nl.n[3 * q + k] = n[k];
    }
    nl.touching[q] = 1;
    pair_output(out, n, wq * fn, {wq * sf.fs[0], wq * sf.fs[1], wq * sf.fs[2]}, D, 1.0 / rs);
    if constexpr (W == 9)
    {
      // the moment M on b, -M on a: torque factors q_a = q - M / R_a and
      // q_b = q + M / R_b (torque = radius times factor)
      double* m_old = &nl.mr[3 * q];
      const Vec3 m_prev = touched ? Vec3{m_old[0], m_old[1], m_old[2]} : Vec3{0, 0, 0};
      const double* wa = &p.w[3 * i];
      const double* wb = &p.w[3 * j];
      const double kr = law.ks * r_star * r_star;
      const Vec3 mt = trial_rolling(m_prev, {n[0], n[1], n[2]}, qa, qb, rad[i] / rs,
                                    {(wb[0] - wa[0]) * dt, (wb[1] - wa[1]) * dt, (wb[2] - wa[2]) * dt}, kr);
      const ShearForce rm = contact_rolling_cap(mt, fn, kr, mat.rolling_friction * r_star, m_prev);
      s.pair_slip[q] += wq * rm.slip_energy;
      for (int k = 0; k < 3; ++k)
      {
        m_old[k] = rm.fs[k];
        out[6 + k] = out[3 + k] + wq * rm.fs[k] / rad[j];
        out[3 + k] -= wq * rm.fs[k] / rad[i];
      }
    }
    return true;
  };
  // a pair that was apart at the last step and is farther apart now than
  // any pair can touch (R_a + R_b + the broken links' closing reach, with a
  // margin over the rounding) stays apart: it is marked (D = -1) and skipped,
  // its shear and rolling springs at zero as they were (a pair apart holds
  // no history); most listed pairs are such, in a perforation
  const double reach_margin = 1.0 + 1e-9;
  auto contact_prepare = [&](std::size_t i, std::int32_t k0, std::int32_t k1, double* g)
  {
    const double* xi = rec + record * i;
    for (std::int32_t k = k0; k < k1; ++k)
    {
      __builtin_prefetch(rec + record * b_ahead(nl.b, k));
      const double* xj = rec + record * nl.b[k];
      double* gk = g + prepared * (k - k0);
      gk[0] = xj[0] - xi[0];
      gk[1] = xj[1] - xi[1];
      gk[2] = xj[2] - xi[2];
      const double d2 = gk[0] * gk[0] + gk[1] * gk[1] + gk[2] * gk[2];
      const double far = (xi[3] + xj[3] + s.contact_reach) * reach_margin;
      gk[3] = !nl.touching[k] && d2 > far * far ? -1.0 : d2;
    }
    unit_normals(g, k1 - k0);
  };

#pragma omp parallel num_threads(nt)
  {
    if (omp_get_num_threads() == nt)
    {
      // (the rolling sweep out of line, so that the pairs' region stays as
      // small as without it: see dem/CMakeLists.txt)
      if (rolling)
        [&]() __attribute__((noinline))
        {
          sweep<9>(s.pairs, nl.b, false, f, t, contact_prepare,
                   [&](std::size_t i, std::int32_t q, const double* n, double* out) __attribute__((always_inline))
                   { return contact_force(std::integral_constant<int, 9>{}, i, q, n, out); });
        }();
      else
        sweep<6>(s.pairs, nl.b, false, f, t, contact_prepare,
                 [&](std::size_t i, std::int32_t q, const double* n, double* out) __attribute__((always_inline))
                 { return contact_force(std::integral_constant<int, 6>{}, i, q, n, out); });
      // torques: each sphere's radius times its summed torque factors
      // (the spheres whose sums this thread's sweep completed)
      const int th = omp_get_thread_num();
      for (std::size_t i = s.pairs.bounds[th]; i < s.pairs.bounds[th + 1]; ++i)
        for (int k = 0; k < 3; ++k)
          t[3 * i + k] *= rad[i];
    }
    else
    {
#pragma omp atomic write
      short_team = true;
    }
  }
  if (short_team)
    throw std::runtime_error("force loop: OpenMP gave fewer threads than asked (set OMP_DYNAMIC=false)");
  // friction, summed in pair order
  for (std::size_t q = 0; q < s.pair_slip.size(); ++q)
    c.friction += s.pair_slip[q];
  c.contact_seconds += omp_get_wtime() - contacts_start;
}

} // namespace dembridge::dem
