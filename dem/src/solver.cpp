#include "dembridge/dem/solver.h"

#include <algorithm>
#include <cstdint>
#include <omp.h>

#include "pairs.h"
#include "threads.h"
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

/// One sweep over the items of `ix` by the calling thread (call from every
/// thread of the team; see SweepIndex). compute(i, k, out) writes item k's
/// force on b and torque factor into out[6] and returns false if the item
/// acts no more (out zeroed). f and q receive the sums for this thread's
/// spheres, ix.bounds[t] to ix.bounds[t + 1]; `reset` zeroes them first.
/// The sums are the same bit for bit whatever the thread count: into each
/// sphere, the items of lower spheres in item order, then its own.
/// Values per item that a sweep prepares for a whole sphere at once.
constexpr int prepared = 8;
/// Doubles per sphere record of the force loop: centre (3), radius, the
/// rotation over the step as a StepRotation (u (3), k): 64 bytes, one cache
/// line, all that a link reads of its sphere b.
constexpr int record = 8;
/// How many items ahead the sweep prefetches what item k's sphere b needs:
/// sphere b lies anywhere along the curve, so its record, force and torque
/// are rarely in the core's caches when its item comes.
constexpr std::int32_t ahead = 16;
/// Sphere b of the item `ahead` items after k (the last item near the end).
inline std::int32_t b_ahead(std::span<const std::int32_t> b, std::int32_t k)
{
  return b[std::min<std::size_t>(static_cast<std::size_t>(k + ahead), b.size() - 1)];
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
  for (std::int32_t m = 0; m < k1 - k0; ++m)
  {
    double* gk = g + prepared * m;
    const double D = std::sqrt(gk[3]);
    const double inv = 1.0 / D;
    gk[0] *= inv;
    gk[1] *= inv;
    gk[2] *= inv;
    gk[3] = D;
  }
}

