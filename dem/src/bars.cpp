#include "dembridge/dem/bars.h"

#include "bar_grid.h"
#include "errors.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <tuple>

namespace dembridge::dem
{
using impl::bar_radius;
using impl::element_grid;
using impl::ElementGrid;
using impl::max_bar_radius;
using impl::nearest_element;
namespace
{
bool finite_positive(double v) { return v > 0.0 && std::isfinite(v); }
} // namespace
using impl::dot;

void Steel::validate() const
{
  if (!finite_positive(youngs_modulus))
    impl::out_of_range("steel youngs_modulus", youngs_modulus, "> 0 Pa");
  if (!finite_positive(density))
    impl::out_of_range("steel density", density, "> 0 kg/m^3");
  if (!finite_positive(yield))
    impl::out_of_range("steel yield strength f_y", yield, "> 0 Pa");
  if (!(hardening >= 0.0) || !std::isfinite(hardening))
    impl::out_of_range("steel hardening modulus H", hardening, ">= 0 Pa");
  if (!(rupture_strain > yield / youngs_modulus) || !std::isfinite(rupture_strain))
    impl::out_of_range("steel rupture strain", rupture_strain,
           "> the yield strain f_y / E = " + std::to_string(yield / youngs_modulus));
}

void BondLaw::validate() const
{
  if (!finite_positive(tau_max))
    impl::out_of_range("bond tau_max", tau_max, "> 0 Pa");
  if (!finite_positive(s1))
    impl::out_of_range("bond s1", s1, "> 0 m");
  if (!(s0 > 0.0 && s0 < s1))
    impl::out_of_range("bond s0", s0, "in (0, s1 = " + std::to_string(s1) + ") m");
  if (!(s2 >= s1) || !std::isfinite(s2))
    impl::out_of_range("bond s2", s2, ">= s1 = " + std::to_string(s1) + " m");
  if (!(s3 > s2) || !std::isfinite(s3))
    impl::out_of_range("bond s3", s3, "> s2 = " + std::to_string(s2) + " m");
  if (!(alpha > 0.0 && alpha <= 1.0))
    impl::out_of_range("bond alpha", alpha, "in (0, 1]");
  if (!(tau_f_ratio >= 0.0 && tau_f_ratio <= 1.0))
    impl::out_of_range("bond tau_f_ratio", tau_f_ratio, "in [0, 1]");
  if (!finite_positive(radial_stiffness))
    impl::out_of_range("bond radial_stiffness", radial_stiffness, "> 0 Pa/m");
  if (!finite_positive(opening))
    impl::out_of_range("bond opening stress", opening, "> 0 Pa");
  if (!(opening_gap > opening / radial_stiffness) || !std::isfinite(opening_gap))
    impl::out_of_range("bond opening_gap", opening_gap,
           "> opening / radial_stiffness = " + std::to_string(opening / radial_stiffness) + " m");
}

LinkLaw radial_law(const BondLaw& b, double surface)
{
  LinkLaw l{};
  l.kn = b.radial_stiffness * surface;
  l.s_int = surface;
  l.tensile = b.opening;
  l.zeta = b.opening_gap * b.radial_stiffness / b.opening - 1.0;
  return l;
}

double BondLaw::k0() const { return tau_max * std::pow(s0 / s1, alpha) / s0; }

double bond_envelope(double slip, const BondLaw& b)
{
  const double s = std::abs(slip);
  if (s <= b.s0)
    return b.k0() * s;
  if (s <= b.s1)
    return b.tau_max * std::pow(s / b.s1, b.alpha);
  if (s <= b.s2)
    return b.tau_max;
  const double tau_f = b.tau_f_ratio * b.tau_max;
  if (s <= b.s3)
    return b.tau_max - (b.tau_max - tau_f) * (s - b.s2) / (b.s3 - b.s2);
  return tau_f;
}

SteelState steel_update(double strain, double plastic, double alpha, const Steel& s)
{
  SteelState out{0.0, plastic, alpha, strain >= s.rupture_strain};
  if (out.broken)
    return out;
  const double trial = s.youngs_modulus * (strain - plastic);
  const double over = std::abs(trial) - (s.yield + s.hardening * alpha);
  if (over <= 0.0)
  {
    out.stress = trial;
    return out;
  }
  // radial return: d gamma = over / (E + H)
  const double dg = over / (s.youngs_modulus + s.hardening), sign = trial > 0.0 ? 1.0 : -1.0;
  out.stress = trial - sign * s.youngs_modulus * dg;
  out.plastic = plastic + sign * dg;
  out.alpha = alpha + dg;
  return out;
}

double steel_plastic_work(double alpha, const Steel& s)
{
  return s.yield * alpha + 0.5 * s.hardening * alpha * alpha;
}

std::array<double, 3> bond_shear(double tau_old, double slip_old, double slip, double slip_max,
                                 const BondLaw& b)
{
  const double k0 = b.k0();
  const double smax = std::max(slip_max, std::abs(slip));
  const double cap = bond_envelope(smax, b);
  const double trial = tau_old + k0 * (slip - slip_old);
  const double tau = std::clamp(trial, -cap, cap);
  const double dissipated =
      0.5 * (tau_old + tau) * (slip - slip_old) - (tau * tau - tau_old * tau_old) / (2.0 * k0);
  return {tau, smax, dissipated};
}

namespace
{
/// Whether the boxes of elements e and g, each grown by its bar's
/// diameter, are apart (then the bars cannot overlap there).
bool boxes_apart(const Bars& bars, std::size_t e, std::size_t g)
{
  const double grow = 2.0 * (std::sqrt(bars.area[e] / std::numbers::pi) + std::sqrt(bars.area[g] / std::numbers::pi));
  for (int k = 0; k < 3; ++k)
  {
    const double e0 = std::min(bars.x[3 * bars.a[e] + k], bars.x[3 * bars.b[e] + k]),
                 e1 = std::max(bars.x[3 * bars.a[e] + k], bars.x[3 * bars.b[e] + k]),
                 g0 = std::min(bars.x[3 * bars.a[g] + k], bars.x[3 * bars.b[g] + k]),
                 g1 = std::max(bars.x[3 * bars.a[g] + k], bars.x[3 * bars.b[g] + k]);
    if (e1 + grow < g0 || g1 + grow < e0)
      return true;
  }
  return false;
}
} // namespace

Bars make_bars(std::span<const BarLine> lines, std::vector<Steel> steels,
               std::vector<BondLaw> bond_laws, double element_length)
{
  if (!finite_positive(element_length))
    impl::out_of_range("bar element length", element_length, "> 0 m");
  for (std::size_t k = 0; k < steels.size(); ++k)
    steels[k].validate();
  for (std::size_t k = 0; k < bond_laws.size(); ++k)
    bond_laws[k].validate();
  Bars bars;
  bars.steels = std::move(steels);
  bars.bond_laws = std::move(bond_laws);
  for (std::size_t q = 0; q < lines.size(); ++q)
  {
    const BarLine& line = lines[q];
    const std::string name = "bar " + std::to_string(q);
    if (line.points.size() < 2)
      throw std::runtime_error(name + ": " + std::to_string(line.points.size())
                               + " points given, a bar needs at least 2");
    if (!finite_positive(line.diameter))
      impl::out_of_range(name + " diameter", line.diameter, "> 0 m");
    if (line.steel >= bars.steels.size())
      impl::out_of_range(name + " steel index", line.steel, "< the number of steels, " + std::to_string(bars.steels.size()));
    if (line.bond >= bars.bond_laws.size())
      impl::out_of_range(name + " bond law index", line.bond,
             "< the number of bond laws, " + std::to_string(bars.bond_laws.size()));
    const Steel& st = bars.steels[line.steel];
    const double area = std::numbers::pi * line.diameter * line.diameter / 4.0;
    auto add_node = [&](const std::array<double, 3>& x)
    {
      for (int k = 0; k < 3; ++k)
      {
        bars.x.push_back(x[k]);
        bars.x0.push_back(x[k]);
        bars.v.push_back(0.0);
        bars.f.push_back(0.0);
      }
      bars.m.push_back(0.0);
      bars.held.push_back(0);
      bars.node_radius.push_back(0.5 * line.diameter);
      bars.node_k.push_back(st.youngs_modulus * std::numbers::pi * 0.5 * line.diameter);
      return static_cast<std::int32_t>(bars.m.size() - 1);
    };
    std::int32_t prev = add_node(line.points[0]);
    const double EI = st.youngs_modulus * std::numbers::pi * std::pow(line.diameter, 4) / 64.0;
    for (std::size_t s = 1; s < line.points.size(); ++s)
    {
      const std::size_t first_element = bars.elements();
      const auto& p0 = line.points[s - 1];
      const auto& p1 = line.points[s];
      const double d[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
      const double len = std::sqrt(dot(d, d));
      if (!finite_positive(len))
        impl::out_of_range(name + " segment " + std::to_string(s - 1) + " length", len, "> 0 m (distinct points)");
      const int n = static_cast<int>(std::ceil(len / element_length - 1e-9));
      for (int e = 1; e <= n; ++e)
      {
        const double t = static_cast<double>(e) / n;
        const std::int32_t next = add_node({p0[0] + t * d[0], p0[1] + t * d[1], p0[2] + t * d[2]});
        const double l = len / n;
        bars.a.push_back(prev);
        bars.b.push_back(next);
        bars.line.push_back(static_cast<std::int32_t>(q));
        bars.area.push_back(area);
        bars.l0.push_back(l);
        bars.plastic.push_back(0.0);
        bars.alpha.push_back(0.0);
        bars.force.push_back(0.0);
        bars.length.push_back(l);
        bars.steel.push_back(line.steel);
        bars.bond_law.push_back(line.bond);
        bars.broken.push_back(0);
        bars.m[prev] += 0.5 * st.density * area * l;
        bars.m[next] += 0.5 * st.density * area * l;
        prev = next;
      }
      // bending springs inside this straight run (a corner of the polyline
      // is a hinge: the springs' energy assumes a straight rest shape)
      for (std::size_t e = first_element + 1; e < bars.elements(); ++e)
      {
        bars.bend_a.push_back(bars.a[e - 1]);
        bars.bend_b.push_back(bars.b[e - 1]);
        bars.bend_c.push_back(bars.b[e]);
        bars.bend_e1.push_back(static_cast<std::int32_t>(e - 1));
        bars.bend_e2.push_back(static_cast<std::int32_t>(e));
        bars.bend_k.push_back(EI / (0.5 * (bars.l0[e - 1] + bars.l0[e])));
        bars.bend_kept.push_back(1);
      }
    }
  }
  // bars apart: no two elements of different bars closer than their radii
  const std::size_t ne = bars.elements();
  for (std::size_t e = 0; e < ne; ++e)
    for (std::size_t g = e + 1; g < ne; ++g)
    {
      if (bars.line[e] == bars.line[g] || boxes_apart(bars, e, g))
        continue;
      // sample the closer segment pair: the distance between two segments
      // is reached at an end of one of them or inside both; check the ends
      // against the other and the midpoints (elements are short)
      const double ra = std::sqrt(bars.area[e] / std::numbers::pi), rb = std::sqrt(bars.area[g] / std::numbers::pi);
      double best = std::numeric_limits<double>::infinity();
      for (int k = 0; k <= 8; ++k)
      {
        const double t = k / 8.0;
        double pe[3], pg[3];
        for (int c = 0; c < 3; ++c)
        {
          pe[c] = (1 - t) * bars.x[3 * bars.a[e] + c] + t * bars.x[3 * bars.b[e] + c];
          pg[c] = (1 - t) * bars.x[3 * bars.a[g] + c] + t * bars.x[3 * bars.b[g] + c];
        }
        best = std::min({best, distance_to_element(bars, g, pe)[0], distance_to_element(bars, e, pg)[0]});
      }
      if (best < ra + rb)
      {
        std::ostringstream s;
        s << "bars " << bars.line[e] << " and " << bars.line[g] << " overlap: their axes come within "
          << best << " m, less than the sum of their radii " << ra + rb << " m";
        throw std::runtime_error(s.str());
      }
    }
  return bars;
}


std::size_t create_bonds(Bars& bars, const Particles& p, double reach)
{
  if (!(reach >= 0.0) || !std::isfinite(reach))
    impl::out_of_range("bond reach", reach, ">= 0 m");
  std::vector<std::size_t> per_element(bars.elements(), 0);
  const std::size_t first = bars.bonds();
  double rmax = 0.0;
  for (double r : p.r)
    rmax = std::max(rmax, r);
  const ElementGrid grid = element_grid(bars, rmax + max_bar_radius(bars) + reach);
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    const auto [e, xi, d] = nearest_element(bars, grid, &p.x[3 * i], [&](std::size_t el)
                                            { return p.r[i] + bar_radius(bars, el) + reach; });
    if (e < 0)
      continue;
    const double* pa = &bars.x[3 * bars.a[e]];
    const double* pb = &bars.x[3 * bars.b[e]];
    double t[3], a[3];
    for (int k = 0; k < 3; ++k)
    {
      t[k] = (pb[k] - pa[k]) / bars.l0[e];
      a[k] = p.x[3 * i + k] - ((1 - xi) * pa[k] + xi * pb[k]);
    }
    const double axial = dot(a, t);
    bars.sphere.push_back(static_cast<std::int32_t>(i));
    bars.element.push_back(static_cast<std::int32_t>(e));
    bars.xi.push_back(xi);
    bars.surface.push_back(0.0);
    bars.axial0.push_back(axial);
    bars.radial0.push_back(std::sqrt(std::max(dot(a, a) - axial * axial, 0.0)));
    bars.tau.push_back(0.0);
    bars.slip.push_back(0.0);
    bars.slip_max.push_back(0.0);
    bars.gap.push_back(0.0);
    bars.gap_max.push_back(0.0);
    bars.open.push_back(0);
    ++per_element[e];
  }
  for (std::size_t k = first; k < bars.bonds(); ++k)
  {
    const std::size_t e = bars.element[k];
    bars.surface[k] = 2.0 * std::numbers::pi * bar_radius(bars, e) * bars.l0[e] / per_element[e];
  }
  return bars.bonds() - first;
}

namespace
{
/// The kinematics of bond k: the unit axis t, the offset a of the sphere's
/// centre from the bond's point on the axis, its axial part a . t, its
/// radial part a_perp (length rho, direction e), and the element's length.
struct BondGeometry
{
  double t[3], a_perp[3], e[3];
  double axial, rho, length;
};
BondGeometry bond_geometry(const Bars& bars, const Particles& p, std::size_t k)
{
  BondGeometry g{};
  const std::size_t el = bars.element[k];
  const double* pa = &bars.x[3 * bars.a[el]];
  const double* pb = &bars.x[3 * bars.b[el]];
  const double* c = &p.x[3 * bars.sphere[k]];
  const double xi = bars.xi[k];
  double d[3], a[3];
  for (int q = 0; q < 3; ++q)
  {
    d[q] = pb[q] - pa[q];
    a[q] = c[q] - ((1 - xi) * pa[q] + xi * pb[q]);
  }
  g.length = std::sqrt(dot(d, d));
  if (!(g.length > 0.0)) // the element's ends meet: no axis (the bond then acts radially from P)
  {
    g.length = 1.0;
    std::fill(std::begin(d), std::end(d), 0.0);
  }
  for (int q = 0; q < 3; ++q)
    g.t[q] = d[q] / g.length;
  g.axial = dot(a, g.t);
  for (int q = 0; q < 3; ++q)
    g.a_perp[q] = a[q] - g.axial * g.t[q];
  g.rho = std::sqrt(dot(g.a_perp, g.a_perp));
  for (int q = 0; q < 3; ++q)
    g.e[q] = g.rho > 0.0 ? g.a_perp[q] / g.rho : 0.0;
  return g;
}

/// Element e's axial force from the positions; with advance, its history
/// moves on (and a rupture releases its energy into `broken`). Returns
/// true when it breaks in this call.
bool element_force(Bars& bars, std::size_t e, bool advance, double& broken)
{
  if (bars.broken[e])
    return false;
  const std::int32_t ia = bars.a[e], ib = bars.b[e];
  double d[3];
  for (int q = 0; q < 3; ++q)
    d[q] = bars.x[3 * ib + q] - bars.x[3 * ia + q];
  const double L = std::sqrt(dot(d, d));
  if (!(L > 1e-12 * bars.l0[e])) // its ends meet: no direction (and no rupture in compression)
    return false;
  const Steel& st = bars.steels[bars.steel[e]];
  const SteelState s = steel_update(L / bars.l0[e] - 1.0, bars.plastic[e], bars.alpha[e], st);
  if (s.broken && advance)
  {
    // what it stored at the step's start plus its force's work over the
    // step, trapezoidal with zero at the end (as the kicks apply it)
    const double n_old = bars.force[e], sig = n_old / bars.area[e];
    broken += sig * sig / (2.0 * st.youngs_modulus) * bars.area[e] * bars.l0[e]
              + 0.5 * n_old * (L - bars.length[e]);
    bars.broken[e] = 1;
    bars.force[e] = 0.0;
    return true;
  }
  const double N = s.broken ? 0.0 : s.stress * bars.area[e];
  if (advance)
  {
    bars.plastic[e] = s.plastic;
    bars.alpha[e] = s.alpha;
  }
  bars.force[e] = N;
  bars.length[e] = L;
  // tension pulls the ends together
  for (int q = 0; q < 3; ++q)
  {
    bars.f[3 * ia + q] += N * d[q] / L;
    bars.f[3 * ib + q] -= N * d[q] / L;
  }
  return false;
}

/// Bond k's forces on its sphere and the element's nodes: the gradients of
/// the bond's energy in the slip s = a . t - axial0 and the opening
/// g = rho - radial0, both unchanged by a rigid motion, so the forces sum to
/// zero with zero moment. With advance, the history moves on.
void bond_force(Bars& bars, Particles& p, std::size_t k, bool advance, bool gone, BarWork& w)
{
  if (bars.open[k])
    return;
  const BondLaw& law = bars.bond_laws[bars.bond_law[bars.element[k]]];
  const BondGeometry g = bond_geometry(bars, p, k);
  const double slip = g.axial - bars.axial0[k], gap = g.rho - bars.radial0[k];
  const double S = bars.surface[k];
  const LinkLaw radial = radial_law(law, S);
  const NormalForce nf = link_normal_force(gap, bars.gap_max[k], radial);
  if (advance && (gone || nf.state == NormalState::broken || bars.broken[bars.element[k]]))
  {
    // what the bond stored at the step's start plus its forces' work over
    // the step, trapezoidal with zero at the end
    const double t0 = bars.tau[k], g0 = bars.gap[k];
    const double f0 = link_normal_force(g0, bars.gap_max[k], radial).fn;
    w.broken += S * (t0 * t0 / (2.0 * law.k0()) + 0.5 * t0 * (slip - bars.slip[k])) + 0.5 * f0 * gap;
    bars.open[k] = 1;
    w.changed = true;
    bars.tau[k] = 0.0;
    return;
  }
  double tau = bars.tau[k];
  if (advance)
  {
    const auto [t_new, smax, diss] = bond_shear(bars.tau[k], bars.slip[k], slip, bars.slip_max[k], law);
    tau = t_new;
    w.slip += S * diss;
    bars.tau[k] = tau;
    bars.slip[k] = slip;
    bars.slip_max[k] = smax;
    bars.gap[k] = gap;
    bars.gap_max[k] = nf.delta_max;
  }
  const double Qs = tau * S, Qg = nf.fn, xi = bars.xi[k];
  const std::size_t el = bars.element[k];
  double* fc = &p.f[3 * bars.sphere[k]];
  double* fa = &bars.f[3 * bars.a[el]];
  double* fb = &bars.f[3 * bars.b[el]];
  for (int q = 0; q < 3; ++q)
  {
    const double lever_s = g.a_perp[q] / g.length, lever_g = g.axial * g.e[q] / g.length;
    fc[q] -= Qs * g.t[q] + Qg * g.e[q];
    fa[q] += Qs * ((1 - xi) * g.t[q] + lever_s) + Qg * ((1 - xi) * g.e[q] - lever_g);
    fb[q] += Qs * (xi * g.t[q] - lever_s) + Qg * (xi * g.e[q] + lever_g);
  }
}
} // namespace

namespace
{
/// Unit directions t1 (a -> b), t2 (b -> c) of bending spring k and the
/// element lengths, whatever its elements' state; false if an element's
/// ends meet (no angle).
bool bend_directions(const Bars& bars, std::size_t k, double* t1, double* t2, double& l1, double& l2)
{
  const double* xa = &bars.x[3 * bars.bend_a[k]];
  const double* xb = &bars.x[3 * bars.bend_b[k]];
  const double* xc = &bars.x[3 * bars.bend_c[k]];
  for (int q = 0; q < 3; ++q)
  {
    t1[q] = xb[q] - xa[q];
    t2[q] = xc[q] - xb[q];
  }
  l1 = std::sqrt(dot(t1, t1));
  l2 = std::sqrt(dot(t2, t2));
  if (!(l1 > 0.0 && l2 > 0.0)) // an element's ends meet: no angle
    return false;
  for (int q = 0; q < 3; ++q)
  {
    t1[q] /= l1;
    t2[q] /= l2;
  }
  return true;
}

/// The same for a spring that acts: false if one of its elements broke.
bool bend_geometry(const Bars& bars, std::size_t k, double* t1, double* t2, double& l1, double& l2)
{
  return !bars.broken[bars.bend_e1[k]] && !bars.broken[bars.bend_e2[k]] && bend_directions(bars, k, t1, t2, l1, l2);
}

/// A bending spring one of whose elements broke in this step releases what
/// it stored, k (1 - t1 . t2) at the step's end (bend_kept marks the
/// springs still counted). Called after the elements' rupture.
void release_bending(Bars& bars, double& broken)
{
  for (std::size_t k = 0; k < bars.bend_k.size(); ++k)
  {
    if (!bars.bend_kept[k] || !(bars.broken[bars.bend_e1[k]] || bars.broken[bars.bend_e2[k]]))
      continue;
    bars.bend_kept[k] = 0;
    double t1[3], t2[3], l1, l2;
    if (bend_directions(bars, k, t1, t2, l1, l2))
      broken += bars.bend_k[k] * (1.0 - dot(t1, t2));
  }
}

/// The bending spring's forces, -grad of k (1 - c), c = t1 . t2:
/// dc/dx_a = -(t2 - c t1) / l1, dc/dx_c = (t1 - c t2) / l2, dc/dx_b the
/// negative of their sum.
void bend_force(Bars& bars, std::size_t k)
{
  double t1[3], t2[3], l1, l2;
  if (!bend_geometry(bars, k, t1, t2, l1, l2))
    return;
  const double c = dot(t1, t2), kb = bars.bend_k[k];
  double* fa = &bars.f[3 * bars.bend_a[k]];
  double* fb = &bars.f[3 * bars.bend_b[k]];
  double* fc = &bars.f[3 * bars.bend_c[k]];
  for (int q = 0; q < 3; ++q)
  {
    const double ga = -(t2[q] - c * t1[q]) / l1, gc = (t1[q] - c * t2[q]) / l2;
    fa[q] += kb * ga;
    fc[q] += kb * gc;
    fb[q] -= kb * (ga + gc);
  }
}
} // namespace

BarWork bar_forces(Bars& bars, Particles& p, bool advance, std::span<const std::uint8_t> gone)
{
  BarWork w;
  std::fill(bars.f.begin(), bars.f.end(), 0.0);
  bool any_broke = false;
  for (std::size_t e = 0; e < bars.elements(); ++e)
    any_broke = element_force(bars, e, advance, w.broken) || any_broke;
  if (any_broke)
    release_bending(bars, w.broken);
  w.changed = any_broke;
  for (std::size_t k = 0; k < bars.bend_k.size(); ++k)
    bend_force(bars, k);
  for (std::size_t k = 0; k < bars.bonds(); ++k)
    bond_force(bars, p, k, advance, !gone.empty() && gone[bars.sphere[k]], w);
  return w;
}

BarEnergy bar_energy(const Bars& bars, const Particles& p)
{
  BarEnergy en;
  for (std::size_t n = 0; n < bars.nodes(); ++n)
    en.kinetic += 0.5 * bars.m[n] * dot(&bars.v[3 * n], &bars.v[3 * n]);
  for (std::size_t e = 0; e < bars.elements(); ++e)
  {
    const Steel& st = bars.steels[bars.steel[e]];
    const double vol = bars.area[e] * bars.l0[e];
    en.plastic += vol * steel_plastic_work(bars.alpha[e], st);
    if (!bars.broken[e])
    {
      const double sig = bars.force[e] / bars.area[e];
      en.elastic += vol * sig * sig / (2.0 * st.youngs_modulus);
    }
  }
  for (std::size_t k = 0; k < bars.bend_k.size(); ++k)
  {
    double t1[3], t2[3], l1, l2;
    if (bend_geometry(bars, k, t1, t2, l1, l2))
      en.elastic += bars.bend_k[k] * (1.0 - dot(t1, t2));
  }
  for (std::size_t k = 0; k < bars.bonds(); ++k)
  {
    const BondLaw& law = bars.bond_laws[bars.bond_law[bars.element[k]]];
    const LinkLaw radial = radial_law(law, bars.surface[k]);
    en.opening += softening_dissipation(bars.gap_max[k], radial);
    if (bars.open[k])
      continue;
    const double gap = bond_geometry(bars, p, k).rho - bars.radial0[k];
    en.elastic += bars.surface[k] * bars.tau[k] * bars.tau[k] / (2.0 * law.k0())
                  + 0.5 * link_normal_force(gap, bars.gap_max[k], radial).fn * gap;
  }
  return en;
}

void bar_body_forces(Bars& bars, RigidBody& b)
{
  for (std::size_t n = 0; n < bars.nodes(); ++n)
  {
    const std::array<double, 3> x{bars.x[3 * n], bars.x[3 * n + 1], bars.x[3 * n + 2]};
    const Distance D = signed_distance(b.shape, b.to_body(x));
    const double delta = bars.node_radius[n] - D.d;
    if (!(delta > 0.0))
      continue;
    const std::array<double, 3> nb = b.to_world({D.n[0], D.n[1], D.n[2]}), o = b.to_world({0.0, 0.0, 0.0});
    const double F = bars.node_k[n] * delta;
    double f[3], r[3];
    for (int k = 0; k < 3; ++k)
    {
      f[k] = F * (nb[k] - o[k]); // the normal turned to the world
      bars.f[3 * n + k] += f[k];
      b.f[k] -= f[k];
      r[k] = x[k] - bars.node_radius[n] * (nb[k] - o[k]) - b.x[k]; // the contact point from the centre of mass
    }
    b.t[0] -= r[1] * f[2] - r[2] * f[1];
    b.t[1] -= r[2] * f[0] - r[0] * f[2];
    b.t[2] -= r[0] * f[1] - r[1] * f[0];
  }
}

double bar_body_energy(const Bars& bars, const RigidBody& b)
{
  double e = 0.0;
  for (std::size_t n = 0; n < bars.nodes(); ++n)
  {
    const Distance D = signed_distance(b.shape, b.to_body({bars.x[3 * n], bars.x[3 * n + 1], bars.x[3 * n + 2]}));
    const double delta = std::max(0.0, bars.node_radius[n] - D.d);
    e += 0.5 * bars.node_k[n] * delta * delta;
  }
  return e;
}

void add_bar_rows(const Bars& bars, const Particles& p, const Material& m, std::vector<double>& sphere_rows,
                  std::vector<double>& node_rows)
{
  // Gershgorin on M^-1/2 K M^-1/2: row i sums |K_ij| / sqrt(m_i m_j). An
  // element couples its two nodes with EA/l0; a bond its sphere C and its
  // point (1 - xi) A + xi B with k = max(K0 S, k_r S, K_contact), the
  // contact with the bar (BarContacts) taking over once the bond opens.
  node_rows.assign(bars.nodes(), 0.0);
  for (std::size_t n = 0; n < bars.nodes(); ++n)
    node_rows[n] += bars.node_k[n] / bars.m[n]; // a body's contact (its mass far above)
  for (std::size_t e = 0; e < bars.elements(); ++e)
  {
    if (bars.broken[e])
      continue;
    const double k = bars.steels[bars.steel[e]].youngs_modulus * bars.area[e] / bars.l0[e];
    const double ma = bars.m[bars.a[e]], mb = bars.m[bars.b[e]];
    node_rows[bars.a[e]] += k / ma + k / std::sqrt(ma * mb);
    node_rows[bars.b[e]] += k / mb + k / std::sqrt(ma * mb);
  }
  // a bending spring, linearised: k (theta^2 / 2) with theta the lateral
  // offset of b against a and c, coefficients (1/l1, -(1/l1 + 1/l2), 1/l2)
  for (std::size_t k = 0; k < bars.bend_k.size(); ++k)
  {
    if (bars.broken[bars.bend_e1[k]] || bars.broken[bars.bend_e2[k]])
      continue;
    const double g[3] = {1.0 / bars.l0[bars.bend_e1[k]],
                         -(1.0 / bars.l0[bars.bend_e1[k]] + 1.0 / bars.l0[bars.bend_e2[k]]),
                         1.0 / bars.l0[bars.bend_e2[k]]};
    const std::int32_t nd[3] = {bars.bend_a[k], bars.bend_b[k], bars.bend_c[k]};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        node_rows[nd[i]] += bars.bend_k[k] * std::abs(g[i] * g[j]) / std::sqrt(bars.m[nd[i]] * bars.m[nd[j]]);
  }
  for (std::size_t b = 0; b < bars.bonds(); ++b)
  {
    if (bars.open[b])
      continue;
    const BondLaw& law = bars.bond_laws[bars.bond_law[bars.element[b]]];
    const std::size_t e = bars.element[b], c = bars.sphere[b];
    const double k = std::max(std::max(law.k0(), law.radial_stiffness) * bars.surface[b],
                              body_contact_stiffness(m, p.r[c]));
    // the node factors of the bond's forces, their lever terms included
    // (the offset from the axis and along it, over the element's length)
    const BondGeometry g = bond_geometry(bars, p, b);
    const double lever = (g.rho + std::abs(g.axial)) / g.length;
    const double w[2] = {1.0 - bars.xi[b] + lever, bars.xi[b] + lever};
    const std::int32_t nd[2] = {bars.a[e], bars.b[e]};
    const double mc = p.m[c];
    sphere_rows[c] += k / mc;
    for (int q = 0; q < 2; ++q)
    {
      const double mq = bars.m[nd[q]];
      sphere_rows[c] += w[q] * k / std::sqrt(mc * mq);
      node_rows[nd[q]] += w[q] * k / std::sqrt(mq * mc)
                          + w[q] * (w[0] * k / std::sqrt(mq * bars.m[nd[0]]) + w[1] * k / std::sqrt(mq * bars.m[nd[1]]));
    }
  }
}

} // namespace dembridge::dem
