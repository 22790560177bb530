// Energies of the links and contacts: what they store and what softening
// dissipated (the force loop books breakage and friction as it goes).
#include "force_loop.h"

#include <cmath>

namespace dembridge::dem
{
using impl::ContactFactors;
using impl::contact_factors;
using impl::dot3;

double elastic_energy(const Particles& p, const Links& l, const NeighbourList& nl,
                      const Material& mat)
{
  double e = 0.0;
  const LinkLaw base = mat.law(1.0, 1.0, 1.0);
  // as the force loop decides it
  const bool compacting = mat.compaction.on() && l.compaction.size() == l.size();
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
    if (l.strength.size() == l.size() && !l.strength.empty())
    {
      law.tensile *= l.strength[k];
      if (mat.rate_cohesion)
        law.cohesion *= l.strength[k];
    }
    double delta = std::sqrt(dot3(d, d)) - l.d0[k];
    if (compacting)
      delta -= compaction_set(l.compaction[k], l.d0[k], mat.compaction); // from the set
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
    // a broken compacted link's spheres touch from its rest distance (force_loop.cpp)
    const std::int32_t k = nl.link[q];
    const double touch = compacting && k >= 0 ? rs + compaction_set(l.compaction[k], l.d0[k], mat.compaction) : rs;
    const double gap = touch - std::sqrt(dot3(d, d));
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
    law.tensile = mat.tensile * (l.strength.size() == l.size() && !l.strength.empty() ? l.strength[k] : 1.0);
    e += (l.weight.empty() ? 1.0 : l.weight[k]) * softening_dissipation(l.delta_max[k], law);
  }
  return e;
}

double compaction_energy(const Links& l, const Material& mat)
{
  double e = 0.0;
  if (!(mat.compaction.on() && l.compaction.size() == l.size()))
    return e;
  for (std::size_t k = 0; k < l.size(); ++k)
    if (l.compaction[k] > mat.compaction.onset)
      e += (l.weight.empty() ? 1.0 : l.weight[k])
           * compaction_dissipation(l.compaction[k], l.kn[k], l.d0[k], mat.compaction);
  return e;
}

} // namespace dembridge::dem
