// Rigid bodies: shapes (signed distances against closed form), mass
// properties, free flight, contact with spheres (bounce, oblique impact with
// friction, torque), the energy budget and momentum of an impact, restart.
#include "dembridge/dem/body.h"
#include "dembridge/dem/solver.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>
#include <unistd.h>

using namespace dembridge::dem;
using Catch::Contains;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using V3 = std::array<double, 3>;

namespace
{

Shape projectile(Nose nose, double d = 0.0254, double length = 0.12)
{
  Shape s;
  s.kind = Shape::Kind::projectile;
  s.diameter = d;
  s.length = length;
  s.nose = nose;
  return s;
}

Material body_concrete()
{
  Material m;
  m.micro = {0.2, 1.0, 1.0};
  return m;
}

/// One free sphere of radius r at x, moving at v.
Particles one_sphere(const V3& x, double r, const V3& v)
{
  Particles p = make_particles(std::vector<double>{x[0], x[1], x[2]}, std::vector<double>{r}, 2400.0, 1.0);
  for (int k = 0; k < 3; ++k)
    p.v[k] = v[k];
  return p;
}

/// The plane z = 0, solid below.
Shape floor_plane()
{
  Shape s;
  s.kind = Shape::Kind::plane;
  s.normal = {0, 0, 1};
  return s;
}

/// Period of a sphere's normal contact with a body [s].
double contact_period(const Particles& p, const Material& m)
{
  return 2 * std::numbers::pi * std::sqrt(p.m[0] / body_contact_stiffness(m, p.r[0]));
}

/// n^3 spheres on a jittered cubic lattice of spacing 2 mm, radii 0.95 mm.
Particles lattice(int n, const V3& origin)
{
  std::mt19937 gen(3);
  std::uniform_real_distribution<double> jit(-0.02e-3, 0.02e-3);
  std::vector<double> x, r;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
      {
        x.insert(x.end(), {origin[0] + 2e-3 * i + jit(gen), origin[1] + 2e-3 * j + jit(gen),
                           origin[2] + 2e-3 * k + jit(gen)});
        r.push_back(0.95e-3);
      }
  return make_particles(x, r, 2400.0, 0.6);
}
} // namespace

TEST_CASE("body shapes: signed distances of the noses against closed form", "[dem][body]")
{
  // Points at a known distance h along the outward normal of a surface point
  // (and -h inside): the distance must be h and the gradient that normal, to
  // round-off (1e-12 m on centimetre shapes).
  const double d = 0.0254, R = d / 2, h = 1e-3;
  auto check = [&](const Shape& s, const V3& surf, const V3& n, const std::string& what)
  {
    for (double sgn : {1.0, -1.0})
    {
      const V3 q{surf[0] + sgn * h * n[0], surf[1] + sgn * h * n[1], surf[2] + sgn * h * n[2]};
      const Distance D = signed_distance(s, q);
      INFO(what << (sgn > 0 ? " outside" : " inside") << ": distance " << D.d);
      CHECK_THAT(D.d, WithinAbs(sgn * h, 1e-12));
      for (int k = 0; k < 3; ++k)
        CHECK_THAT(D.n[k], WithinAbs(n[k], 1e-9));
    }
  };
  const double c45 = std::sqrt(0.5);
  // flat nose: the face, the shank's side
  check(projectile(Nose::flat), {0.0, 0.3 * R, 0.0}, {1, 0, 0}, "flat face");
  check(projectile(Nose::flat), {-0.05, 0.0, R}, {0, 0, 1}, "shank side");
  // hemisphere: centre of the nose sphere at -R on the axis
  {
    const Shape s = projectile(Nose::hemispherical);
    check(s, {0.0, 0.0, 0.0}, {1, 0, 0}, "hemisphere tip");
    check(s, {-R + R * c45, R * c45, 0.0}, {c45, c45, 0.0}, "hemisphere at 45 degrees");
  }
  // cone of half-angle 30 degrees: its side's normal (cos 60, sin 60) in (a, r)
  {
    Shape s = projectile(Nose::conical);
    s.cone_angle_deg = 30.0;
    const double Ln = s.nose_length(), a = -0.5 * Ln, r = R * 0.5; // half-way along the side
    const double na = std::sin(std::numbers::pi / 6), nr = std::cos(std::numbers::pi / 6);
    check(s, {a, 0.0, r}, {na, 0.0, nr}, "cone side");
    CHECK_THAT(Ln, WithinRel(R / std::tan(std::numbers::pi / 6), 1e-14));
  }
  // tangent ogive CRH 3: arc radius s = 3 d centred at (-L, -(s - R)), L = d sqrt(psi - 1/4)
  {
    Shape sh = projectile(Nose::ogive);
    sh.crh = 3.0;
    const double s = 3.0 * d, L = d * std::sqrt(2.75), c = s - R;
    CHECK_THAT(sh.nose_length(), WithinRel(L, 1e-14));
    for (double frac : {0.1, 0.5, 0.9})
    {
      const double x = frac * L, r = std::sqrt(s * s - x * x) - c; // x from the nose base
      const double na = x / s, nr = (r + c) / s;
      check(sh, {-L + x, r * c45, r * c45}, {na, nr * c45, nr * c45}, "ogive at " + std::to_string(frac) + " L");
    }
    // on the axis ahead of the tip: the tip is the nearest point
    CHECK_THAT(signed_distance(sh, {h, 0.0, 0.0}).d, WithinAbs(h, 1e-15));
  }
  // the gradient is the distance's derivative (central differences, away from edges)
  for (Nose nose : {Nose::flat, Nose::hemispherical, Nose::conical, Nose::ogive})
  {
    const Shape s = projectile(nose);
    std::mt19937 gen(1);
    std::uniform_real_distribution<double> ua(-0.1, 0.01), ur(-0.02, 0.02);
    for (int k = 0; k < 200; ++k)
    {
      const V3 q{ua(gen), ur(gen), ur(gen)};
      const Distance D = signed_distance(s, q);
      const double e = 1e-7;
      for (int c = 0; c < 3; ++c)
      {
        V3 qp = q, qm = q;
        qp[c] += e;
        qm[c] -= e;
        const double fd = (signed_distance(s, qp).d - signed_distance(s, qm).d) / (2 * e);
        if (std::abs(signed_distance(s, qp).d - D.d - (D.d - signed_distance(s, qm).d)) < 1e-10) // smooth here
          CHECK_THAT(fd, WithinAbs(D.n[c], 1e-5));
      }
    }
  }
}

