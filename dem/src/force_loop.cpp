#include "force_loop.h"
#include "contact_kernel.h"
#include "link_kernel.h"

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
using impl::dot3;
using kernel::b_ahead;

namespace
{
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

namespace
{
/// Rebuilds the sweeps' indices when the links or the thread count changed,
/// and the contacts' reach when the crack closure did.
void fit_scratch(const Particles& p, const Links& l, const Material& mat, int nt, ForceScratch& s)
{
  const std::size_t np = p.size();
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
  if (s.broken.size() < static_cast<std::size_t>(nt))
    s.broken.resize(nt);
  for (auto& b : s.broken)
    b.clear();
}

/// The spheres' records, 64-byte aligned (one cache line each).
double* aligned_records(ForceScratch& s, std::size_t np)
{
  s.records.resize(record * np + record);
  double* rec = s.records.data();
  return rec + (record - (reinterpret_cast<std::uintptr_t>(rec) / sizeof(double)) % record) % record;
}

/// Sphere i's record: centre, radius, rotation over the step. Returns
/// false if it turns by more than 1 rad in the step.
inline bool fill_record(const Particles& p, std::size_t i, double dt, double* rec)
{
  const Vec3 th{p.w[3 * i] * dt, p.w[3 * i + 1] * dt, p.w[3 * i + 2] * dt};
  const StepRotation q = step_rotation(th);
  double* r = rec + record * i;
  r[0] = p.x[3 * i];
  r[1] = p.x[3 * i + 1];
  r[2] = p.x[3 * i + 2];
  r[3] = p.r[i];
  r[4] = q.u[0];
  r[5] = q.u[1];
  r[6] = q.u[2];
  r[7] = q.k;
  return !(detail::dot(th, th) > 1.0);
}

void check_team(bool short_team)
{
  if (short_team)
    throw std::runtime_error("force loop: OpenMP gave fewer threads than asked (set OMP_DYNAMIC=false)");
}

void check_spin(const Particles& p, std::size_t spinning, double dt)
{
  if (spinning >= p.size())
    return;
  std::ostringstream msg;
  msg << "force loop: sphere " << spinning << " turns by "
      << dt * std::sqrt(dot3(&p.w[3 * spinning], &p.w[3 * spinning])) << " rad in one step of " << dt
      << " s (angular velocity |w| dt must stay below 1 rad; the time step is far above "
         "the critical one, or the state diverged)";
  throw std::runtime_error(msg.str());
}

/// The links broken in this step: their energy booked in link order, their
/// ids in s.broken_ids (their pairs go to the contacts within this step).
void book_broken_links(ForceScratch& s, ForceCounters& c)
{
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
}

/// The links' sweep: each sphere's record, then every intact link's force
/// (LinkKernel), the sums reset. Returns the first sphere that turns by
/// more than 1 rad in the step (np if none).
std::size_t sweep_links(Particles& p, Links& l, double dt, int nt, ForceScratch& s, double* rec,
                        const kernel::LinkKernel& links)
{
  const std::size_t np = p.size();
  bool short_team = false;
  std::size_t spinning = np;
#pragma omp parallel num_threads(nt)
  {
    if (omp_get_num_threads() != nt)
    {
#pragma omp atomic write
      short_team = true;
    }
    else
    {
#pragma omp for schedule(static)
      for (std::size_t i = 0; i < np; ++i)
        if (!fill_record(p, i, dt, rec))
        {
#pragma omp critical(dem_spinning)
          spinning = std::min(spinning, i);
        }
      // (each thread's own copy of the kernel, in its lambdas)
      sweep<6>(
          s.links, l.b, true, p.f.data(), p.t.data(),
          [links](std::size_t i, std::int32_t k0, std::int32_t k1, double* g) __attribute__((always_inline))
          { links.prepare(i, k0, k1, g); },
          [links](std::size_t i, std::int32_t k, const double* n, double* out) __attribute__((always_inline))
          { return links.force(i, k, n, out); });
    }
  }
  check_team(short_team);
  return spinning;
}

/// The contacts' sweep (ContactKernel; width 9 with rolling resistance),
/// added to the links' sums, then each sphere's torque: its radius times
/// its summed torque factors.
void sweep_contacts(Particles& p, const NeighbourList& nl, bool rolling, int nt, ForceScratch& s,
                    const kernel::ContactKernel& contacts)
{
  double* f = p.f.data();
  double* t = p.t.data();
  const double* rad = p.r.data();
  bool short_team = false;
  auto prepare = [&](std::size_t i, std::int32_t k0, std::int32_t k1, double* g) { contacts.prepare(i, k0, k1, g); };
#pragma omp parallel num_threads(nt)
  {
    if (omp_get_num_threads() == nt)
    {
      // (the rolling sweep out of line, so that the pairs' region stays as
      // small as without it: see dem/CMakeLists.txt)
      if (rolling)
        [&]() __attribute__((noinline))
        {
          sweep<9>(s.pairs, nl.b, false, f, t, prepare,
                   [&](std::size_t i, std::int32_t q, const double* n, double* out) __attribute__((always_inline))
                   { return contacts.force<9>(i, q, n, out); });
        }();
      else
        sweep<6>(s.pairs, nl.b, false, f, t, prepare,
                 [&](std::size_t i, std::int32_t q, const double* n, double* out) __attribute__((always_inline))
                 { return contacts.force<6>(i, q, n, out); });
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
  check_team(short_team);
}
} // namespace

/// The force loop's schedule: the step's law resolved once (kernel::
/// step_law), the per-sphere sums its gates need, the links' sweep, the
/// links broken now handed to the contacts, the contacts' sweep.
void compute_forces(Particles& p, Links& l, NeighbourList& nl, const Material& mat, double dt,
                    ForceCounters& c, ForceScratch& s)
{
  const std::size_t np = p.size();
  const int nt = impl::threads_for(np);
  fit_scratch(p, l, mat, nt, s);
  double* rec = aligned_records(s, np);
  const kernel::StepLaw law = kernel::step_law(p, l, mat, dt, c);
  s.demand.assign(8 * nt, law.demand_before); // a cache line per thread
  sphere_gate_sums(p, l, mat, nt, s, law.gated, law.pressure_gated);
  check_spin(p, sweep_links(p, l, dt, nt, s, rec, kernel::LinkKernel(law, p, l, s, rec)), dt);
  if (law.track)
    for (int k = 0; k < nt; ++k)
      c.cohesion_demand = std::max(c.cohesion_demand, s.demand[8 * k]);
  book_broken_links(s, c);
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
  sweep_contacts(p, nl, rolling, nt, s, kernel::ContactKernel(law, p, l, nl, s, rec));
  // friction, summed in pair order
  for (std::size_t q = 0; q < s.pair_slip.size(); ++q)
    c.friction += s.pair_slip[q];
  c.contact_seconds += omp_get_wtime() - contacts_start;
}

} // namespace dembridge::dem
