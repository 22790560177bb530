// The linearised stiffness of the links (its action f = K u) and the
// critical time step bounded from it.
#include "force_loop.h"

#include "dembridge/dem/bars.h"
#include "dembridge/dem/body.h"
#include "dembridge/dem/linearised.h"
#include "dembridge/core/stepping.h"

#include <algorithm>
#include <limits>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace dembridge::dem
{
using impl::cross3;
using impl::dot3;

StiffnessOperator::StiffnessOperator(const Particles& p, const Links& l) : _p(p), _l(l)
{
  const std::size_t n = p.size();
  _first.assign(n + 1, 0);
  for (std::size_t k = 0; k < l.size(); ++k)
    if (l.state[k] == LinkState::intact)
    {
      ++_first[l.a[k] + 1];
      ++_first[l.b[k] + 1];
    }
  for (std::size_t i = 0; i < n; ++i)
    _first[i + 1] += _first[i];
  _links.resize(_first[n]);
  std::vector<std::int32_t> next(_first.begin(), _first.end() - 1);
  for (std::size_t k = 0; k < l.size(); ++k)
    if (l.state[k] == LinkState::intact)
    {
      _links[next[l.a[k]]++] = static_cast<std::int32_t>(k);
      _links[next[l.b[k]]++] = static_cast<std::int32_t>(k);
    }
  _out.resize(9 * l.size());
}

void StiffnessOperator::apply(std::span<const double> u, std::span<double> f)
{
  const Particles& p = _p;
  const Links& l = _l;
  const std::size_t n = p.size(), nl = l.size();
  if (u.size() != 6 * n || f.size() != 6 * n)
    throw std::runtime_error("stiffness_action: u and f need 6 values per particle");
  if (_out.size() != 9 * nl || _first.size() != n + 1)
    throw std::runtime_error("stiffness operator: the spheres or links changed since it was built");
  const double* th = u.data() + 3 * n;
  double* t = f.data() + 3 * n;
#pragma omp parallel
  {
#pragma omp for schedule(static)
    for (std::size_t k = 0; k < nl; ++k)
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
      double* o = _out.data() + 9 * k;
      for (int c = 0; c < 3; ++c)
      {
        // f = K u is the internal force: minus the force the link applies
        o[c] = -fn * nv[c] + fs[c];
        o[3 + c] = tq[0][c];
        o[6 + c] = tq[1][c];
      }
    }
#pragma omp for schedule(static)
    for (std::size_t s = 0; s < n; ++s)
    {
      double fs[3] = {0.0, 0.0, 0.0}, ts[3] = {0.0, 0.0, 0.0};
      for (auto e = _first[s]; e < _first[s + 1]; ++e)
      {
        const std::int32_t k = _links[e];
        if (l.state[k] != LinkState::intact) // (broken since construction: its slots are stale)
          continue;
        const double* o = _out.data() + 9 * k;
        const bool is_a = l.a[k] == static_cast<std::int32_t>(s);
        for (int c = 0; c < 3; ++c)
        {
          fs[c] = is_a ? fs[c] + o[c] : fs[c] - o[c];
          ts[c] -= is_a ? o[3 + c] : o[6 + c];
        }
      }
      for (int c = 0; c < 3; ++c)
      {
        f[3 * s + c] = fs[c];
        t[3 * s + c] = ts[c];
      }
    }
  }
}

void stiffness_action(const Particles& p, const Links& l, std::span<const double> u,
                      std::span<double> f)
{
  StiffnessOperator(p, l).apply(u, f);
}

namespace
{
/// Rows of M^-1/2 K M^-1/2 in 3 x 3 blocks, summed per sphere: translation
/// rt and rotation rr. Per link, translation blocks of norm <= max(kn, ks),
/// translation-rotation blocks <= ks l, rotation blocks <= ks l_a l_b (and
/// ks l_a^2 on the diagonal).
void link_rows(const Particles& p, const Links& l, std::vector<double>& rt, std::vector<double>& rr)
{
  const std::size_t n = p.size();
  rt.assign(n, 0.0);
  rr.assign(n, 0.0);
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
}

double step_from_rows(const std::vector<double>& rt, const std::vector<double>& rr)
{
  double lmax = 0.0;
  for (std::size_t i = 0; i < rt.size(); ++i)
    lmax = std::max({lmax, rt[i], rr[i]});
  if (!(lmax > 0.0))
    throw std::runtime_error("critical time step: the assembly has no intact link");
  return 2.0 / std::sqrt(lmax);
}
} // namespace