TEST_CASE("body mass properties against closed form", "[dem][body]")
{
  const double d = 0.0254, R = d / 2, len = 0.12, rho = 7850.0;
  // flat: a cylinder, I_axis = m R^2 / 2, I_transverse = m (3 R^2 + len^2) / 12
  {
    const RigidBody b = make_projectile("p", projectile(Nose::flat), rho, {0, 0, 0}, {1, 0, 0}, {0, 0, 0});
    const double m = rho * std::numbers::pi * R * R * len;
    CHECK_THAT(b.mass, WithinRel(m, 1e-12));
    CHECK_THAT(b.centre[0], WithinRel(-0.5 * len, 1e-12));
    CHECK_THAT(b.inertia[0], WithinRel(0.5 * m * R * R, 1e-12));
    CHECK_THAT(b.inertia[1], WithinRel(m * (3 * R * R + len * len) / 12.0, 1e-12));
  }
  // hemispherical and conical noses: volumes std::numbers::pi R^2 (len - Ln) + 2/3 std::numbers::pi R^3, + std::numbers::pi R^2 Ln / 3
  CHECK_THAT(projectile(Nose::hemispherical).volume(), WithinRel(std::numbers::pi * R * R * (len - R) + 2.0 / 3.0 * std::numbers::pi * R * R * R, 1e-12));
  {
    const Shape s = projectile(Nose::conical);
    CHECK_THAT(s.volume(), WithinRel(std::numbers::pi * R * R * (len - s.nose_length()) + std::numbers::pi * R * R * s.nose_length() / 3.0, 1e-12));
  }
  // ogive: the nose int_0^L std::numbers::pi r^2 = std::numbers::pi (s^2 L - L^3 / 3 - c s^2 asin(L / s)), c = s - R
  {
    const Shape sh = projectile(Nose::ogive);
    const double s = 3.0 * d, L = sh.nose_length(), c = s - R;
    const double nose = std::numbers::pi * (s * s * L - L * L * L / 3.0 - c * s * s * std::asin(L / s));
    // Simpson on a smooth r^2 with 4000 intervals: 1e-10
    CHECK_THAT(sh.volume(), WithinRel(std::numbers::pi * R * R * (len - L) + nose, 1e-10));
  }
}

TEST_CASE("rigid body in free flight: translation and spin exact", "[dem][body]")
{
  // No sphere near: the body moves at constant velocity, spins at constant
  // rate about its axis (the axis of symmetry: Euler's equations leave it
  // alone), and keeps its angular momentum exactly.
  Particles p = one_sphere({10.0, 10.0, 10.0}, 1e-3, {0, 0, 0});
  Links l;
  const Material m = body_concrete();
  DemSolver s(p, l, m, 1e-6, 0.0, 1e-4);
  RigidBody b = make_projectile("p", projectile(Nose::ogive), 7850.0, {0, 0, 0}, {1, 0, 0}, {300.0, 5.0, -2.0});
  const double spin = 2000.0; // rad/s about the axis
  b.L = {b.inertia[0] * spin, 0.0, 0.0};
  const V3 x0 = b.x;
  s.add_body(b);
  s.start();
  const int n = 5000;
  for (int k = 0; k < n; ++k)
    s.step();
  const RigidBody& e = s.body(0);
  const double t = n * 1e-6;
  for (int k = 0; k < 3; ++k)
  {
    CHECK_THAT(e.x[k], WithinAbs(x0[k] + t * b.v[k], 1e-12));
    CHECK(e.v[k] == b.v[k]);
    CHECK(e.L[k] == b.L[k]);
  }
  // R: the initial orientation turned by spin t about the axis x
  const double a = spin * t, ca = std::cos(a), sa = std::sin(a);
  const double Q[9] = {1, 0, 0, 0, ca, -sa, 0, sa, ca};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
    {
      double want = 0.0;
      for (int q = 0; q < 3; ++q)
        want += Q[3 * i + q] * b.R[3 * q + j];
      CHECK_THAT(e.R[3 * i + j], WithinAbs(want, 1e-12));
    }
  CHECK_THAT(s.energy().imbalance(), WithinAbs(0.0, 1e-9 * e.kinetic_energy()));
}

