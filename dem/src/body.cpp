// Rigid bodies: shapes as signed distances, mass properties, the contact law
// between spheres and bodies (body.h; docs/method.md section 1.7b).
#include "dembridge/dem/body.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "force_loop.h"

namespace dembridge::dem
{
namespace
{
using V3 = std::array<double, 3>;
using impl::cross3;
using impl::dot3;

/// A 2D signed distance in the meridian plane (a along the axis, r >= 0 the
/// distance from it) and its gradient.
struct D2
{
  double d, ga, gr;
};

/// The box |a - ac| <= ha, |r| <= hr (Quilez's exact box distance).
D2 box2(double a, double r, double ac, double ha, double hr)
{
  const double sa = a >= ac ? 1.0 : -1.0;
  const double qa = std::abs(a - ac) - ha, qr = r - hr;
  if (qa > 0.0 || qr > 0.0)
  {
    const double ma = std::max(qa, 0.0), mr = std::max(qr, 0.0), len = std::hypot(ma, mr);
    return {len, sa * ma / len, mr / len};
  }
  return qa > qr ? D2{qa, sa, 0.0} : D2{qr, 0.0, 1.0};
}

/// The disc of centre (ac, 0) and radius R.
D2 disc2(double a, double r, double ac, double R)
{
  const double len = std::hypot(a - ac, r);
  if (len == 0.0)
    return {-R, 1.0, 0.0};
  return {len - R, (a - ac) / len, r / len};
}

/// The lens (vesica) of two discs of radius s whose centres lie at r = +-c
/// on the line a = ac, with tips at a = ac +- b, b = sqrt(s^2 - c^2)
/// (Quilez's exact vesica distance, the lens's axis along a).
D2 lens2(double a, double r, double ac, double s, double c)
{
  const double b = std::sqrt(s * s - c * c);
  const double sa = a >= ac ? 1.0 : -1.0;
  const double py = std::abs(a - ac), px = r;
  if ((py - b) * c > px * b)
  {
    // nearest to the tip
    const double len = std::hypot(px, py - b);
    if (len == 0.0)
      return {0.0, sa, 0.0};
    return {len, sa * (py - b) / len, px / len};
  }
  // nearest to the arc of the disc centred on the other side (-c)
  const double len = std::hypot(px + c, py);
  return {len - s, sa * py / len, (px + c) / len};
}

/// The convex polygon with vertices v (counter-clockwise, in (a, r)),
/// exact: the distance to the nearest edge, negative inside.
D2 polygon2(double a, double r, const std::vector<std::array<double, 2>>& v)
{
  double best = 1e300, ga = 0.0, gr = 0.0;
  bool inside = true;
  for (std::size_t k = 0; k < v.size(); ++k)
  {
    const auto& p = v[k];
    const auto& q = v[(k + 1) % v.size()];
    const double ea = q[0] - p[0], er = q[1] - p[1], wa = a - p[0], wr = r - p[1];
    const double t = std::clamp((wa * ea + wr * er) / (ea * ea + er * er), 0.0, 1.0);
    const double da = wa - t * ea, dr = wr - t * er, len = std::hypot(da, dr);
    if (len < best)
    {
      best = len;
      if (len > 0.0)
      {
        ga = da / len;
        gr = dr / len;
      }
      else
      {
        const double el = std::hypot(ea, er); // on the edge: its outward normal
        ga = er / el;
        gr = -ea / el;
      }
    }
    if (ea * wr - er * wa < 0.0) // right of a counter-clockwise edge: outside
      inside = false;
  }
  return inside ? D2{-best, -ga, -gr} : D2{best, ga, gr};
}

/// The union of two shapes: the nearer surface (exact outside, and inside
/// near the outer surface).
D2 unite(const D2& x, const D2& y) { return x.d <= y.d ? x : y; }

/// The projectile's meridian section: tip at a = 0, nose base at a = -Ln,
/// tail at a = -length; r = distance from the axis.
D2 projectile2(const Shape& s, double a, double r)
{
  const double R = 0.5 * s.diameter, Ln = s.nose_length(), a1 = -Ln, a0 = -s.length;
  switch (s.nose)
  {
  case Nose::flat:
    return box2(a, r, 0.5 * a0, -0.5 * a0, R);
  case Nose::hemispherical:
    return unite(box2(a, r, 0.5 * (a0 + a1), 0.5 * (a1 - a0), R), disc2(a, r, a1, R));
  case Nose::conical:
    return polygon2(a, r, {{a0, -R}, {a1, -R}, {0.0, 0.0}, {a1, R}, {a0, R}});
  case Nose::ogive:
  {
    const double arc = s.crh * s.diameter;
    return unite(box2(a, r, 0.5 * (a0 + a1), 0.5 * (a1 - a0), R), lens2(a, r, a1, arc, arc - R));
  }
  }
  throw std::logic_error("projectile2: unknown nose");
}

/// Radius of the projectile's section at a (a in [-length, 0]).
double radius_at(const Shape& s, double a)
{
  const double R = 0.5 * s.diameter, Ln = s.nose_length(), a1 = -Ln;
  if (a <= a1)
    return R;
  const double x = a - a1; // into the nose
  switch (s.nose)
  {
  case Nose::flat:
    return R;
  case Nose::hemispherical:
    return std::sqrt(std::max(0.0, R * R - x * x));
  case Nose::conical:
    return R * (1.0 - x / Ln);
  case Nose::ogive:
  {
    const double arc = s.crh * s.diameter;
    return std::max(0.0, std::sqrt(arc * arc - x * x) - (arc - R));
  }
  }
  return R;
}

V3 mat_vec(const std::array<double, 9>& M, const V3& x)
{
  return {M[0] * x[0] + M[1] * x[1] + M[2] * x[2], M[3] * x[0] + M[4] * x[1] + M[5] * x[2],
          M[6] * x[0] + M[7] * x[1] + M[8] * x[2]};
}
V3 mat_t_vec(const std::array<double, 9>& M, const V3& x)
{
  return {M[0] * x[0] + M[3] * x[1] + M[6] * x[2], M[1] * x[0] + M[4] * x[1] + M[7] * x[2],
          M[2] * x[0] + M[5] * x[1] + M[8] * x[2]};
}
} // namespace

// ---- Shape -----------------------------------------------------------------------

SurfaceMesh body_surface(const Shape& s, int rings, int segments)
{
  if (s.kind != Shape::Kind::projectile)
    throw std::runtime_error("body_surface: only a projectile has a surface mesh");
  if (rings < 1 || segments < 3)
    throw std::runtime_error("body_surface: rings >= 1 and segments >= 3");
  // the sections along the axis, tip (a = 0) to tail (a = -length)
  const double Ln = s.nose_length();
  std::vector<double> a;
  if (Ln > 0.0)
    for (int k = 0; k <= rings; ++k)
      a.push_back(-Ln * k / rings);
  else
    a.push_back(0.0);
  a.push_back(-s.length);
  SurfaceMesh m;
  auto vertex = [&](double ax, double r, double phi)
  {
    m.x.insert(m.x.end(), {ax, r * std::cos(phi), r * std::sin(phi)});
    return static_cast<std::int32_t>(m.vertices() - 1);
  };
  auto tri = [&](std::int32_t i, std::int32_t j, std::int32_t k) { m.triangles.insert(m.triangles.end(), {i, j, k}); };
  const std::int32_t tip = vertex(0.0, 0.0, 0.0), n = segments;
  std::vector<std::int32_t> prev(n, tip);
  for (double ak : a)
  {
    const double r = radius_at(s, ak);
    if (r <= 0.0)
      continue; // the tip's section is the tip itself
    std::vector<std::int32_t> ring(n);
    for (int j = 0; j < n; ++j)
      ring[j] = vertex(ak, r, 2.0 * std::numbers::pi * j / n);
    for (int j = 0; j < n; ++j)
    {
      const int j1 = (j + 1) % n;
      // counter-clockwise seen from outside (towards the tip is +x)
      if (prev[j] == prev[j1]) // a fan round a point
        tri(prev[j], ring[j], ring[j1]);
      else
      {
        tri(prev[j], ring[j1], prev[j1]);
        tri(prev[j], ring[j], ring[j1]);
      }
    }
    prev = ring;
  }
  const std::int32_t tail = vertex(-s.length, 0.0, 0.0);
  for (int j = 0; j < n; ++j)
    tri(prev[j], tail, prev[(j + 1) % n]);
  return m;
}

double Shape::nose_length() const
{
  const double R = 0.5 * diameter;
  switch (nose)
  {
  case Nose::flat:
    return 0.0;
  case Nose::hemispherical:
    return R;
  case Nose::conical:
    return R / std::tan(cone_angle_deg * std::numbers::pi / 180.0);
  case Nose::ogive:
    return diameter * std::sqrt(crh - 0.25);
  }
  return 0.0;
}

void Shape::validate() const
{
  auto bad = [](const std::string& what) { throw std::runtime_error("body shape: " + what); };
  if (kind == Kind::projectile)
  {
    if (!(diameter > 0.0) || !std::isfinite(diameter))
      bad("diameter " + std::to_string(diameter) + " m: must be > 0");
    if (nose == Nose::ogive && !(crh >= 0.5 && std::isfinite(crh)))
      bad("ogive CRH " + std::to_string(crh) + ": must be >= 0.5");
    if (nose == Nose::conical && !(cone_angle_deg > 0.0 && cone_angle_deg < 90.0))
      bad("cone half-angle " + std::to_string(cone_angle_deg) + " degree: must be in (0, 90)");
    // the hemisphere's disc and the ogive's lens reach behind the nose base
    // by R and by the nose length: the shank must cover that
    const double reach = nose == Nose::hemispherical ? 2.0 * nose_length()
                         : nose == Nose::ogive       ? 2.0 * nose_length()
                                                     : nose_length();
    if (!(length > reach) || !std::isfinite(length))
      bad("length " + std::to_string(length) + " m: must exceed " + std::to_string(reach) + " m ("
          + (nose == Nose::ogive || nose == Nose::hemispherical ? "twice the nose length" : "the nose length")
          + " of this nose)");
  }
  else if (kind == Kind::plane)
  {
    if (!(std::hypot(normal[0], normal[1], normal[2]) > 0.0))
      bad("a plane's normal must not be zero");
  }
  else
    for (int k = 0; k < 3; ++k)
      if (!(hi[k] > lo[k]))
        bad("a box's hi must exceed its lo on every axis");
}

double Shape::volume() const
{
  // the shank exactly, the nose by Simpson's rule on r(a)^2
  const double R = 0.5 * diameter, Ln = nose_length();
  double v = std::numbers::pi * R * R * (length - Ln);
  const int n = 4000;
  const double h = Ln / n;
  double s = 0.0;
  for (int k = 0; k <= n; ++k)
  {
    const double r = radius_at(*this, -Ln + k * h);
    s += (k == 0 || k == n ? 1.0 : (k % 2 ? 4.0 : 2.0)) * r * r;
  }
  return v + std::numbers::pi * s * h / 3.0;
}

Distance signed_distance(const Shape& s, const std::array<double, 3>& x)
{
  if (s.kind == Shape::Kind::plane)
  {
    const double len = std::hypot(s.normal[0], s.normal[1], s.normal[2]);
    const V3 n{s.normal[0] / len, s.normal[1] / len, s.normal[2] / len};
    return {n[0] * (x[0] - s.point[0]) + n[1] * (x[1] - s.point[1]) + n[2] * (x[2] - s.point[2]), n};
  }
  if (s.kind == Shape::Kind::box)
  {
    // exact box distance, its gradient from the nearest face or edge
    V3 q, c, sg;
    for (int k = 0; k < 3; ++k)
    {
      c[k] = 0.5 * (s.lo[k] + s.hi[k]);
      sg[k] = x[k] >= c[k] ? 1.0 : -1.0;
      q[k] = std::abs(x[k] - c[k]) - 0.5 * (s.hi[k] - s.lo[k]);
    }
    const V3 m{std::max(q[0], 0.0), std::max(q[1], 0.0), std::max(q[2], 0.0)};
    const double len = std::hypot(m[0], m[1], m[2]);
    if (len > 0.0)
      return {len, {sg[0] * m[0] / len, sg[1] * m[1] / len, sg[2] * m[2] / len}};
    const int k = static_cast<int>(std::max_element(q.begin(), q.end()) - q.begin());
    V3 n{0, 0, 0};
    n[k] = sg[k];
    return {q[k], n};
  }
  const double r = std::hypot(x[1], x[2]);
  const D2 d = projectile2(s, x[0], r);
  const double ey = r > 0.0 ? x[1] / r : 1.0, ez = r > 0.0 ? x[2] / r : 0.0;
  return {d.d, {d.ga, d.gr * ey, d.gr * ez}};
}
} // namespace dembridge::dem