/// prepare(i, k0, k1, g) fills the `prepared` values of the items of sphere
/// i (reading state only); compute(i, k, g_k, out) then does item k.
template <typename Prepare, typename Compute>
void sweep(SweepIndex& ix, std::span<const std::int32_t> b, bool reset,
           double* f, double* q, Prepare&& prepare, Compute&& compute)
{
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
      compute(static_cast<std::size_t>(i), k, g.data(), &ix.out[6 * c]);
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
      const double* o = &ix.out[6 * ix.in[e]];
      for (int c = 0; c < 3; ++c)
      {
        f[3 * j + c] += o[c];
        q[3 * j + c] += o[3 + c];
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
      double local[6];
      const double* o = local;
      if (j >= bhi)
        o = &ix.out[6 * slot++];
      else if (compute(i, k, &g[prepared * (k - k0)], local))
        for (int c = 0; c < 3; ++c)
        {
          f[3 * j + c] += local[c];
          q[3 * j + c] += local[3 + c];
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
} // namespace

void SweepIndex::build(std::size_t np, std::span<const std::int32_t> a,
                       std::span<const std::int32_t> b, int nt)
{
  first = impl::first_by_a(np, a, b, "force loop: links and pairs");
  threads = nt;
  // thread t sweeps spheres [bounds[t], bounds[t + 1]): equal shares of
  // items + spheres (a sphere's own cost, reset and sums, ~ one item),
  // not of spheres -- where the sphere order makes the early spheres own
  // more items (a Morton curve over a box whose sides are not in powers of
  // 2) a split by spheres left one thread 24 % more items (coupled bar)
  bounds.assign(nt + 1, np);
  bounds[0] = 0;
  {
    const double total = static_cast<double>(first[np]) + static_cast<double>(np);
    std::size_t i = 0;
    for (int t = 1; t < nt; ++t)
    {
      const double share = total * t / nt;
      while (i < np && static_cast<double>(first[i]) + static_cast<double>(i) < share)
        ++i;
      bounds[t] = i;
    }
  }
  cross_first.assign(nt + 1, 0);
  in_first.assign(np + 1, 0);
  cross_i.clear();
  cross_k.clear();
  std::vector<std::int32_t> target;
  for (int t = 0; t < nt; ++t)
  {
    const std::size_t lo = bounds[t], hi = bounds[t + 1];
    cross_first[t + 1] = cross_first[t];
    for (std::size_t i = lo; i < hi; ++i)
      for (std::int32_t k = first[i]; k < first[i + 1]; ++k)
        if (static_cast<std::size_t>(b[k]) >= hi)
        {
          ++cross_first[t + 1];
          ++in_first[b[k] + 1];
          target.push_back(b[k]);
          cross_i.push_back(static_cast<std::int32_t>(i));
          cross_k.push_back(k);
        }
  }
  for (std::size_t i = 0; i < np; ++i)
    in_first[i + 1] += in_first[i];
  in.resize(target.size());
  std::vector<std::int32_t> fill(in_first.begin(), in_first.end() - 1);
  for (std::size_t s = 0; s < target.size(); ++s) // slots are in item order
    in[fill[target[s]]++] = static_cast<std::int32_t>(s);
  out.assign(6 * target.size(), 0.0);
  std::int32_t most = 0;
  for (std::size_t i = 0; i < np; ++i)
    most = std::max(most, first[i + 1] - first[i]);
  geometry.assign(nt, std::vector<double>(prepared * most));
}

void set_min_spheres_per_thread_team(std::size_t n) { impl::min_items_per_team() = n; }
std::size_t min_spheres_per_thread_team() { return impl::min_items_per_team(); }

std::size_t SweepIndex::bytes() const
{
  std::size_t s = (first.capacity() + cross_first.capacity() + in_first.capacity() + in.capacity()
                   + cross_i.capacity() + cross_k.capacity())
             * sizeof(std::int32_t)
         + out.capacity() * sizeof(double) + bounds.capacity() * sizeof(std::size_t);
  for (const auto& g : geometry)
    s += g.capacity() * sizeof(double);
  return s;
}

std::size_t ForceScratch::bytes() const
{
  std::size_t s = (records.capacity() + pair_slip.capacity()) * sizeof(double) + links.bytes()
                  + pairs.bytes() + broken_ids.capacity() * sizeof(std::int32_t)
                  + broken_all.capacity() * sizeof(broken_all[0]);
  for (const auto& b : broken)
    s += b.capacity() * sizeof(b[0]);
  return s;
}

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
    const double delta = D - l.d0[k];
    const NormalForce nf = link_normal_force(delta, l.delta_max[k], law);
    double* fs_old = &l.fs[3 * k];
    const double wk = weighted_links ? l.weight[k] : 1.0;
    l.delta_max[k] = nf.delta_max;
    if (nf.state == NormalState::broken)
    {
      l.state[k] = LinkState::broken_tension;
      s.broken[omp_get_thread_num()].emplace_back(k, wk * 0.5 * dot3(fs_old, fs_old) / law.ks);
      std::fill(fs_old, fs_old + 3, 0.0);
      std::fill(out, out + 6, 0.0);
      return false;
    }
    const Vec3 trial{n[4], n[5], n[6]};
    const ShearForce sf = link_shear_cap(trial, nf.fn, law);
    if (track)
    {
      // the cap with C0 = the demand before this call; beyond it, this
      // thread's demand grows
      const double f2 = dot3(trial.data(), trial.data());
      const double room = law.s_int * demand_before - nf.fn * law.tan_phi_i;
      if (f2 > 0.0 && (room < 0.0 || f2 > room * room))
      {
        double& dm = s.demand[8 * omp_get_thread_num()];
        dm = std::max(dm, (std::sqrt(f2) + nf.fn * law.tan_phi_i) / law.s_int);
      }
    }
    if (sf.exceeded)
    {
      // Mohr-Coulomb reached: the link breaks and its elastic energy is
      // released; if the spheres touch, a contact takes over from zero shear.
      l.state[k] = LinkState::broken_shear;
      s.broken[omp_get_thread_num()].emplace_back(
          k, wk * (0.5 * nf.fn * delta + 0.5 * dot3(sf.fs.data(), sf.fs.data()) / law.ks));
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
      sweep(s.links, l.b, true, f, t, link_prepare, link_force);
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
  nl.add_broken_links(l, s.broken_ids);
  if (s.pairs_version != nl.version() || s.pairs.first.size() != np + 1 || s.pairs.threads != nt)
  {
    s.pairs.build(np, nl.a, nl.b, nt);
    s.pair_slip.assign(nl.size(), 0.0);
    s.pairs_version = nl.version();
  }

  // contacts between spheres without an intact link
  auto contact_force = [&](std::size_t i, std::int32_t q, const double* n, double* out)
                           __attribute__((always_inline)) -> bool
  {
    s.pair_slip[q] = 0.0;
    const std::int32_t j = nl.b[q];
    const double D = n[3];
    const double rs = rad[i] + rad[j];
    double* fs_old = &nl.fs[3 * q];
    if (D >= rs) // (a listed pair never has an intact link: NeighbourList)
    {
      nl.touching[q] = 0;
      std::fill(fs_old, fs_old + 3, 0.0);
      std::fill(out, out + 6, 0.0);
      return false;
    }
    LinkLaw law = base;
    law.s_int = pair_surface(rad[i], rad[j]);
    law.kn = mat.youngs_modulus * law.s_int / rs * cf.cn;
    law.ks = law.kn * cf.cs;
    const double fn = contact_normal_force(D, rs, law.kn);
    const double* n_old = nl.touching[q] ? &nl.n[3 * q] : n;
    const Vec3 fs_prev = nl.touching[q] ? Vec3{fs_old[0], fs_old[1], fs_old[2]} : Vec3{0, 0, 0};
    const Vec3 trial = trial_shear(fs_prev, {n_old[0], n_old[1], n_old[2]}, {n[0], n[1], n[2]},
                                   rotation_minus_identity(load_rotation(rec + record * i)),
                                   load_rotation(rec + record * j),
                                   rad[i] / rs, law.ks * D);
    const ShearForce sf = contact_shear_cap(trial, fn, law);
    const double wq = weighted_spheres ? 0.5 * (p.weight[i] + p.weight[j]) : 1.0;
    s.pair_slip[q] = wq * sf.slip_energy;
    for (int k = 0; k < 3; ++k)
    {
      fs_old[k] = sf.fs[k];
      nl.n[3 * q + k] = n[k];
    }
    nl.touching[q] = 1;
    pair_output(out, n, wq * fn, {wq * sf.fs[0], wq * sf.fs[1], wq * sf.fs[2]}, D, 1.0 / rs);
    return true;
  };

#pragma omp parallel num_threads(nt)
  {
    if (omp_get_num_threads() == nt)
    {
      sweep(s.pairs, nl.b, false, f, t,
            [&](std::size_t i, std::int32_t k0, std::int32_t k1, double* g)
            { branches(rec, i, nl.b, k0, k1, g); },
            contact_force);
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
    law.s_int = link_surface(p, l, k);
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

double softening_energy(const Particles& p, const Links& l, const Material& mat)
{
  double e = 0.0;
  LinkLaw law = mat.law(1.0, 1.0, 1.0);
  for (std::size_t k = 0; k < l.size(); ++k)
  {
    if (l.delta_max[k] <= 0.0)
      continue;
    law.kn = l.kn[k];
    law.ks = l.ks[k];
    law.s_int = link_surface(p, l, k);
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
}

std::size_t DemSolver::bytes() const
{
  return _held.capacity() + (_held_dofs.capacity()) * sizeof(std::int32_t)
         + (_fext.capacity() + _fext_old.capacity() + _reac.capacity() + _fold.capacity()
            + _vold.capacity() + _part.capacity())
               * sizeof(double)
         + _scratch.bytes() + _nl.bytes();
}

void DemSolver::update_held()
{
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
  _fold.assign(_held_dofs.size(), 0.0);
  _vold.assign(_held_dofs.size(), 0.0);
  _reac.assign(_held_dofs.size(), 0.0);
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
    if (i < 0 || static_cast<std::size_t>(i) >= _p.size())
      throw std::runtime_error("condition '" + m.name + "': sphere index out of range");
  for (const auto& f : _forces)
    if (f.plate)
      for (auto i : m.ids)
        if (std::find(f.ids.begin(), f.ids.end(), i) != f.ids.end())
          throw std::runtime_error("condition '" + m.name + "' holds sphere " + std::to_string(i)
                                   + " of the loading plate '" + f.name + "': a plate's spheres must move freely");
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
        if (_held[6 * i + k])
          throw std::runtime_error("force '" + f.name + "': sphere " + std::to_string(i)
                                   + " of the loading plate is held by a condition; a plate's spheres must move freely");
    for (const auto& o : _motions)
      if (o.hinged())
        for (auto i : f.ids)
          if (std::find(o.ids.begin(), o.ids.end(), i) != o.ids.end())
            throw std::runtime_error("force '" + f.name + "': sphere " + std::to_string(i)
                                     + " of the loading plate moves with the hinged condition '" + o.name
                                     + "'; a plate's spheres must move freely");
  }
  _forces.push_back(std::move(f));
  // external force arrays only once there is an external force
  _fext.resize(3 * _p.size(), 0.0);
  _fext_old.resize(3 * _p.size(), 0.0);
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

namespace
{
/// The motions of a plate (a set of spheres) along a unit direction d: its
/// translation, and (with `rotates`) its two rotations normal to d, whose
/// component along d is linear in the position across d. The rotation
/// modes are mass-orthonormalised (Gram-Schmidt); one the spheres do not
/// span (all on one line across d, or a single sphere) is dropped, as it
/// moves no sphere.
struct PlateModes
{
  double mass = 0.0;
  int nrot = 0;
  std::vector<std::array<double, 2>> phi; ///< per sphere, the rotation modes' v_d
};

PlateModes plate_modes(const Particles& p, const std::vector<std::int32_t>& ids, const double* d,
                       bool rotates)
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
  // e0, e1: an orthonormal pair normal to d
  double e[2][3], t[3] = {0.0, 0.0, 0.0};
  t[std::abs(d[0]) < 0.9 ? 0 : 1] = 1.0;
  const double td = dot3(t, d);
  for (int k = 0; k < 3; ++k)
    e[0][k] = t[k] - td * d[k];
  const double n0 = std::sqrt(dot3(e[0], e[0]));
  for (int k = 0; k < 3; ++k)
    e[0][k] /= n0;
  e[1][0] = d[1] * e[0][2] - d[2] * e[0][1];
  e[1][1] = d[2] * e[0][0] - d[0] * e[0][2];
  e[1][2] = d[0] * e[0][1] - d[1] * e[0][0];
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

void DemSolver::start()
{
  _nl.update(_p.x, _p.r, _l);
  compute_forces(_p, _l, _nl, _mat, 0.0, _counters, _scratch);
  if (!_forces.empty())
    external(_forces, _t, _fext);
  _e = DemEnergy{};
  const DemEnergy e = energy();
  _e.initial = e.kinetic + e.elastic;
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

void DemSolver::move_hinged(std::size_t motion, double t_half, double t_new, bool begin)
{
  const auto& m = _motions[motion];
  for (int k = 0; k < 3; ++k)
  {
    if (!m.components[k])
      continue;
    const double d[3] = {k == 0 ? 1.0 : 0.0, k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0};
    const auto pm = plate_modes(_p, m.ids, d, true);
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
  kick(0.5 * dt);
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

void DemSolver::end_step()
{
  if (!_in_step)
    throw std::runtime_error("DemSolver::end_step without begin_step");
  _in_step = false;
  const double t0 = omp_get_wtime();
  const std::size_t n = _p.size();
  const double dt = _dt, t_new = _t + dt;
  std::swap(_fext_old, _fext); // no allocation in the step loop
  const bool loaded = !_forces.empty();
  if (loaded)
    external(_forces, t_new, _fext);
  const std::vector<double>& fext_old = _fext_old;
  // drift, with the work of external forces and of damping summed in fixed
  // blocks (the same sums whatever the thread count)
  constexpr std::size_t block = 1024;
  const std::size_t nb = (n + block - 1) / block;
  _part.resize(2 * nb);
  // moves by multiples of the position quantum q (Particles::quantum):
  // (d + C) - C rounds d to a multiple of q for |d| < 2^51 q, C = 1.5 2^52 q,
  // and x + that is exact, so equal velocities move spheres by equal bits
  const double q = _p.quantum;
  const double C = q > 0.0 ? std::ldexp(1.5, 52) * q : 0.0;
#pragma omp parallel for schedule(static) num_threads(impl::threads_for(n))
  for (std::size_t b = 0; b < nb; ++b)
  {
    double we = 0.0, wd = 0.0;
    for (std::size_t i = b * block; i < std::min(n, (b + 1) * block); ++i)
    {
      double v2 = 0.0, w2 = 0.0;
      for (int k = 0; k < 3; ++k)
      {
        const double vh = _p.v[3 * i + k];
        const double dx = q > 0.0 ? (dt * vh + C) - C : dt * vh;
        _p.x[3 * i + k] += dx;
        if (loaded)
          we += dx * 0.5 * (fext_old[3 * i + k] + _fext[3 * i + k]);
        v2 += vh * vh;
        w2 += _p.w[3 * i + k] * _p.w[3 * i + k];
      }
      wd += dt * _c * (_p.m[i] * v2 + _p.inertia[i] * w2);
    }
    _part[2 * b] = we;
    _part[2 * b + 1] = wd;
  }
  double w_ext = 0.0, w_damp = 0.0;
  for (std::size_t b = 0; b < nb; ++b)
  {
    w_ext += _part[2 * b];
    w_damp += _part[2 * b + 1];
  }
  const double t1 = omp_get_wtime();
  _nl.update(_p.x, _p.r, _l);
  const double t2 = omp_get_wtime();
  compute_forces(_p, _l, _nl, _mat, dt, _counters, _scratch);
  const double t3 = omp_get_wtime();
  _time.neighbours += t2 - t1;
  _time.forces += t3 - t2;
  // reactions on held translations: m (v_new - v_old) = dt/2 (F_old + F_new) + dt R
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
  kick(0.5 * dt);
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

  // any NaN or infinity makes the sum non-finite, whatever the order
  double check = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : check) num_threads(impl::threads_for(n))
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
  _time.integration += (t1 - t0) + (omp_get_wtime() - t3);
}

DemEnergy DemSolver::energy() const
{
  DemEnergy e = _e;
  e.kinetic = 0.0;
  for (std::size_t i = 0; i < _p.size(); ++i)
    e.kinetic += 0.5 * _p.m[i] * dot3(&_p.v[3 * i], &_p.v[3 * i])
                 + 0.5 * _p.inertia[i] * dot3(&_p.w[3 * i], &_p.w[3 * i]);
  e.elastic = elastic_energy(_p, _l, _nl, _mat);
  e.softening = softening_energy(_p, _l, _mat);
  e.breakage = _counters.breakage;
  e.friction = _counters.friction;
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