TEST_CASE("rigid body in free flight: a tilted spin precesses about the angular momentum", "[dem][body]")
{
  // A symmetric body (I_t about its transverse axes) whose angular momentum
  // is not along its axis: L stays constant exactly, and the axis turns
  // about L at the rate |L| / I_t (torque-free precession), keeping its
  // angle to L. The update R <- exp(dt [omega]) R is exact for a rotation
  // about a fixed axis only; here the axis' direction after 0.2 rad of
  // precession is within (|L| dt / I_t)-order of the closed form: 1e-4.
  Particles p = one_sphere({10.0, 10.0, 10.0}, 1e-3, {0, 0, 0});
  Links l;
  DemSolver s(p, l, body_concrete(), 1e-6, 0.0, 1e-4);
  RigidBody b = make_projectile("p", projectile(Nose::ogive), 7850.0, {0, 0, 0}, {1, 0, 0}, {0, 0, 0});
  b.L = {b.inertia[1] * 50.0, b.inertia[1] * 30.0, 0.0}; // 30 degrees off the axis
  s.add_body(b);
  s.start();
  const double Ln = std::hypot(b.L[0], b.L[1], b.L[2]), rate = Ln / b.inertia[1];
  const int n = static_cast<int>(0.2 / rate / 1e-6);
  for (int k = 0; k < n; ++k)
    s.step();
  const RigidBody& e = s.body(0);
  CHECK(e.L == b.L);
  // the axis: body x in the world, R's first column
  const V3 axis{e.R[0], e.R[3], e.R[6]};
  // closed form: e(0) = x turned by rate t about L / |L| (Rodrigues)
  const double a = rate * n * 1e-6;
  const V3 u{b.L[0] / Ln, b.L[1] / Ln, b.L[2] / Ln}, e0{1, 0, 0};
  const double ue = u[0];
  const V3 uxe{0.0, u[2], -u[1]};
  for (int k = 0; k < 3; ++k)
  {
    const double want = e0[k] * std::cos(a) + uxe[k] * std::sin(a) + u[k] * ue * (1 - std::cos(a));
    CHECK_THAT(axis[k], WithinAbs(want, 1e-4));
  }
  // the energy 1/2 L . omega: omega follows R, so it drifts with R's error
  CHECK_THAT(e.kinetic_energy(), WithinRel(b.kinetic_energy(), 1e-4));
}

TEST_CASE("spheres resting on planes: every one that overlaps a plane is in contact", "[dem][body]")
{
  // A 6^3 lattice whose bottom layer overlaps a floor by 50 um and whose
  // side overlaps an inclined plane: the contacts found are those a direct
  // test of every sphere finds (the candidates come from the neighbour
  // list's cells, a plane's unbounded box clamped to the grid).
  Particles p = lattice(6, {0.0, 0.0, 0.95e-3 - 5e-5});
  Links l = create_links(p, 1.2, body_concrete());
  DemSolver s(p, l, body_concrete(), 1e-8, 0.0, 0.2e-3);
  const Shape floor = floor_plane();
  Shape slope;
  slope.kind = Shape::Kind::plane;
  slope.point = {0.0, 9.5e-3, 0.0};
  slope.normal = {0.0, -1.0, 1.0}; // solid below the line y - z = 9.5 mm... above y
  s.add_body(make_wall("floor", floor));
  s.add_body(make_wall("slope", slope));
  s.start();
  for (std::size_t k = 0; k < 2; ++k)
  {
    std::size_t direct = 0;
    for (std::size_t i = 0; i < p.size(); ++i)
      direct += signed_distance(s.body(k).shape, {p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]}).d < p.r[i];
    INFO(s.body(k).name << ": " << direct << " spheres overlap it");
    CHECK(direct >= 6);
    CHECK(s.body_contacts(k).ids.size() == direct);
  }
  CHECK(s.body_contacts(0).ids.size() == 36);
}