namespace
{
// rolling resistance (method.md 1.7d): each link's pair, once a contact,
// adds the rolling spring k_r = K_s R*^2 between the two rotations, rows
// k_r / I_i + k_r / sqrt(I_i I_j) (the contacts' K_s equals the links' for
// the same pair, so the links stand for the contacts the packing can have)
void rolling_rows(const Particles& p, const Links& l, std::vector<double>& rr)
{
  for (std::size_t k = 0; k < l.size(); ++k)
  {
    if (l.state[k] != LinkState::intact)
      continue;
    const std::int32_t i = l.a[k], j = l.b[k];
    const double r_star = p.r[i] * p.r[j] / (p.r[i] + p.r[j]);
    const double kr = (l.weight.empty() ? 1.0 : l.weight[k]) * l.ks[k] * r_star * r_star;
    const double Ii = p.inertia[i], Ij = p.inertia[j];
    rr[i] += kr / Ii + kr / std::sqrt(Ii * Ij);
    rr[j] += kr / Ij + kr / std::sqrt(Ii * Ij);
  }
}

} // namespace

double critical_time_step(const Particles& p, const Links& l, bool rolling)
{
  std::vector<double> rt, rr;
  link_rows(p, l, rt, rr);
  if (rolling)
    rolling_rows(p, l, rr);
  return step_from_rows(rt, rr);
}

namespace
{
// one contact with a rigid body per sphere (of infinite mass: the body's
// rows are left out), K_n = body_contact_stiffness, K_s = cs K_n, its shear
// acting at the arm r from the centre
void body_rows(const Particles& p, const Links& l, const Material& m, std::vector<double>& rt,
               std::vector<double>& rr)
{
  link_rows(p, l, rt, rr);
  const double cs = impl::contact_factors(m).cs;
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    const double kn = body_contact_stiffness(m, p.r[i]), ks = cs * kn, r = p.r[i];
    const double mi = p.m[i], Ii = p.inertia[i];
    rt[i] += std::max(kn, ks) / mi + ks * r / std::sqrt(mi * Ii);
    rr[i] += ks * r * r / Ii + ks * r / std::sqrt(Ii * mi);
  }
  if (m.rolling_friction > 0.0)
    rolling_rows(p, l, rr);
}
} // namespace

double critical_time_step(const Particles& p, const Links& l, const Material& m)
{
  std::vector<double> rt, rr;
  body_rows(p, l, m, rt, rr);
  return step_from_rows(rt, rr);
}

double critical_time_step(const Particles& p, const Links& l, const Material& m, const Bars& bars)
{
  std::vector<double> rt, rr, nodes;
  body_rows(p, l, m, rt, rr);
  add_bar_rows(bars, p, m, rt, nodes);
  const double spheres = step_from_rows(rt, rr);
  const double lmax = nodes.empty() ? 0.0 : *std::max_element(nodes.begin(), nodes.end());
  return lmax > 0.0 ? std::min(spheres, 2.0 / std::sqrt(lmax)) : spheres;
}

double critical_time_step(const Particles& p, const Links& l, const Material& m, const Bars& bars,
                          std::span<const std::uint8_t> skip_spheres, std::span<const std::uint8_t> skip_nodes)
{
  if (skip_spheres.size() != p.size() || skip_nodes.size() != bars.nodes())
    throw std::runtime_error("critical time step: the flags to skip are not one per sphere and per bar node");
  std::vector<double> rt, rr, nodes;
  body_rows(p, l, m, rt, rr);
  add_bar_rows(bars, p, m, rt, nodes);
  double lmax = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (!skip_spheres[i])
      lmax = std::max({lmax, rt[i], rr[i]});
  for (std::size_t n = 0; n < nodes.size(); ++n)
    if (!skip_nodes[n])
      lmax = std::max(lmax, nodes[n]);
  return lmax > 0.0 ? 2.0 / std::sqrt(lmax) : std::numeric_limits<double>::infinity();
}

double particle_critical_time_step(const Particles& p, const Links& l, double rtol)
{
  const std::size_t n = p.size();
  std::vector<double> mass(6 * n);
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d)
    {
      mass[3 * i + d] = p.m[i];
      mass[3 * n + 3 * i + d] = p.inertia[i];
    }
  StiffnessOperator k(p, l);
  auto f = [&](std::span<const double> z, std::span<double> out) { k.apply(z, out); };
  const double lmax = core::max_eigenvalue(mass, f, rtol, 20000);
  if (!(lmax > 0.0))
    throw std::runtime_error("critical time step: the assembly has no intact link");
  return 2.0 / std::sqrt(lmax);
}

} // namespace dembridge::dem