namespace dembridge::dem
{
namespace
{
using V3 = std::array<double, 3>;

/// Mass properties of a projectile of density rho, by Simpson's rule along
/// the axis: mass, centre of mass (on the axis, a < 0), and the principal
/// moments about the centre: axial int rho pi r^4 / 2 da, transverse
/// int rho pi r^2 (r^2 / 4 + (a - a_c)^2) da.
struct MassProperties
{
  double mass, ac, Ia, It;
};

MassProperties mass_properties(const Shape& s, double rho)
{
  auto integrate = [&](auto&& g)
  {
    // [-length, -Ln] and [-Ln, 0] separately: r(a) is smooth on each
    const double Ln = s.nose_length();
    double total = 0.0;
    for (auto [lo, hi] : {std::pair{-s.length, -Ln}, std::pair{-Ln, 0.0}})
    {
      if (!(hi > lo))
        continue;
      const int n = 4000;
      const double h = (hi - lo) / n;
      double sum = 0.0;
      for (int k = 0; k <= n; ++k)
      {
        const double a = lo + k * h;
        sum += (k == 0 || k == n ? 1.0 : (k % 2 ? 4.0 : 2.0)) * g(a, radius_at(s, a));
      }
      total += sum * h / 3.0;
    }
    return total;
  };
  constexpr double pi = std::numbers::pi;
  const double m = rho * integrate([](double, double r) { return pi * r * r; });
  const double ac = rho * integrate([](double a, double r) { return a * pi * r * r; }) / m;
  const double Ia = rho * integrate([](double, double r) { return 0.5 * pi * r * r * r * r; });
  const double It = rho * integrate([&](double a, double r) { return pi * r * r * (0.25 * r * r + (a - ac) * (a - ac)); });
  return {m, ac, Ia, It};
}
} // namespace

std::array<double, 3> RigidBody::omega() const
{
  if (fixed)
    return {0, 0, 0};
  const V3 Lb = mat_t_vec(R, L);
  const V3 wb{Lb[0] / inertia[0], Lb[1] / inertia[1], Lb[2] / inertia[2]};
  return mat_vec(R, wb);
}

double RigidBody::kinetic_energy() const
{
  if (fixed)
    return 0.0;
  const V3 w = omega();
  return 0.5 * mass * dot3(v.data(), v.data()) + 0.5 * dot3(w.data(), L.data());
}

std::array<double, 3> RigidBody::to_world(const std::array<double, 3>& q) const
{
  const V3 d{q[0] - centre[0], q[1] - centre[1], q[2] - centre[2]};
  const V3 w = mat_vec(R, d);
  return {x[0] + w[0], x[1] + w[1], x[2] + w[2]};
}

std::array<double, 3> RigidBody::to_body(const std::array<double, 3>& w) const
{
  const V3 b = mat_t_vec(R, {w[0] - x[0], w[1] - x[1], w[2] - x[2]});
  return {b[0] + centre[0], b[1] + centre[1], b[2] + centre[2]};
}

RigidBody make_projectile(const std::string& name, const Shape& shape, double density,
                          const std::array<double, 3>& tip, const std::array<double, 3>& direction,
                          const std::array<double, 3>& velocity)
{
  shape.validate();
  if (!(density > 0.0) || !std::isfinite(density))
    throw std::runtime_error("projectile '" + name + "': density " + std::to_string(density) + " kg/m^3 must be > 0");
  const double len = std::hypot(direction[0], direction[1], direction[2]);
  if (!(len > 0.0))
    throw std::runtime_error("projectile '" + name + "': its direction must not be zero");
  RigidBody b;
  b.name = name;
  b.shape = shape;
  const MassProperties mp = mass_properties(shape, density);
  b.mass = mp.mass;
  b.inertia = {mp.Ia, mp.It, mp.It};
  b.centre = {mp.ac, 0.0, 0.0};
  // R: body x -> direction, body y, z two unit vectors normal to it
  const V3 e1{direction[0] / len, direction[1] / len, direction[2] / len};
  const V3 helper = std::abs(e1[0]) < 0.9 ? V3{1, 0, 0} : V3{0, 1, 0};
  V3 e2 = cross3(e1.data(), helper.data());
  const double l2 = std::hypot(e2[0], e2[1], e2[2]);
  e2 = {e2[0] / l2, e2[1] / l2, e2[2] / l2};
  const V3 e3 = cross3(e1.data(), e2.data());
  b.R = {e1[0], e2[0], e3[0], e1[1], e2[1], e3[1], e1[2], e2[2], e3[2]};
  // the tip (body origin) at `tip`: x = tip + R (centre - 0)
  const V3 c = mat_vec(b.R, b.centre);
  b.x = {tip[0] + c[0], tip[1] + c[1], tip[2] + c[2]};
  b.v = velocity;
  return b;
}

RigidBody make_wall(const std::string& name, const Shape& shape, double friction)
{
  if (shape.kind == Shape::Kind::projectile)
    throw std::runtime_error("wall '" + name + "': a wall is a plane or a box");
  shape.validate();
  if (!(friction >= 0.0) || !std::isfinite(friction))
    throw std::runtime_error("wall '" + name + "': friction " + std::to_string(friction) + " must be >= 0");
  RigidBody b;
  b.name = name;
  b.shape = shape;
  b.fixed = true;
  b.friction = friction;
  return b;
}

double body_contact_stiffness(const Material& m, double r)
{
  const auto cf = impl::contact_factors(m);
  return cf.cn * m.youngs_modulus * std::numbers::pi * r;
}

void body_forces(Particles& p, RigidBody& b, BodyContacts& c, const NeighbourList& nl, const Material& m, double dt)
{
  refresh_candidates(p, b, c, nl);
  const double cs = impl::contact_factors(m).cs;
  const V3 w_b = b.omega();
  std::vector<std::int32_t> ids;
  std::vector<double> fs;
  std::size_t h = 0; // walks the previous contacts (sorted)
  b.f = b.t = {0, 0, 0};
  for (const std::int32_t i : c.near)
  {
    const V3 xi{p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]};
    const Distance D = signed_distance(b.shape, b.to_body(xi));
    const double ri = p.r[i], delta = ri - D.d;
    while (h < c.ids.size() && c.ids[h] < i)
      ++h;
    const double kn = body_contact_stiffness(m, ri), ks = cs * kn, Fn = kn * delta;
    if (!(delta > 0.0))
    {
      // a contact that opens: its cap fell to zero, the shear spring's
      // energy went by sliding
      if (h < c.ids.size() && c.ids[h] == i)
        c.friction_work += 0.5 * dot3(&c.fs[3 * h], &c.fs[3 * h]) / ks;
      continue;
    }
    const V3 n = mat_vec(b.R, D.n); // outward from the body, towards the sphere
    const double arm = ri - 0.5 * delta; // centre to contact point
    const V3 cp{xi[0] - arm * n[0], xi[1] - arm * n[1], xi[2] - arm * n[2]};
    // relative velocity of the sphere's surface over the body's at the contact point
    const V3 ws{p.w[3 * i], p.w[3 * i + 1], p.w[3 * i + 2]};
    const V3 rs{-arm * n[0], -arm * n[1], -arm * n[2]}, rb{cp[0] - b.x[0], cp[1] - b.x[1], cp[2] - b.x[2]};
    const V3 a1 = cross3(ws.data(), rs.data()), a2 = cross3(w_b.data(), rb.data());
    V3 vr;
    for (int k = 0; k < 3; ++k)
      vr[k] = p.v[3 * i + k] + a1[k] - b.v[k] - a2[k];
    const double vn = dot3(vr.data(), n.data());
    // the shear force: the stored one turned into the new tangent plane
    // (its magnitude kept), plus -ks v_t dt, capped at mu Fn (Coulomb)
    V3 f{0, 0, 0};
    if (h < c.ids.size() && c.ids[h] == i)
    {
      f = {c.fs[3 * h], c.fs[3 * h + 1], c.fs[3 * h + 2]};
      const double mag = std::hypot(f[0], f[1], f[2]), fn = dot3(f.data(), n.data());
      for (int k = 0; k < 3; ++k)
        f[k] -= fn * n[k];
      const double now = std::hypot(f[0], f[1], f[2]);
      if (now > 0.0)
        for (int k = 0; k < 3; ++k)
          f[k] *= mag / now;
    }
    const V3 f0 = f;
    for (int k = 0; k < 3; ++k)
      f[k] -= ks * (vr[k] - vn * n[k]) * dt;
    const double cap = b.friction * Fn, mag = std::hypot(f[0], f[1], f[2]);
    if (mag > cap)
    {
      const V3 trial = f;
      for (int k = 0; k < 3; ++k)
        f[k] = mag > 0.0 ? f[k] * cap / mag : 0.0;
      // the mean force's work over the increment less the spring's gain
      // (dem::contact_shear_force)
      double e = 0.0;
      for (int k = 0; k < 3; ++k)
        e += (f0[k] + f[k]) * (trial[k] - f[k]);
      c.friction_work += 0.5 * e / ks;
    }
    V3 F;
    for (int k = 0; k < 3; ++k)
      F[k] = Fn * n[k] + f[k];
    const V3 ts = cross3(rs.data(), F.data()), tb = cross3(rb.data(), F.data());
    for (int k = 0; k < 3; ++k)
    {
      p.f[3 * i + k] += F[k];
      p.t[3 * i + k] += ts[k];
      b.f[k] -= F[k];
      b.t[k] -= tb[k];
    }
    ids.push_back(i);
    fs.insert(fs.end(), f.begin(), f.end());
  }
  c.ids = std::move(ids);
  c.fs = std::move(fs);
}