TEST_CASE("a sphere bouncing on a fixed plane keeps its speed", "[dem][body]")
{
  // Frictionless, undamped: the linear penalty contact is conservative; with
  // velocity Verlet at 1/50 of the contact's period the rebound speed is the
  // impact speed to O((omega dt)^2) -- within 1e-3.
  const double r = 1e-3, v0 = 2.0;
  Particles p = one_sphere({0.0, 0.0, 1.5e-3}, r, {0.0, 0.0, -v0});
  Links l;
  const Material m = body_concrete();
  DemSolver s(p, l, m, contact_period(p, m) / 50.0, 0.0, 1e-4);
  s.add_body(make_wall("floor", floor_plane()));
  s.start();
  while (p.v[2] < 0.0 || s.body_contacts(0).ids.size() > 0 || p.x[2] < r)
    s.step();
  INFO("rebound speed " << p.v[2] << " m/s for " << v0 << " m/s");
  CHECK_THAT(p.v[2], WithinRel(v0, 1e-3));
  CHECK(std::abs(p.v[0]) + std::abs(p.v[1]) == 0.0);
  const auto e = s.energy();
  CHECK(std::abs(e.imbalance()) < 1e-3 * e.initial);
}

TEST_CASE("critical time step with body contacts: below the contact's own bound", "[dem][body]")
{
  // One free sphere on a wall: the normal contact alone is a mass on a
  // spring, critical at 2 sqrt(m / K_n); the bound (with the shear spring
  // and the rotation) must lie below it, and a bounce at the bound stays
  // bounded.
  const double r = 1e-3, v0 = 1.0;
  Particles p = one_sphere({0.0, 0.0, 1.05e-3}, r, {0.0, 0.0, -v0});
  Links l;
  const Material m = body_concrete();
  const double dt = critical_time_step(p, l, m), own = 2.0 * std::sqrt(p.m[0] / body_contact_stiffness(m, r));
  INFO("bound " << dt << " s, normal contact alone " << own << " s");
  CHECK(dt < own);
  CHECK(dt > 0.3 * own); // not uselessly small
  DemSolver s(p, l, m, dt, 0.0, 1e-4);
  s.add_body(make_wall("floor", floor_plane(), 0.5));
  s.start();
  for (int k = 0; k < 200; ++k)
    s.step();
  CHECK(p.v[2] > 0.0);
  CHECK(std::hypot(p.v[0], p.v[1], p.v[2]) < 1.5 * v0);
}

TEST_CASE("oblique impact with friction: the sliding outcome of impulse theory", "[dem][body]")
{
  // A non-rotating sphere hits a plane with tangential speed 3 v_n, friction
  // mu = 0.1: it slides throughout (v_t > 7/2 mu (1 + e) v_n), so the
  // friction impulse is mu times the normal one, J_n = m (v_n' + v_n):
  //   v_t' = v_t - mu (v_n' + v_n),  omega' = (5 / 2) mu (v_n' + v_n) / r
  // (a solid sphere, I = 2/5 m r^2). The shear spring reaches the Coulomb cap
  // from the first step, so the outcome holds to the bounce's 1e-3.
  const double r = 1e-3, vn = 1.0, vt = 3.0, mu = 0.1;
  Particles p = one_sphere({0.0, 0.0, 1.2e-3}, r, {vt, 0.0, -vn});
  Links l;
  const Material m = body_concrete();
  DemSolver s(p, l, m, contact_period(p, m) / 100.0, 0.0, 1e-4);
  s.add_body(make_wall("floor", floor_plane(), mu));
  s.start();
  while (p.v[2] < 0.0 || s.body_contacts(0).ids.size() > 0)
    s.step();
  const double vn1 = p.v[2];
  INFO("after: v_n " << vn1 << ", v_t " << p.v[0] << ", omega_y " << p.w[1]);
  CHECK_THAT(vn1, WithinRel(vn, 2e-3));
  CHECK_THAT(p.v[0], WithinRel(vt - mu * (vn1 + vn), 1e-3));
  // the friction turns the sphere about +y (v_t along +x, contact below)
  CHECK_THAT(p.w[1], WithinRel(2.5 * mu * (vn1 + vn) / r, 1e-3));
  const auto e = s.energy();
  REQUIRE(e.body_friction > 0.0);
  CHECK(std::abs(e.imbalance()) < 1e-3 * e.initial);
}

TEST_CASE("a contact off the body's axis: force and torque on the body", "[dem][body]")
{
  // A flat-nosed projectile at rest, its face at x = 0, pressed on a sphere
  // held at y0 off its axis and overlapping the face by delta: the body feels
  // -K_n delta along x at (0, y0, 0) (the contact point on the face, half-way
  // in the overlap), so its torque about the centre of mass is
  // (0, 0, K_n delta y0) (r x F with r = (-x_c, y0, 0)), to round-off.
  const double r = 1e-3, delta = 1e-5, y0 = 5e-3;
  Particles p = one_sphere({r - delta, y0, 0.0}, r, {0, 0, 0});
  Links l;
  const Material m = body_concrete();
  DemSolver s(p, l, m, 1e-8, 0.0, 1e-4);
  s.add_motion({"held", {0}, MotionKind::fixed, {true, true, true}, {}});
  s.add_body(make_projectile("p", projectile(Nose::flat), 7850.0, {0, 0, 0}, {1, 0, 0}, {0, 0, 0}));
  s.start();
  const RigidBody& b = s.body(0);
  const double F = body_contact_stiffness(m, r) * delta;
  CHECK_THAT(b.f[0], WithinRel(-F, 1e-9));
  CHECK_THAT(b.f[1], WithinAbs(0.0, 1e-12 * F));
  CHECK_THAT(b.t[2], WithinRel(F * y0, 1e-9));
  CHECK_THAT(b.t[0], WithinAbs(0.0, 1e-12 * F * y0));
  CHECK_THAT(b.t[1], WithinAbs(0.0, 1e-12 * F * y0));
  // the sphere feels the opposite force
  CHECK_THAT(p.f[0], WithinRel(F, 1e-9));
}

