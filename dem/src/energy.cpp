// Energies of the links and contacts: what they store and what softening
// dissipated (the force loop books breakage and friction as it goes).
#include "force_loop.h"
#include "threads.h"

#include <cmath>

namespace dembridge::dem
{
using impl::ContactFactors;
using impl::contact_factors;
using impl::dot3;

namespace
{
/// Energy stored in intact link k: its normal spring from the compaction's
/// set and its shear spring, times the link's weight.
double link_energy(const Particles& p, const Links& l, const Material& mat, const LinkLaw& base,
                   bool compacting, std::size_t k)
{
  if (l.state[k] != LinkState::intact)
    return 0.0;
  const std::int32_t i = l.a[k], j = l.b[k];
  double d[3];
  for (int q = 0; q < 3; ++q)
    d[q] = p.x[3 * j + q] - p.x[3 * i + q];
  LinkLaw law = base;
  law.kn = l.kn[k];
  law.ks = l.ks[k];
  law.s_int = link_surface(p, l, k);
  if (l.strength.size() == l.size() && !l.strength.empty())
  {
    law.tensile *= l.strength[k];
    if (mat.rate_cohesion)
      law.cohesion *= l.strength[k];
  }
  double delta = std::sqrt(dot3(d, d)) - l.d0[k];
  if (compacting)
    delta -= compaction_set(l.compaction[k], l.d0[k], link_compaction(l, k, mat.compaction)); // from the set
  const double fn = link_normal_force(delta, l.delta_max[k], law).fn;
  const double wk = l.weight.empty() ? 1.0 : l.weight[k];
  return wk * (0.5 * fn * delta + 0.5 * dot3(&l.fs[3 * k], &l.fs[3 * k]) / law.ks);
}

/// Energy stored in touching contact q: the normal overlap's spring, the
/// shear spring and the rolling spring, times the pair's mean weight.
double contact_energy(const Particles& p, const Links& l, const NeighbourList& nl, const Material& mat,
                      const ContactFactors& cf, bool compacting, std::size_t q)
{
  if (!nl.touching[q])
    return 0.0;
  const std::int32_t i = nl.a[q], j = nl.b[q];
  double d[3];
  for (int k = 0; k < 3; ++k)
    d[k] = p.x[3 * j + k] - p.x[3 * i + k];
  const double rs = p.r[i] + p.r[j];
  // as the force loop has them (impl::contact_spring)
  const impl::ContactSpring cs = impl::contact_spring(mat, cf, l, nl.link[q], p.r[i], p.r[j], compacting);
  const double gap = cs.touch - std::sqrt(dot3(d, d));
  const double wq = p.weight.empty() ? 1.0 : 0.5 * (p.weight[i] + p.weight[j]);
  double e = wq * 0.5 * dot3(&nl.fs[3 * q], &nl.fs[3 * q]) / cs.ks;
  if (nl.rolling())
  {
    // the rolling spring, k_r = K_s R*^2 (method.md 1.7d)
    const double r_star = p.r[i] * p.r[j] / rs;
    e += wq * 0.5 * dot3(&nl.mr[3 * q], &nl.mr[3 * q]) / (cs.ks * r_star * r_star);
  }
  if (gap > 0.0)
    e += wq * 0.5 * cs.kn * gap * gap;
  return e;
}
} // namespace

// The sums run in parallel over fixed blocks (impl::block_sum): the same
// bit for bit on any thread count, as the step is.
double elastic_energy(const Particles& p, const Links& l, const NeighbourList& nl,
                      const Material& mat)
{
  const LinkLaw base = mat.law(1.0, 1.0, 1.0);
  // as the force loop decides it
  const bool compacting = mat.compaction.on() && l.compaction.size() == l.size();
  const double links = impl::block_sum(l.size(), [&](std::size_t k)
                                       { return link_energy(p, l, mat, base, compacting, k); });
  const ContactFactors cf = contact_factors(mat);
  const double contacts = impl::block_sum(nl.size(), [&](std::size_t q)
                                          { return contact_energy(p, l, nl, mat, cf, compacting, q); });
  return links + contacts;
}

double elastic_energy_of(const Particles& p, const Links& l, const NeighbourList& nl, const Material& mat,
                         std::span<const std::size_t> links, std::span<const std::size_t> pairs)
{
  const LinkLaw base = mat.law(1.0, 1.0, 1.0);
  const bool compacting = mat.compaction.on() && l.compaction.size() == l.size();
  const ContactFactors cf = contact_factors(mat);
  double e = 0.0;
  for (auto k : links)
    e += link_energy(p, l, mat, base, compacting, k);
  for (auto q : pairs)
    e += contact_energy(p, l, nl, mat, cf, compacting, q);
  return e;
}

double softening_energy(const Particles& p, const Links& l, const Material& mat)
{
  const LinkLaw base = mat.law(1.0, 1.0, 1.0);
  const bool rated = l.strength.size() == l.size() && !l.strength.empty();
  return impl::block_sum(l.size(),
                         [&](std::size_t k)
                         {
                           if (l.delta_max[k] <= 0.0)
                             return 0.0;
                           LinkLaw law = base;
                           law.kn = l.kn[k];
                           law.ks = l.ks[k];
                           law.s_int = link_surface(p, l, k);
                           law.tensile = mat.tensile * (rated ? l.strength[k] : 1.0);
                           return (l.weight.empty() ? 1.0 : l.weight[k]) * softening_dissipation(l.delta_max[k], law);
                         });
}

double compaction_energy(const Links& l, const Material& mat)
{
  if (!(mat.compaction.on() && l.compaction.size() == l.size()))
    return 0.0;
  return impl::block_sum(l.size(),
                         [&](std::size_t k)
                         {
                           const CompactionLaw c = link_compaction(l, k, mat.compaction);
                           if (!(l.compaction[k] > c.onset))
                             return 0.0;
                           return (l.weight.empty() ? 1.0 : l.weight[k])
                                  * compaction_dissipation(l.compaction[k], l.kn[k], l.d0[k], c);
                         });
}

} // namespace dembridge::dem