double body_contact_energy(const Particles& p, const RigidBody& b, const BodyContacts& c, const Material& m)
{
  const double cs = impl::contact_factors(m).cs;
  double e = 0.0;
  for (std::size_t h = 0; h < c.ids.size(); ++h)
  {
    const std::int32_t i = c.ids[h];
    const Distance D = signed_distance(b.shape, b.to_body({p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]}));
    const double delta = std::max(0.0, p.r[i] - D.d), kn = body_contact_stiffness(m, p.r[i]);
    const double f2 = c.fs[3 * h] * c.fs[3 * h] + c.fs[3 * h + 1] * c.fs[3 * h + 1] + c.fs[3 * h + 2] * c.fs[3 * h + 2];
    e += 0.5 * kn * delta * delta + 0.5 * f2 / (cs * kn);
  }
  return e;
}

void refresh_candidates(const Particles& p, const RigidBody& b, BodyContacts& c, const NeighbourList& nl)
{
  // the spheres that may touch the body before the next refresh: those
  // whose centre lies within r + skin of the body's bounding box. Spheres
  // move less than nl.drift() (0.6 skin) between changes of the neighbour
  // list, which refresh the candidates; the body is held to skin/2 since the
  // last refresh.
  const double skin = nl.skin();
  // the farthest any point of the body may have moved: the centre's move,
  // plus the turn since the refresh (the angle of R R_refresh^T) times the
  // body's size
  double moved = std::hypot(b.x[0] - c.x_refresh[0], b.x[1] - c.x_refresh[1], b.x[2] - c.x_refresh[2]);
  if (b.shape.kind == Shape::Kind::projectile)
  {
    double tr = 0.0; // trace of R R_refresh^T
    for (int k = 0; k < 9; ++k)
      tr += b.R[k] * c.R_refresh[k];
    const double angle = std::acos(std::clamp(0.5 * (tr - 1.0), -1.0, 1.0));
    moved += angle * (b.shape.length + 0.5 * b.shape.diameter);
  }
  if (c.refreshed && c.version == nl.version() && moved <= 0.5 * skin)
    return;
  c.refreshed = true;
  c.version = nl.version();
  c.x_refresh = b.x;
  c.R_refresh = b.R;
  const auto [lo, hi] = bounding_box(b);
  double rmax = 0.0;
  for (double r : p.r)
    rmax = std::max(rmax, r);
  // a sphere moves up to a skin from where it was at the refresh, the body
  // up to skin/2
  const double g = rmax + 2.0 * skin;
  const double glo[3] = {lo[0] - g, lo[1] - g, lo[2] - g}, ghi[3] = {hi[0] + g, hi[1] + g, hi[2] + g};
  c.near.clear();
  auto take = [&](std::int32_t i)
  {
    const double* x = &p.x[3 * i];
    if (x[0] > glo[0] && x[0] < ghi[0] && x[1] > glo[1] && x[1] < ghi[1] && x[2] > glo[2] && x[2] < ghi[2])
      c.near.push_back(i);
  };
  // the cells of the neighbour list's grid around the box (its positions
  // are the last change's: spheres have moved less than nl.drift() since),
  // else every sphere. The box is kept finite (a plane's is unbounded).
  if (const CellGrid* grid = nl.grid())
  {
    const double half = nl.drift(), big = 1e200;
    const double qlo[3] = {std::max(glo[0] - half, -big), std::max(glo[1] - half, -big), std::max(glo[2] - half, -big)};
    const double qhi[3] = {std::min(ghi[0] + half, big), std::min(ghi[1] + half, big), std::min(ghi[2] + half, big)};
    grid->for_each_in_box(qlo, qhi, take);
    std::sort(c.near.begin(), c.near.end());
  }
  else
    for (std::size_t i = 0; i < p.size(); ++i)
      take(static_cast<std::int32_t>(i));
}