TEST_CASE("projectile into a free bonded block: momentum kept, energy budget closed", "[dem][body]")
{
  // An ogive projectile at 100 m/s into a free 8^3 lattice with friction:
  // contact forces are equal and opposite, so the total momentum (spheres
  // and body) is kept to round-off; the budget (the body's kinetic and
  // contact energy and friction included) closes to the integration's
  // O((omega dt)^2) of the energy exchanged (within 1e-3 of the initial).
  Particles p = lattice(8, {0.0, -7e-3, -7e-3});
  Material m = body_concrete();
  m.tensile = 1e12;
  m.cohesion = 1e12; // elastic links: no breakage, the budget's terms here are the contacts'
  Links l = create_links(p, 1.2, m);
  const double dt = 0.2 * critical_time_step(p, l);
  DemSolver s(p, l, m, dt, 0.0, 0.2e-3);
  Shape sh = projectile(Nose::ogive, 0.006, 0.03);
  RigidBody b = make_projectile("p", sh, 7850.0, {-0.2e-3, 0.0, 0.0}, {1, 0, 0}, {100.0, 0.0, 0.0});
  b.friction = 0.2;
  s.add_body(b);
  s.start();
  auto momentum = [&]
  {
    V3 q{0, 0, 0};
    for (std::size_t i = 0; i < p.size(); ++i)
      for (int k = 0; k < 3; ++k)
        q[k] += p.m[i] * p.v[3 * i + k];
    for (int k = 0; k < 3; ++k)
      q[k] += s.body(0).mass * s.body(0).v[k];
    return q;
  };
  // angular momentum about the origin: the spheres' and the body's orbital
  // and spin parts; contact forces and their moments cancel in pairs
  auto angular = [&]
  {
    V3 a{0, 0, 0};
    for (std::size_t i = 0; i < p.size(); ++i)
    {
      const double* x = &p.x[3 * i];
      const double* v = &p.v[3 * i];
      a[0] += p.m[i] * (x[1] * v[2] - x[2] * v[1]) + p.inertia[i] * p.w[3 * i];
      a[1] += p.m[i] * (x[2] * v[0] - x[0] * v[2]) + p.inertia[i] * p.w[3 * i + 1];
      a[2] += p.m[i] * (x[0] * v[1] - x[1] * v[0]) + p.inertia[i] * p.w[3 * i + 2];
    }
    const RigidBody& q = s.body(0);
    a[0] += q.mass * (q.x[1] * q.v[2] - q.x[2] * q.v[1]) + q.L[0];
    a[1] += q.mass * (q.x[2] * q.v[0] - q.x[0] * q.v[2]) + q.L[1];
    a[2] += q.mass * (q.x[0] * q.v[1] - q.x[1] * q.v[0]) + q.L[2];
    return a;
  };
  const V3 q0 = momentum(), a0 = angular();
  const double e0 = s.energy().initial;
  std::size_t most = 0;
  for (int k = 0; k < 600; ++k)
  {
    s.step();
    most = std::max(most, s.body_contacts(0).ids.size());
  }
  REQUIRE(most > 3); // the nose did hit the block
  const V3 q1 = momentum(), a1 = angular();
  for (int k = 0; k < 3; ++k)
    CHECK_THAT(q1[k], WithinAbs(q0[k], 1e-9 * std::abs(q0[0])));
  // the scale: the body's momentum times the block's size
  const double scale = std::abs(q0[0]) * 16e-3;
  INFO("angular momentum before " << a0[0] << ", " << a0[1] << ", " << a0[2] << "; after " << a1[0] << ", " << a1[1]
                                  << ", " << a1[2]);
  for (int k = 0; k < 3; ++k)
    CHECK_THAT(a1[k], WithinAbs(a0[k], 1e-9 * scale));
  const auto e = s.energy();
  INFO("body kinetic " << e.body_kinetic << " J of " << e0 << " J; friction " << e.body_friction << " J, imbalance "
                       << e.imbalance() << " J");
  CHECK(e.body_kinetic < e0);
  CHECK(e.body_friction > 0.0);
  CHECK(std::abs(e.imbalance()) < 1e-3 * e0);
}

TEST_CASE("restart with a rigid body: bit for bit", "[dem][body][restart]")
{
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / ("dembridge-body-restart-" + std::to_string(::getpid()) + ".h5");
  struct Run
  {
    Particles p = lattice(6, {0.0, -5e-3, -5e-3});
    Material m = body_concrete();
    Links l;
    std::unique_ptr<DemSolver> s;
    Run()
    {
      l = create_links(p, 1.2, m);
      s = std::make_unique<DemSolver>(p, l, m, 0.2 * critical_time_step(p, l), 10.0, 0.2e-3);
      RigidBody b = make_projectile("p", projectile(Nose::conical, 0.005, 0.02), 7850.0, {-0.2e-3, 1e-3, 0.0},
                                    {1, 0.1, 0}, {150.0, 0.0, 0.0});
      b.friction = 0.3;
      s->add_body(b);
      s->set_domain({-1.2e-3, -6.2e-3, -6.2e-3}, {11.2e-3, 6.2e-3, 6.2e-3}); // tight: spheres pushed out leave
      s->start();
    }
  };
  Run whole;
  const int total = 700;
  for (int k = 0; k < total; ++k)
    whole.s->step();
  std::int64_t at = 0;
  {
    // the checkpoint during a contact (from step 400 on), so that the shear
    // history is in it
    Run first;
    while (first.s->steps() < 400 || first.s->body_contacts(0).ids.empty())
      first.s->step();
    at = first.s->steps();
    REQUIRE(at < total);
    INFO("spheres removed by the checkpoint: " << first.s->removed().count);
    CHECK(first.s->removed().count > 0); // the removed spheres' state is in the checkpoint
    auto f = dembridge::checkpoint::File::create(file, "body test");
    first.s->save(f.root().group("dem"));
    f.commit();
  }
  Run resumed;
  resumed.s->load(dembridge::checkpoint::File::open(file, "body test").root().group("dem"));
  for (std::int64_t k = at; k < total; ++k)
    resumed.s->step();
  fs::remove(file);
  REQUIRE(whole.s->energy().body_friction > 0.0);
  INFO("spheres removed: " << whole.s->removed().count);
  CHECK(whole.s->removed().count > 0);
  CHECK(resumed.s->removed().count == whole.s->removed().count);
  CHECK(resumed.s->removed().momentum == whole.s->removed().momentum);
  CHECK(resumed.s->energy().removed == whole.s->energy().removed);
  CHECK(resumed.p.x == whole.p.x);
  CHECK(resumed.p.v == whole.p.v);
  CHECK(resumed.p.w == whole.p.w);
  CHECK(resumed.s->body(0).x == whole.s->body(0).x);
  CHECK(resumed.s->body(0).L == whole.s->body(0).L);
  CHECK(resumed.s->body(0).R == whole.s->body(0).R);
  CHECK(resumed.s->energy().body_friction == whole.s->energy().body_friction);
}

TEST_CASE("rigid bodies: bad shapes and bodies are refused, naming the value", "[dem][body][errors]")
{
  Shape s = projectile(Nose::ogive);
  s.crh = 0.3;
  CHECK_THROWS_WITH(s.validate(), Contains("ogive CRH 0.3") && Contains(">= 0.5"));
  s = projectile(Nose::ogive, 0.0254, 0.02); // shorter than its nose
  CHECK_THROWS_WITH(s.validate(), Contains("twice the nose length"));
  s = projectile(Nose::conical);
  s.cone_angle_deg = 90.0;
  CHECK_THROWS_WITH(s.validate(), Contains("cone half-angle 90"));
  CHECK_THROWS_WITH(make_projectile("p", projectile(Nose::flat), -1.0, {0, 0, 0}, {1, 0, 0}, {0, 0, 0}),
                    Contains("density -1"));
  Particles p = one_sphere({0, 0, 0}, 1e-3, {0, 0, 0});
  Links l;
  DemSolver solver(p, l, body_concrete(), 1e-7, 0.0, 1e-4);
  RigidBody b = make_projectile("p", projectile(Nose::flat), 7850.0, {1, 0, 0}, {1, 0, 0}, {0, 0, 0});
  solver.add_body(b);
  CHECK_THROWS_WITH(solver.add_body(b), Contains("'p': the name is in use"));
  b.name = "q";
  b.mass = 0.0;
  CHECK_THROWS_WITH(solver.add_body(b), Contains("needs a mass"));
}