std::pair<std::array<double, 3>, std::array<double, 3>> bounding_box(const RigidBody& b)
{
  constexpr double big = 1e300;
  const Shape& s = b.shape;
  if (s.kind == Shape::Kind::box)
    return {s.lo, s.hi};
  if (s.kind == Shape::Kind::plane)
  {
    // the half space, bounded where its normal is along an axis
    V3 lo{-big, -big, -big}, hi{big, big, big};
    const double len = std::hypot(s.normal[0], s.normal[1], s.normal[2]);
    for (int k = 0; k < 3; ++k)
      if (std::abs(std::abs(s.normal[k]) / len - 1.0) < 1e-12)
      {
        if (s.normal[k] > 0.0)
          hi[k] = s.point[k];
        else
          lo[k] = s.point[k];
      }
    return {lo, hi};
  }
  // the projectile's cylinder hull: the tip, the tail, and the radius around them
  const V3 tip = b.to_world({0, 0, 0}), tail = b.to_world({-s.length, 0, 0});
  const double R = 0.5 * s.diameter;
  V3 lo, hi;
  for (int k = 0; k < 3; ++k)
  {
    lo[k] = std::min(tip[k], tail[k]) - R;
    hi[k] = std::max(tip[k], tail[k]) + R;
  }
  return {lo, hi};
}

} // namespace dembridge::dem