TEST_CASE("fragments: spheres leaving the domain are removed and booked", "[dem][body][fragments]")
{
  // A bonded 6^3 block hit by a projectile at 400 m/s through it, in a
  // domain a little larger than the block: the spheres thrown out are
  // removed. Booked: their count and mass; momentum is kept (active spheres,
  // body and removed together) to round-off; the energy budget, the
  // removed spheres' kinetic and stored energy included, closes within
  // 1e-3 of the initial energy (the impact test's integration error). The
  // neighbour grid stays within the domain (the removed spheres do not
  // stretch it, as they do without a domain).
  Particles p = lattice(6, {0.0, -5e-3, -5e-3});
  Material m = body_concrete();
  m.tensile = 0.3e6;
  m.cohesion = 0.5e6; // weak: the block breaks up
  Links l = create_links(p, 1.2, m);
  DemSolver s(p, l, m, 0.2 * critical_time_step(p, l, m), 0.0, 0.2e-3);
  s.set_energy_guard(0.0); // the jittered lattice's overlaps: see the threads test
  s.set_domain({-3e-3, -8e-3, -8e-3}, {13e-3, 8e-3, 8e-3});
  // a face moved at a set velocity: its reactions and their work must not
  // be disturbed by the removals (the held dofs' histories of the step)
  s.add_motion({"face", DemSolver::select(p, [](const auto& x) { return x[1] < -4.5e-3; }, "face"),
                MotionKind::velocity, {false, true, false}, [](double) { return -2.0; }});
  s.add_body(make_projectile("p", projectile(Nose::ogive, 0.006, 0.03), 7850.0, {-1.5e-3, 0.0, 0.0}, {1, 0, 0},
                             {400.0, 0.0, 0.0}));
  s.start();
  const double cell = s.neighbours().grid()->cell_size();
  const double e0 = s.energy().initial;
  V3 q0{0, 0, 0};
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int k = 0; k < 3; ++k)
      q0[k] += p.m[i] * p.v[3 * i + k];
  for (int k = 0; k < 3; ++k)
    q0[k] += s.body(0).mass * s.body(0).v[k];
  for (int k = 0; k < 1500; ++k)
    s.step();
  const Removed& g = s.removed();
  REQUIRE(g.count > 0);
  std::size_t flagged = 0;
  double mass = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (s.removed_flags()[i])
    {
      ++flagged;
      mass += p.m[i];
      CHECK(p.v[3 * i] == 0.0); // held where it left
    }
  CHECK(flagged == g.count);
  CHECK_THAT(g.mass, WithinRel(mass, 1e-12));
  V3 q1 = g.momentum;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int k = 0; k < 3; ++k)
      q1[k] += p.m[i] * p.v[3 * i + k];
  for (int k = 0; k < 3; ++k)
    q1[k] += s.body(0).mass * s.body(0).v[k];
  for (int k : {0, 2}) // y is driven by the face's condition
    CHECK_THAT(q1[k], WithinAbs(q0[k], 1e-9 * q0[0]));
  const auto e = s.energy();
  INFO(g.count << " spheres removed, " << g.kinetic << " J kinetic and " << g.elastic << " J stored carried away; "
               << "imbalance " << e.imbalance() << " J of " << e0 << " J");
  CHECK_THAT(e.removed, WithinRel(g.kinetic + g.elastic, 1e-12));
  CHECK(std::abs(e.imbalance()) < 1e-3 * e0);
  for (std::size_t k = 0; k < l.size(); ++k) // no intact link left to a removed sphere
    if (s.removed_flags()[l.a[k]] || s.removed_flags()[l.b[k]])
      CHECK(l.state[k] != LinkState::intact);
  // the grid spans the domain at most: its cells grow only as the set in it
  // thins (4 cells per sphere at most), not with the fragments' flight
  const double with_domain = s.neighbours().grid()->cell_size();
  CHECK(with_domain < 1.5 * cell);
  {
    // the same impact without a domain: the fragments stretch the grid
    Particles q = lattice(6, {0.0, -5e-3, -5e-3});
    Links lq = create_links(q, 1.2, m);
    DemSolver t(q, lq, m, s.dt(), 0.0, 0.2e-3);
    t.set_energy_guard(0.0);
    t.add_body(make_projectile("p", projectile(Nose::ogive, 0.006, 0.03), 7850.0, {-1.5e-3, 0.0, 0.0}, {1, 0, 0},
                               {400.0, 0.0, 0.0}));
    t.start();
    for (int k = 0; k < 1500; ++k)
      t.step();
    INFO("cell size " << cell << " m at the start, " << with_domain << " m with the domain, "
                      << t.neighbours().grid()->cell_size() << " m without");
    CHECK(t.neighbours().grid()->cell_size() > 1.2 * with_domain);
  }
  CHECK_THROWS_WITH(s.set_domain({0, 0, 0}, {1, -1, 1}), Contains("hi must exceed lo"));
}

TEST_CASE("fragments: a sphere pushed out of the domain by a body takes its contact's energy along",
          "[dem][body][fragments]")
{
  // A free sphere pressed by a flat nose (overlap 10 um) and pushed across
  // the domain's face while in contact: the contact ends with the removal,
  // its elastic energy is booked with the sphere, and the budget closes to
  // one step's work of the contact force, F v dt: the sphere leaves with
  // its half-step velocity, the second half kick of the step it leaves in
  // not given (so that momentum is kept exactly), and velocity Verlet
  // pairs the stored energy with the full-step velocity. Without the
  // contact's energy booked the imbalance would be the whole of it.
  const double r = 1e-3;
  Particles p = one_sphere({r - 1e-5, 0.0, 0.0}, r, {0, 0, 0});
  Links l;
  const Material m = body_concrete();
  DemSolver s(p, l, m, contact_period(p, m) / 100.0, 0.0, 1e-4);
  s.set_domain({-1.0, -1.0, -1.0}, {r + 2e-6, 1.0, 1.0});
  s.add_body(make_projectile("p", projectile(Nose::flat), 7850.0, {0, 0, 0}, {1, 0, 0}, {5.0, 0, 0}));
  s.start();
  REQUIRE(s.body_contacts(0).ids.size() == 1);
  double fmax = 0.0, v = 0.0;
  for (int k = 0; k < 200 && s.removed().count == 0; ++k)
  {
    v = p.v[0];
    s.step();
    fmax = std::max(fmax, std::abs(p.f[0]));
  }
  REQUIRE(s.removed().count == 1);
  s.step();
  CHECK(s.body_contacts(0).ids.empty());
  const auto e = s.energy();
  INFO("stored energy carried away " << s.removed().elastic << " J; imbalance " << e.imbalance() << " J of "
                                     << e.initial << " J");
  CHECK(s.removed().elastic > 0.0);
  CHECK(std::abs(e.imbalance()) < fmax * v * s.dt());
  CHECK(std::abs(e.imbalance()) < 0.5 * s.removed().elastic);
}

TEST_CASE("fragments: a sphere leaving with a stretched link and a contact takes their energy along",
          "[dem][fragments]")
{
  // Spheres a and b on the x axis, c beside b along y: a-b joined by a link
  // stretched by 0.1 um (below the tensile strength), b-c a contact (their
  // link broken) pressed by 0.2 um, each holding a good part of the energy.
  // b moves out through the domain's face at 0.2 m/s; when it goes,
  // the link and the contact end and their energy is booked with it, summed
  // over what it ends alone. Nothing else stores energy, so what is booked
  // is the assembly's whole elastic energy then: within one step's work of
  // the forces (sum of F v dt) of the energy stored the step before, and the
  // budget closes to that work (the body test above says why). The link
  // holds a fifth of the energy, the contact the rest: booking either alone
  // would miss by some 40 times that bound.
  const double r = 1e-3;
  Particles p = make_particles(std::vector<double>{0.0, 0.0, 0.0, 2 * r, 0.0, 0.0, 2 * r, 2 * r - 0.2e-6, 0.0},
                               std::vector<double>{r, r, r}, 2400.0, 1.0);
  const Material m = body_concrete();
  Links l = create_links(p, 1.2, m);
  REQUIRE(l.size() == 2);
  l.state[1] = LinkState::broken_tension; // b-c: a contact
  p.x[3] += 1e-7;                          // a-b stretched
  p.v[3] = 0.2;
  DemSolver s(p, l, m, contact_period(p, m) / 1000.0, 0.0, 1e-4);
  s.set_domain({-1.0, -1.0, -1.0}, {p.x[3] + 2.5 * 0.2 * s.dt(), 1.0, 1.0});
  s.start();
  REQUIRE(s.energy().elastic > 0.0);
  // the most work the forces do in a step: sum of |F| |v| dt over the spheres
  auto step_work = [&]
  {
    double w = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i)
      w += std::hypot(p.f[3 * i], p.f[3 * i + 1], p.f[3 * i + 2]) * std::hypot(p.v[3 * i], p.v[3 * i + 1], p.v[3 * i + 2]);
    return w * s.dt();
  };
  double stored = 0.0, work = step_work();
  for (int k = 0; k < 10 && s.removed().count == 0; ++k)
  {
    stored = s.energy().elastic;
    s.step();
    work = std::max(work, step_work());
  }
  REQUIRE(s.removed().count == 1);
  CHECK(l.state[0] == LinkState::removed);
  const auto e = s.energy();
  INFO("stored " << stored << " J the step before; booked " << s.removed().elastic << " J; one step's work "
                 << work << " J; imbalance " << e.imbalance() << " J");
  CHECK(e.elastic == 0.0);
  CHECK(std::abs(s.removed().elastic - stored) < work);
  CHECK(std::abs(e.imbalance()) < work);
  CHECK(work < 0.1 * stored); // (the bounds above are tight)
}

TEST_CASE("fragments: a removal leaves the conditions' reactions and work alone", "[dem][fragments]")
{
  // Sphere a moves at a set 1 m/s with nothing on it: its reaction and the
  // work of its condition are zero at every step. Sphere b flies out of the
  // domain and is removed: the step it leaves in must not disturb a's
  // (the held dofs' histories of that step are kept).
  Particles p = make_particles(std::vector<double>{0, 0, 0, 0.1, 0, 0}, std::vector<double>{1e-3, 1e-3}, 2400.0,
                               1.0);
  p.v[0] = 1.0; // already at its set velocity: no impulse at the start
  p.v[3] = 50.0;
  Links l;
  DemSolver s(p, l, body_concrete(), 1e-6, 0.0, 1e-4);
  s.set_domain({-1.0, -1.0, -1.0}, {0.1 + 1e-3, 1.0, 1.0});
  s.add_motion({"a", {0}, MotionKind::velocity, {true, false, false}, [](double) { return 1.0; }});
  s.start();
  for (int k = 0; k < 100; ++k)
    s.step();
  REQUIRE(s.removed().count == 1);
  CHECK(s.reaction("a")[0] == 0.0);
  CHECK(s.energy().prescribed_work == 0.0);
}
