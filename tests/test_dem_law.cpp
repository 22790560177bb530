// The concrete law of the DE model (docs/method.md sections 1.5-1.8), pair by pair,
// against the closed-form values of the law itself.
#include "dembridge/dem/law.h"
#include "dembridge/dem/material_file.h"
#include "dembridge/dem/packing.h"
#include "dembridge/dem/solver.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <numbers>

using namespace dembridge::dem;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;

namespace
{
// S = pi (1 mm)^2, K_n = 1e7 N/m: elastic limit delta_e = S T / K_n
LinkLaw law()
{
  return {1e7, 4e6, std::numbers::pi * 1e-6, 3.3e6, 4.4e6, std::tan(30 * std::numbers::pi / 180),
          std::tan(20 * std::numbers::pi / 180), 10.0};
}
double norm(const Vec3& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }
} // namespace

TEST_CASE("normal law: elastic, peak, softening slope, rupture, secant unloading", "[dem][law]")
{
  const LinkLaw p = law();
  const double fpk = p.s_int * p.tensile, de = fpk / p.kn, dr = (1 + p.zeta) * de;
  // elastic: K_n delta, in tension and compression
  auto r = link_normal_force(0.5 * de, 0.0, p);
  CHECK_THAT(r.fn, WithinRel(p.kn * 0.5 * de, 1e-14));
  CHECK(r.state == NormalState::elastic);
  CHECK_THAT(link_normal_force(-3 * de, 0.0, p).fn, WithinRel(-3 * p.kn * de, 1e-14));
  CHECK(link_normal_force(-100 * de, 0.0, p).state != NormalState::broken); // compression never breaks
  // peak S_int T at delta_e
  CHECK_THAT(link_normal_force(de, 0.0, p).fn, WithinRel(fpk, 1e-14));
  // softening slope -K_n / zeta
  const double f1 = link_normal_force(2 * de, 0.0, p).fn, f2 = link_normal_force(3 * de, 2 * de, p).fn;
  CHECK_THAT((f2 - f1) / de, WithinRel(-p.kn / p.zeta, 1e-12));
  // rupture at (1 + zeta) delta_e: just before, positive; at it, broken
  CHECK(link_normal_force(dr * (1 - 1e-9), 0.0, p).fn > 0.0);
  CHECK(link_normal_force(dr, 0.0, p).state == NormalState::broken);
  CHECK(link_normal_force(dr, 0.0, p).fn == 0.0);
  // unloading from delta_max = 4 delta_e follows the secant to the origin
  const double dm = 4 * de, fdm = fpk - p.kn / p.zeta * (dm - de);
  auto u = link_normal_force(2 * de, dm, p);
  CHECK(u.state == NormalState::softening);
  CHECK_THAT(u.fn, WithinRel(fdm / dm * 2 * de, 1e-14));
  CHECK(u.delta_max == dm);
  // reloading past delta_max rejoins the envelope
  CHECK_THAT(link_normal_force(5 * de, dm, p).fn, WithinRel(fpk - p.kn / p.zeta * 4 * de, 1e-14));
  // once broken, always broken
  CHECK(link_normal_force(0.5 * de, dr, p).state == NormalState::broken);
}

TEST_CASE("softening dissipation: zero when elastic, the whole triangle at rupture", "[dem][law]")
{
  const LinkLaw p = law();
  const double fpk = p.s_int * p.tensile, de = fpk / p.kn, dr = (1 + p.zeta) * de;
  CHECK(softening_dissipation(0.9 * de, p) == 0.0);
  CHECK_THAT(softening_dissipation(dr, p), WithinRel(0.5 * fpk * dr, 1e-12));
  CHECK_THAT(softening_dissipation(10 * dr, p), WithinRel(0.5 * fpk * dr, 1e-12));
  // in between: loading-path area minus secant energy
  const double dm = 3 * de, f = fpk - p.kn / p.zeta * 2 * de;
  CHECK_THAT(softening_dissipation(dm, p),
             WithinRel(0.5 * fpk * de + 0.5 * (fpk + f) * 2 * de - 0.5 * f * dm, 1e-12));
}

TEST_CASE("shear law: Mohr-Coulomb cap of a link", "[dem][law]")
{
  const LinkLaw p = law();
  const double c0 = p.s_int * p.cohesion;
  // in compression F_c = 1000 N the cap is S C0 + F_c tan(phi_i)
  const double fn = -1000.0, cap = c0 + 1000.0 * p.tan_phi_i;
  const double du = 0.999 * cap / p.ks;
  auto s = link_shear_force({0, 0, 0}, {du, 0, 0}, fn, p);
  CHECK(!s.exceeded);
  CHECK_THAT(s.fs[0], WithinRel(-p.ks * du, 1e-14)); // opposes the motion of b
  CHECK(link_shear_force({0, 0, 0}, {1.002 * cap / p.ks, 0, 0}, fn, p).exceeded);
  // in tension the cap shrinks: F_c < 0
  CHECK(link_shear_force({0, 0, 0}, {0.999 * c0 / p.ks, 0, 0}, 100.0, p).exceeded);
}

TEST_CASE("contacts: push only, Coulomb friction cap", "[dem][law]")
{
  const LinkLaw p = law();
  CHECK(contact_normal_force(2.1e-3, 2e-3, p.kn) == 0.0);
  CHECK_THAT(contact_normal_force(1.9e-3, 2e-3, p.kn), WithinRel(-p.kn * 1e-4, 1e-9));
  const double fn = -500.0, cap = 500.0 * p.tan_phi_c;
  auto s = contact_shear_force({0, 0, 0}, {0, 2 * cap / p.ks, 0}, fn, p);
  CHECK(s.exceeded);
  CHECK_THAT(norm(s.fs), WithinRel(cap, 1e-14));
  // sliding starts from rest: the mean force cap/2 over the slip cap/ks
  CHECK_THAT(s.slip_energy, WithinRel(0.5 * cap * cap / p.ks, 1e-12));
  // sliding goes on at the cap: cap x slip
  auto g = contact_shear_force(s.fs, {0, 0.3 * cap / p.ks, 0}, fn, p);
  CHECK_THAT(g.slip_energy, WithinRel(0.3 * cap * cap / p.ks, 1e-12));
  auto t = contact_shear_force({0, 0, 0}, {0, 0.5 * cap / p.ks, 0}, fn, p);
  CHECK(!t.exceeded);
  CHECK(t.slip_energy == 0.0);
  // no compression, no friction
  CHECK(norm(contact_shear_force({1, 0, 0}, {0, 0, 0}, 0.0, p).fs) == 0.0);
}

TEST_CASE("contacts: the Tresca limit caps friction at S_int tau_max under high pressure only", "[dem][law]")
{
  LinkLaw p = law();
  p.shear_limit = 50e6; // S_int tau_max = 157 N
  const double tresca = p.s_int * p.shear_limit;
  // low pressure: Coulomb's cap, 100 N x tan 20 = 36 N, binds
  const double low = 100.0 * p.tan_phi_c;
  auto a = contact_shear_force({0, 0, 0}, {0, 2 * low / p.ks, 0}, -100.0, p);
  CHECK_THAT(norm(a.fs), WithinRel(low, 1e-14));
  // high pressure: 5 kN x tan 20 = 1.8 kN, far above the limit, which binds
  auto b = contact_shear_force({0, 0, 0}, {0, 2 * tresca / p.ks, 0}, -5000.0, p);
  CHECK(b.exceeded);
  CHECK_THAT(norm(b.fs), WithinRel(tresca, 1e-14));
  // sliding on at the limit dissipates limit x slip, as at Coulomb's cap
  auto g = contact_shear_force(b.fs, {0, 0.3 * tresca / p.ks, 0}, -5000.0, p);
  CHECK_THAT(g.slip_energy, WithinRel(0.3 * tresca * tresca / p.ks, 1e-12));
  // 0 = no limit: Coulomb at any pressure
  p.shear_limit = 0.0;
  const double coulomb = 5000.0 * p.tan_phi_c;
  CHECK_THAT(norm(contact_shear_force({0, 0, 0}, {0, 2 * coulomb / p.ks, 0}, -5000.0, p).fs), WithinRel(coulomb, 1e-14));
}

TEST_CASE("torques: magnitude R |F_s|, direction -n x F_s", "[dem][law]")
{
  const Vec3 n{1, 0, 0}, fs{0, 2.0, 0};
  const auto t = shear_torques(n, fs, 0.003, 0.005);
  // n x fs = (0, 0, 2): t_a = -l_a (0,0,2), t_b = -l_b (0,0,2)
  CHECK_THAT(t[0][2], WithinRel(-0.006, 1e-14));
  CHECK_THAT(t[1][2], WithinRel(-0.010, 1e-14));
  CHECK(t[0][0] == 0.0);
}

TEST_CASE("shear kinematics: rigid rotations give no shear, the force turns with the pair",
          "[dem][law]")
{
  // a finite rigid rotation (0.3 rad about an oblique axis) of the pair and
  // both spheres: no shear increment, and the stored force turns exactly
  const Vec3 axis{0.3, -0.5, 0.8};
  const double an = norm(axis);
  const Vec3 th{0.3 * axis[0] / an, 0.3 * axis[1] / an, 0.3 * axis[2] / an};
  const Vec3 n0{1.0, 0.0, 0.0};
  const Vec3 n1 = rotate(th, n0);
  CHECK(std::abs(norm(n1) - 1.0) < 1e-15);
  const Mat3 R = rotation_matrix(th);
  CHECK(norm(shear_increment(n0, n1, R, R, 2e-3, 0.4)) < 1e-18);
  const Vec3 fs{0.0, 3.0, -1.0};
  const Vec3 f1 = rotate_shear(fs, R, R, 0.4, n1), expect = rotate(th, fs);
  for (int i = 0; i < 3; ++i)
    CHECK(std::abs(f1[i] - expect[i]) < 1e-14);
  // b displaced tangentially by delta (no spin): du_s = delta to first order
  const double D = 2e-3, delta = 1e-8;
  Vec3 n2{D, delta, 0.0};
  const double l2 = norm(n2);
  for (auto& c : n2)
    c /= l2;
  const Mat3 I = rotation_matrix({0, 0, 0});
  const Vec3 t = shear_increment(n0, n2, I, I, l2, 0.5);
  CHECK(std::abs(t[1] - delta) < 1e-6 * delta);
  // sphere a spinning by w about z (no branch motion): the contact point of a
  // moves by +l_a w along y, so b moves by -l_a w relative to it
  const Vec3 u = shear_increment(n0, n0, rotation_matrix({0, 0, 1e-6}), I, D, 0.5);
  CHECK(std::abs(u[1] + 0.5 * D * 1e-6) < 1e-9 * D * 1e-6);
}

TEST_CASE("trial shear in one product equals the stored force turned minus K_s times the "
          "increment", "[dem][law]")
{
  // The force loop uses trial_shear = P Rp (fs + K_s D n_old); the law's two
  // steps are rotate_shear (P Rp fs) and shear_increment (-D P Rp n_old).
  // Both are linear in Rp and P, so the results agree to round-off: terms
  // of size |fs| ~ K_s D |n| ~ 1e2 N summed in a different order, a few ulps
  // of 1e2 N, i.e. ~1e-13 N; bound 1e-12 relative to the largest term.
  const double ks = 4e6, D = 2.1e-3, fa = 0.4;
  for (int c = 0; c < 20; ++c)
  {
    const double s = 0.37 * c; // deterministic spread of directions and angles
    const Vec3 th_a{1e-3 * std::sin(s), 2e-3 * std::cos(1.3 * s), -1e-3 * std::sin(0.7 * s)};
    const Vec3 th_b{0.3 * std::cos(s), -0.2 * std::sin(2.1 * s), 0.1};
    const Mat3 ra = rotation_matrix(th_a), rb = rotation_matrix(th_b);
    Vec3 n_old{std::cos(s), std::sin(s), 0.3}, n_new{std::cos(s + 0.01), std::sin(s + 0.01), 0.28};
    const double lo = norm(n_old), ln = norm(n_new);
    for (int k = 0; k < 3; ++k)
    {
      n_old[k] /= lo;
      n_new[k] /= ln;
    }
    const Vec3 fs{30.0 * std::cos(2 * s), -20.0, 10.0 * std::sin(s)};
    const Vec3 turned = rotate_shear(fs, ra, rb, fa, n_new);
    const Vec3 du = shear_increment(n_old, n_new, ra, rb, D, fa);
    const Vec3 fused
        = trial_shear(fs, n_old, n_new, rotation_minus_identity(th_a), step_rotation(th_b), fa, ks * D);
    const double scale = std::max(norm(fs), ks * D);
    for (int k = 0; k < 3; ++k)
      CHECK(std::abs(fused[k] - (turned[k] - ks * du[k])) < 1e-12 * scale);
  }
}

TEST_CASE("trial shear: a link that neither turns nor spins keeps its force exactly",
          "[dem][law]")
{
  // R - I is exactly zero without rotation; I + (R - I) is a rotation
  // (orthogonal to round-off, 1e-15) about theta (which it leaves fixed),
  // turning a vector as rotate() does (1e-15 of its length)
  const Mat3 q0 = rotation_minus_identity(Vec3{0.0, 0.0, 0.0});
  for (double v : q0)
    CHECK(v == 0.0);
  const Vec3 th{0.1, -0.2, 0.2};
  const Mat3 q = rotation_minus_identity(th);
  Mat3 r = q;
  r[0] += 1.0;
  r[4] += 1.0;
  r[8] += 1.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
    {
      double rr = 0.0;
      for (int k = 0; k < 3; ++k)
        rr += r[3 * i + k] * r[3 * j + k];
      CHECK(std::abs(rr - (i == j ? 1.0 : 0.0)) < 1e-15);
    }
  const Vec3 qt = detail::mul(q, th);
  CHECK(norm(qt) < 1e-16);
  const Vec3 v{0.7, 0.1, -0.4}, rv = detail::mul(r, v), expect = rotate(th, v);
  for (int k = 0; k < 3; ++k)
    CHECK(std::abs(rv[k] - expect[k]) < 1e-15);
  // the force loop's four-number form of the same rotation: (R - I) v as the
  // matrix gives it, to round-off of |v| (1e-15; |theta| = 0.3, and 1e-7 in
  // the series branch), exactly zero for theta = 0
  for (const Vec3& t : {th, Vec3{1e-7, 3e-8, -2e-8}})
  {
    const Mat3 m = rotation_minus_identity(t), mq = rotation_minus_identity(step_rotation(t));
    const Vec3 a = rotation_minus_identity_times(step_rotation(t), v), b = detail::mul(m, v);
    for (int k = 0; k < 3; ++k)
      CHECK(std::abs(a[k] - b[k]) < 1e-15 * norm(v));
    for (int k = 0; k < 9; ++k)
      CHECK(std::abs(mq[k] - m[k]) < 1e-15);
  }
  for (double c : rotation_minus_identity_times(step_rotation({0.0, 0.0, 0.0}), v))
    CHECK(c == 0.0);
  // A stored force and a normal that do not change: trial_shear gives the
  // force back exactly, whatever the stiffness (the form P R (fs + K_s D n)
  // would leave K_s D eps ~ 1e-12 N here, from 1 - |n|^2 != 0).
  Vec3 n{0.3, -0.5, 0.8};
  const double ln = norm(n);
  for (auto& c : n)
    c /= ln;
  const double ks_d = 4e6 * 2.1e-3;
  const StepRotation none = step_rotation({0.0, 0.0, 0.0});
  const Vec3 zero = trial_shear({0.0, 0.0, 0.0}, n, n, rotation_minus_identity(none), none, 0.4, ks_d);
  for (double z : zero)
    CHECK(z == 0.0);
  // a tangential force is kept to round-off relative to itself (1e-15 of
  // |fs|), not to K_s D
  Vec3 fs{0.8, 0.0, -0.3}; // fs . n = 0
  const Vec3 kept = trial_shear(fs, n, n, rotation_minus_identity(none), none, 0.4, ks_d);
  for (int k = 0; k < 3; ++k)
    CHECK(std::abs(kept[k] - fs[k]) < 1e-15 * norm(fs));
}

TEST_CASE("strain-rate effect: the Malvar-Ross factor", "[dem][rate]")
{
  // fc = 48 MPa: delta = 1 / (1 + 8 x 4.8) = 1 / 39.4, beta = 10^(6 delta - 2)
  const double fc = 48e6, delta = 1.0 / 39.4, beta = std::pow(10.0, 6.0 * delta - 2.0);
  CHECK(malvar_ross_dif(1e-6, fc) == 1.0);
  CHECK(malvar_ross_dif(1e-9, fc) == 1.0);
  CHECK(malvar_ross_dif(-50.0, fc) == 1.0); // compression: no increase
  CHECK_THAT(malvar_ross_dif(1e-3, fc), WithinRel(std::pow(1e3, delta), 1e-14));
  CHECK_THAT(malvar_ross_dif(1.0, fc), WithinRel(std::pow(1e6, delta), 1e-14));
  CHECK_THAT(malvar_ross_dif(100.0, fc), WithinRel(beta * std::cbrt(1e8), 1e-14));
  // continuous at 1 /s (to the slope of the curve there)
  CHECK_THAT(malvar_ross_dif(1.0 + 1e-9, fc), WithinRel(malvar_ross_dif(1.0, fc), 1e-8));
  // the figures of the law for this concrete: 1.42 at 1 /s, 6.59 at 100 /s
  CHECK_THAT(malvar_ross_dif(1.0, fc), WithinAbs(1.42, 0.005));
  CHECK_THAT(malvar_ross_dif(100.0, fc), WithinAbs(6.59, 0.01));
}

TEST_CASE("strain-rate effect: a link pulled at several rates peaks at S T DIF", "[dem][rate]")
{
  // Two spheres, a held, b pulled along the link at V = rate x D_init: the
  // link's strain rate is exactly `rate` once the pull's ramp is over, so
  // its strength factor is DIF(rate) and the force peaks at S_int T DIF, the
  // elastic limit, before softening to rupture at (1 + zeta) of it. The
  // force is sampled at steps of V dt = delta_e / 2000: the peak is within
  // 1e-3 of the limit (the pull ramped in over the first 100 steps, the
  // link elastic and its factor that of the final rate). Without the rate
  // effect the peak is S_int T at every rate. The energy the link
  // dissipates is the law's at the raised strength (the factor is fixed
  // once the link softens).
  for (double rate : {0.5, 30.0, 1000.0})
    for (bool rated : {true, false})
    {
      Material m;
      m.micro = {0.2, 1.0, 1.0};
      m.rate_fc = rated ? 48e6 : 0.0;
      Particles p = make_particles(std::vector<double>{0, 0, 0, 2e-3, 0, 0}, std::vector<double>{1e-3, 1e-3},
                                   2400.0, 1.0);
      Links l = create_links(p, 1.01, m);
      REQUIRE(l.size() == 1);
      const double S = std::numbers::pi * 1e-6, dif = rated ? malvar_ross_dif(rate, 48e6) : 1.0;
      const double peak = S * m.tensile * dif, de = peak / l.kn[0], V = rate * l.d0[0];
      const double dt = de / 2000.0 / V, ramp = 100.0 * dt; // the pull ramped in over 100 steps
      DemSolver s(p, l, m, dt, 0.0, 1e-4);
      s.add_motion({"a", {0}, MotionKind::fixed, {true, true, true}, {}});
      s.add_motion({"b", {1}, MotionKind::velocity, {true, false, false},
                    [=](double t) { return V * std::min(1.0, t / ramp); }});
      s.start();
      double most = 0.0;
      while (l.state[0] == LinkState::intact)
      {
        s.step();
        most = std::max(most, -p.f[3]); // the link's pull on b, along -x
      }
      INFO("rate " << rate << " /s, " << (rated ? "with" : "without") << " the rate effect: peak " << most
                   << " N, S T DIF " << peak << " N");
      CHECK_THAT(most, WithinRel(peak, 1e-3));
      CHECK(l.state[0] == LinkState::broken_tension);
      if (rated)
        CHECK_THAT(l.strength[0], WithinRel(dif, 1e-12));
      // the link dissipated its fracture energy at the raised strength:
      // S T DIF delta_r / 2, delta_r = (1 + zeta) S T DIF / K_n (a factor
      // DIF^2 over the quasi-static one), to the sampling's 1e-3
      const DemEnergy e = s.energy();
      const double dr = (1.0 + m.zeta) * de;
      CHECK_THAT(e.softening + e.breakage, WithinRel(0.5 * peak * dr, 1e-3));
    }
}

TEST_CASE("compaction: the envelope, the set and the dissipation in closed form", "[dem][compaction]")
{
  const CompactionLaw c{0.01, 0.25, 0.05};
  CHECK(compaction_envelope(0.005, c) == 0.005);                              // elastic
  CHECK_THAT(compaction_envelope(0.03, c), WithinRel(0.01 + 0.25 * 0.02, 1e-14)); // collapsing
  CHECK_THAT(compaction_envelope(0.07, c), WithinRel(0.01 + 0.25 * 0.04 + 0.02, 1e-14)); // closed
  CHECK(compaction_set(0.008, 2e-3, c) == 0.0);
  CHECK_THAT(compaction_set(0.03, 2e-3, c), WithinRel(-2e-3 * (0.03 - 0.015), 1e-14));
  // the area between the envelope and the unloading line from e_max: for
  // e_max in the collapsing piece, the triangle (1 - stiffness) (e - onset)^2 / 2
  // scaled by the stiffness... written out: integral 0.00005 + (0.01 + 0.015) / 2
  // x 0.02 = 0.0003, less 0.015^2 / 2 = 0.0001125: 0.0001875 K_n D_init^2
  CHECK_THAT(compaction_dissipation(0.03, 1e7, 2e-3, c), WithinRel(1.875e-4 * 1e7 * 4e-6, 1e-12));
  CHECK(compaction_dissipation(0.009, 1e7, 2e-3, c) == 0.0);
}

TEST_CASE("compaction: a link crushed, unloaded and pulled follows the law, its energy closed",
          "[dem][compaction]")
{
  // Two spheres, a held, b moved quasi-statically (positions set, forces
  // computed): compressed past the onset into the collapsing range, back to
  // zero force, past the lock, unloaded, then pulled to rupture. The force
  // is the law's at every point: the envelope while the strain is the
  // largest yet, the elastic line from the set below it, and the tension
  // law counted from the set. The work done on the link, summed by the
  // trapezoidal rule over steps of 1e-4 of the elastic range, equals what
  // it stores plus what compaction, softening and breakage dissipated (the
  // rule is exact on the law's straight pieces: to 1e-6).
  Material m;
  m.micro = {0.2, 1.0, 1.0};
  m.compaction = {0.002, 0.3, 0.01};
  Particles p = make_particles(std::vector<double>{0, 0, 0, 2e-3, 0, 0}, std::vector<double>{1e-3, 1e-3}, 2400.0, 1.0);
  Links l = create_links(p, 1.01, m);
  REQUIRE(l.size() == 1);
  l.compaction.assign(1, 0.0); // as DemSolver sizes it
  NeighbourList nl(1e-4);
  ForceCounters counters;
  const double d0 = l.d0[0], kn = l.kn[0];
  const LinkLaw law = m.law(1e-3, 1e-3, d0);
  double work = 0.0, x_prev = p.x[3], f_prev = 0.0;
  auto move_to = [&](double strain) // compressive strain > 0
  {
    p.x[3] = d0 * (1.0 - strain);
    std::fill(p.f.begin(), p.f.end(), 0.0);
    nl.update(p.x, p.r, l);
    compute_forces(p, l, nl, m, 0.0, counters);
    const double f = p.f[3]; // on b along +x: > 0 pushes b away (compression)
    work += -0.5 * (f + f_prev) * (p.x[3] - x_prev);
    x_prev = p.x[3];
    f_prev = f;
    return f;
  };
  auto walk = [&](double from, double to, int n)
  {
    double f = 0.0;
    for (int k = 1; k <= n; ++k)
      f = move_to(from + (to - from) * k / n);
    return f;
  };
  // to e = 0.006 (collapsing): on the envelope
  double f = walk(0.0, 0.006, 6000);
  CHECK_THAT(f, WithinRel(kn * d0 * compaction_envelope(0.006, m.compaction), 1e-9));
  // back to the set: zero force there, elastic on the way
  const double set = compaction_set(0.006, d0, m.compaction); // < 0
  f = walk(0.006, -set / d0, 6000);
  CHECK_THAT(f, WithinAbs(0.0, 1e-9 * kn * d0 * 0.006));
  // reloaded past the lock (the envelope again above 0.006), unloaded to 0.015
  walk(-set / d0, 0.02, 20000);
  f = walk(0.02, 0.015, 5000);
  CHECK_THAT(f, WithinRel(kn * d0 * (compaction_envelope(0.02, m.compaction) - 0.005), 1e-9));
  // pulled: tension from the new set, peak S T, rupture at (1 + zeta) delta_e
  const double set2 = compaction_set(0.02, d0, m.compaction), de = law.s_int * law.tensile / kn;
  walk(0.015, -(set2 + de) / d0, 20000);
  CHECK_THAT(-p.f[3], WithinRel(law.s_int * law.tensile, 1e-6));
  walk(-(set2 + de) / d0, -(set2 + (1.0 + m.zeta) * de) / d0 - 1e-6, 20000);
  CHECK(l.state[0] == LinkState::broken_tension);
  const double stored = elastic_energy(p, l, nl, m), compaction = compaction_energy(l, m);
  const double softening = softening_energy(p, l, m);
  INFO("work " << work << " J, compaction " << compaction << " J, softening " << softening << " J, breakage "
               << counters.breakage << " J, stored " << stored << " J");
  CHECK_THAT(compaction, WithinRel(compaction_dissipation(0.02, kn, d0, m.compaction), 1e-12));
  CHECK_THAT(stored + compaction + softening + counters.breakage, WithinRel(work, 1e-6));
}

TEST_CASE("compaction under a pressure gate: elastic below it, then from the strain it opened at",
          "[dem][compaction]")
{
  // The pair of the test above, gated at the pressure its spheres have at
  // a compressive strain of 0.004 (twice the onset): from the virial, each
  // sphere's p = -rho F_n D / (6 m) = rho K_n D_init e D / (6 m). Below it
  // the link stays elastic, its onset following its strain; from it on it
  // compacts from that strain, with the law's stiffness ratio, the force
  // continuous (no step larger than an elastic step's). Unloaded to zero
  // force, the work equals what it stores plus the compaction's dissipation
  // from its own onset (to 1e-6, as above). Gated above the pressure the
  // walk reaches, the link stays elastic throughout.
  Material m;
  m.micro = {0.2, 1.0, 1.0};
  Particles p = make_particles(std::vector<double>{0, 0, 0, 2e-3, 0, 0}, std::vector<double>{1e-3, 1e-3}, 2400.0, 1.0);
  const Links l0 = create_links(p, 1.01, m);
  REQUIRE(l0.size() == 1);
  const double d0 = l0.d0[0], kn = l0.kn[0], e_gate = 0.004;
  auto pressure = [&](double e) { return m.density * kn * d0 * e * d0 * (1.0 - e) / (6.0 * p.m[0]); };
  REQUIRE(p.m[0] == p.m[1]);
  auto run = [&](double gate, double to, std::vector<double>& forces, double& work, Links& l)
  {
    m.compaction = {0.002, 0.3, 0.01, gate};
    l = l0;
    l.compaction.assign(1, 0.0); // as DemSolver sizes them
    l.compaction_onset.assign(1, m.compaction.onset);
    Particles q = p;
    NeighbourList nl(1e-4);
    ForceCounters counters;
    double x_prev = q.x[3], f_prev = 0.0;
    work = 0.0;
    const int n = 6000;
    for (int k = 1; k <= 2 * n; ++k)
    {
      // to `to`, then back to the set: zero force
      const double e = k <= n ? to * k / n : to - (to + compaction_set(l.compaction[0], d0, link_compaction(l, 0, m.compaction)) / d0) * (k - n) / n;
      q.x[3] = d0 * (1.0 - e);
      std::fill(q.f.begin(), q.f.end(), 0.0);
      nl.update(q.x, q.r, l);
      compute_forces(q, l, nl, m, 0.0, counters);
      work += -0.5 * (q.f[3] + f_prev) * (q.x[3] - x_prev);
      x_prev = q.x[3];
      f_prev = q.f[3];
      forces.push_back(q.f[3]);
    }
  };
  std::vector<double> f;
  double work = 0.0;
  Links l;
  run(pressure(e_gate), 0.006, f, work, l);
  // opened within one step of 1e-6 of the gate's strain
  CHECK_THAT(l.compaction_onset[0], WithinAbs(e_gate, 1.1e-6));
  // at 0.006: compacting from there, on the shifted envelope
  CHECK_THAT(f[5999], WithinRel(kn * d0 * (e_gate + 0.3 * (0.006 - e_gate)), 1e-3));
  CHECK_THAT(f[2999], WithinRel(kn * d0 * 0.003, 1e-9)); // elastic below the gate, past the onset (step 3000)
  double largest = 0.0;
  for (int k = 1; k < 6000; ++k)
    largest = std::max(largest, std::abs(f[k] - f[k - 1]));
  CHECK(largest <= 1.001 * kn * d0 * 1e-6);
  CHECK_THAT(f.back(), WithinAbs(0.0, 1e-9 * kn * d0 * 0.006));
  CHECK(compaction_energy(l, m) > 0.0);
  CHECK_THAT(compaction_energy(l, m),
             WithinRel(compaction_dissipation(0.006, kn, d0, m.compaction.from(l.compaction_onset[0])), 1e-12));
  // (at zero force nothing is stored: the work is the dissipation)
  CHECK_THAT(work, WithinRel(compaction_energy(l, m), 1e-6));
  // gated above the walk's pressure: elastic throughout
  f.clear();
  run(2.0 * pressure(0.006), 0.006, f, work, l);
  CHECK_THAT(l.compaction_onset[0], WithinRel(0.006, 1e-9)); // (the strain from the positions, to round-off)
  CHECK_THAT(f[5999], WithinRel(kn * d0 * 0.006, 1e-9));
  CHECK(compaction_energy(l, m) == 0.0);
}

TEST_CASE("compaction: a DE sample in hydrostatic compression follows the law's curve", "[dem][compaction]")
{
  // A bonded packing compressed by an affine field x = (1 - e) x0 (every
  // link then has the compressive strain e, and no shear), loaded past the
  // onset into the collapsing range and unloaded. Its pressure, from the
  // virial p = -sum(x . f) / (3 V), is the elastic sample's times the
  // law's envelope over e while loading, and times (envelope(e_max) - (e_max
  // - e)) / e while unloading: the sample's curve is the link's, to
  // round-off. (No unbonded pair comes into contact: lambda > 1.3 and e <=
  // 1 %.) This checks the law through the whole assembly: every link's
  // history, the set, the sums.
  const Region box = box_region({0, 0, 0}, {0.02, 0.02, 0.02});
  PackingOptions po;
  po.mean_radius = 1.5e-3;
  const Packing pk = generate_packing(box, po);
  Material m;
  m.micro = {0.2, 1.0, 1.0};
  m.tensile = m.cohesion = 1e12; // the links hold: only compression is looked at
  const CompactionLaw c{0.002, 0.3, 0.05};
  auto pressure_at = [&](const std::vector<double>& strains, bool compacting)
  {
    Material mc = m;
    if (compacting)
      mc.compaction = c;
    Particles p = make_particles(pk.x, pk.r, 2400.0, 0.6);
    Links l = create_links(p, 1.35, mc);
    if (compacting)
      l.compaction.assign(l.size(), 0.0);
    const std::vector<double> x0 = p.x;
    NeighbourList nl(1e-4);
    ForceCounters counters;
    std::vector<double> out;
    for (double e : strains)
    {
      for (std::size_t q = 0; q < x0.size(); ++q)
        p.x[q] = (1.0 - e) * x0[q];
      std::fill(p.f.begin(), p.f.end(), 0.0);
      nl.update(p.x, p.r, l);
      compute_forces(p, l, nl, mc, 0.0, counters);
      double virial = 0.0;
      for (std::size_t q = 0; q < p.x.size(); ++q)
        virial += p.x[q] * p.f[q];
      out.push_back(virial / (3.0 * box.volume));
      CHECK(counters.friction == 0.0);
    }
    return out;
  };
  std::vector<double> strains;
  for (int k = 1; k <= 10; ++k)
    strains.push_back(0.001 * k); // to 5 x the onset
  for (int k = 1; k <= 4; ++k)
    strains.push_back(0.01 - 0.001 * k); // unloading
  const auto elastic = pressure_at(strains, false), compacted = pressure_at(strains, true);
  const double e_max = 0.01, g_max = compaction_envelope(e_max, c);
  for (std::size_t k = 0; k < strains.size(); ++k)
  {
    const double e = strains[k];
    const double g = k < 10 ? compaction_envelope(e, c) : g_max - (e_max - e);
    INFO("strain " << e << ": " << compacted[k] << " Pa, elastic " << elastic[k] << " Pa");
    CHECK(elastic[k] > 0.0);
    CHECK_THAT(compacted[k], WithinRel(elastic[k] * g / e, 1e-9));
  }
}

TEST_CASE("strain-rate effect: the factor stops growing at the rate cap", "[dem][rate]")
{
  // The pull of the test above at 1000 /s with the cap at 100 /s: the link
  // peaks at S T DIF(100 /s), within the sampling's 1e-3.
  Material m;
  m.micro = {0.2, 1.0, 1.0};
  m.rate_fc = 48e6;
  m.rate_max = 100.0;
  Particles p = make_particles(std::vector<double>{0, 0, 0, 2e-3, 0, 0}, std::vector<double>{1e-3, 1e-3}, 2400.0, 1.0);
  Links l = create_links(p, 1.01, m);
  const double dif = malvar_ross_dif(100.0, 48e6), peak = std::numbers::pi * 1e-6 * m.tensile * dif;
  const double V = 1000.0 * l.d0[0], dt = peak / l.kn[0] / 2000.0 / V, ramp = 100.0 * dt;
  DemSolver s(p, l, m, dt, 0.0, 1e-4);
  s.add_motion({"a", {0}, MotionKind::fixed, {true, true, true}, {}});
  s.add_motion({"b", {1}, MotionKind::velocity, {true, false, false}, [=](double t) { return V * std::min(1.0, t / ramp); }});
  s.start();
  double most = 0.0;
  while (l.state[0] == LinkState::intact)
  {
    s.step();
    most = std::max(most, -p.f[3]);
  }
  CHECK_THAT(l.strength[0], WithinRel(dif, 1e-12));
  CHECK_THAT(most, WithinRel(peak, 1e-3));
}

TEST_CASE("strain-rate effect: with rate_current the factor follows the current rate, floored at what the link holds",
          "[dem][rate]")
{
  // A link pulled at 100 /s to half its strength there (force F1 = S T
  // DIF(100 /s) / 2), then at 0.01 /s. Keeping the largest factor
  // (rate_current false) it stays at DIF(100 /s) and the link elastic. With
  // rate_current the factor falls to what the link holds, F1 / (S T) (above
  // DIF(0.01 /s) = 1.26), so the link softens at the first slow step with its
  // strength F1: its largest force is F1 to within that step's increment
  // (1e-6 of F1), and its factor F1 / (S T) to round-off.
  for (const bool current : {false, true})
  {
    Material m;
    m.micro = {0.2, 1.0, 1.0};
    m.rate_fc = 48e6;
    m.rate_current = current;
    Particles p = make_particles(std::vector<double>{0, 0, 0, 2e-3, 0, 0}, std::vector<double>{1e-3, 1e-3}, 2400.0, 1.0);
    Links l = create_links(p, 1.01, m);
    const double s_t = std::numbers::pi * 1e-6 * m.tensile, dif = malvar_ross_dif(100.0, 48e6);
    const double fast = 100.0 * l.d0[0], slow = 0.01 * l.d0[0];
    const double dt = 0.5 * s_t * dif / l.kn[0] / 2000.0 / fast; // 1000 steps to F1
    bool slowed = false;
    DemSolver s(p, l, m, dt, 0.0, 1e-4);
    s.add_motion({"a", {0}, MotionKind::fixed, {true, true, true}, {}});
    s.add_motion({"b", {1}, MotionKind::velocity, {true, false, false}, [&](double) { return slowed ? slow : fast; }});
    s.start();
    while (l.delta_max[0] * l.kn[0] < 0.5 * s_t * dif)
      s.step();
    INFO("rate_current " << current);
    CHECK_THAT(l.strength[0], WithinRel(dif, 1e-12));
    const double f1 = l.delta_max[0] * l.kn[0];
    slowed = true;
    double most = 0.0;
    for (int n = 0; n < 20; ++n)
    {
      s.step();
      most = std::max(most, -p.f[3]);
    }
    const bool softened = l.delta_max[0] * l.kn[0] > s_t * l.strength[0];
    CHECK(softened == current);
    if (current)
    {
      CHECK_THAT(l.strength[0], WithinRel(f1 / s_t, 1e-12));
      CHECK(l.strength[0] > malvar_ross_dif(0.01, 48e6));
      CHECK_THAT(most, WithinRel(f1, 1e-5));
    }
    else
      CHECK_THAT(l.strength[0], WithinRel(dif, 1e-12));
  }
}

TEST_CASE("strain-rate effect: the factor raises C0 too, or T alone (rate_cohesion false)", "[dem][rate]")
{
  // A link at its initial distance (no normal force) whose stored shear
  // force is 1.5 S C0, with a strength factor of 3 (as a fast pull leaves
  // it). Its Mohr-Coulomb cap is S C0 times the factor, 3 S C0, when the
  // factor raises C0: the link holds; S C0 when it raises T alone: the link
  // breaks in shear. Closed form: the caps differ by the factor, 3.
  for (const bool cohesion : {true, false})
  {
    Material m;
    m.micro = {0.2, 1.0, 1.0};
    m.rate_fc = 48e6;
    m.rate_cohesion = cohesion;
    Particles p = make_particles(std::vector<double>{0, 0, 0, 2e-3, 0, 0}, std::vector<double>{1e-3, 1e-3}, 2400.0, 1.0);
    Links l = create_links(p, 1.01, m);
    REQUIRE(l.size() == 1);
    l.strength.assign(1, 3.0);
    l.fs[1] = 1.5 * std::numbers::pi * 1e-6 * m.cohesion; // along y, normal to the link
    NeighbourList nl(1e-4);
    nl.update(p.x, p.r, l);
    ForceCounters counters;
    compute_forces(p, l, nl, m, 0.0, counters);
    INFO("rate_cohesion " << cohesion);
    CHECK((l.state[0] == LinkState::intact) == cohesion);
    if (cohesion)
      CHECK_THAT(p.f[4], WithinRel(l.fs[1], 1e-12)); // the stored force, on b
  }
}

TEST_CASE("strain-rate effect: the factor follows the link's rate through the low-pass filter", "[dem][rate]")
{
  // A link pulled at a constant 100 /s from the first step (sphere b at 0.2
  // m/s, a held), the filter's weight a = dt / tau = 0.05: after n steps
  // the filtered rate is 100 (1 - (1 - a)^n) /s and the factor DIF of it
  // (it only grows), to round-off. The link stays elastic (its elongation
  // after 60 steps is half its elastic limit).
  Material m;
  m.micro = {0.2, 1.0, 1.0};
  m.rate_fc = 48e6;
  const double dt = 1e-8, a = 0.05;
  m.rate_filter = dt / a;
  Particles p = make_particles(std::vector<double>{0, 0, 0, 2e-3, 0, 0}, std::vector<double>{1e-3, 1e-3}, 2400.0, 1.0);
  Links l = create_links(p, 1.01, m);
  const double V = 100.0 * l.d0[0];
  DemSolver s(p, l, m, dt, 0.0, 1e-4);
  s.add_motion({"a", {0}, MotionKind::fixed, {true, true, true}, {}});
  s.add_motion({"b", {1}, MotionKind::velocity, {true, false, false}, [=](double) { return V; }});
  s.start();
  REQUIRE(l.rate.size() == 1);
  for (int n = 1; n <= 60; ++n)
  {
    s.step();
    const double rf = 100.0 * (1.0 - std::pow(1.0 - a, n));
    INFO("step " << n);
    REQUIRE_THAT(l.rate[0], WithinRel(rf, 1e-9));
    REQUIRE_THAT(l.strength[0], WithinRel(malvar_ross_dif(rf, 48e6), 1e-9));
  }
  CHECK(l.state[0] == LinkState::intact);
  CHECK(l.delta_max[0] * l.kn[0] < 0.6 * std::numbers::pi * 1e-6 * m.tensile);
  // without the filter the factor is DIF(100 /s) from the first step
  m.rate_filter = 0.0;
  Particles q = make_particles(std::vector<double>{0, 0, 0, 2e-3, 0, 0}, std::vector<double>{1e-3, 1e-3}, 2400.0, 1.0);
  Links k = create_links(q, 1.01, m);
  DemSolver u(q, k, m, dt, 0.0, 1e-4);
  u.add_motion({"a", {0}, MotionKind::fixed, {true, true, true}, {}});
  u.add_motion({"b", {1}, MotionKind::velocity, {true, false, false}, [=](double) { return V; }});
  u.start();
  u.step();
  CHECK(k.rate.empty());
  CHECK_THAT(k.strength[0], WithinRel(malvar_ross_dif(100.0, 48e6), 1e-9));
}

TEST_CASE("strain-rate effect: with rate_mean_tension the factor grows only where the spheres are stretched",
          "[dem][rate]")
{
  // Four spheres in a row, C - A - B - D, linked to their neighbours. B
  // moves away from A at 100 /s of the link's length and A-B is stretched
  // by 1e-8 m; the A-B link holds a factor of 3 from an earlier fast pull,
  // but has never been stretched (delta_max 0: it holds nothing). With C
  // and D pushed 0.1 mm in (their links compressed far more than A-B is
  // stretched) A's and B's sums of K_n (D - D_init) D are negative: the
  // gated factor stays 3 (it falls to 1 following the current rate,
  // rate_current), the ungated one is DIF(100 /s) = 6.59. With C and D in
  // place the sums are positive and the gated factor is DIF(100 /s) too.
  for (const bool pushed : {true, false})
    for (const bool gate : {true, false})
      for (const bool current : {false, true})
      {
        Material m;
        m.micro = {0.2, 1.0, 1.0};
        m.rate_fc = 48e6;
        m.rate_mean_tension = gate;
        m.rate_current = current;
        Particles p = make_particles(std::vector<double>{-2e-3, 0, 0, 0, 0, 0, 2e-3, 0, 0, 4e-3, 0, 0},
                                     std::vector<double>{1e-3, 1e-3, 1e-3, 1e-3}, 2400.0, 1.0);
        Links l = create_links(p, 1.01, m);
        REQUIRE(l.size() == 3);
        l.strength.assign(3, 3.0);
        const double shift = pushed ? 1e-4 : 0.0;
        p.x[0] += shift;     // C
        p.x[6] += 1e-8;      // B
        p.x[9] -= shift;     // D
        p.v[6] = 0.2;        // B: 100 /s over D_init = 2 mm
        NeighbourList nl(1e-4);
        nl.update(p.x, p.r, l);
        ForceCounters counters;
        compute_forces(p, l, nl, m, 1e-9, counters);
        // the A-B link: the one between spheres 1 and 2
        std::size_t ab = 0;
        while (!(l.a[ab] == 1 && l.b[ab] == 2))
          ++ab;
        INFO("pushed " << pushed << ", gate " << gate << ", rate_current " << current);
        const double expected = gate && pushed ? (current ? 1.0 : 3.0) : malvar_ross_dif(100.0, 48e6);
        CHECK_THAT(l.strength[ab], WithinRel(expected, 1e-9));
      }
}

TEST_CASE("material file: the optional impact keys round trip, absent ones stay off", "[dem][law]")
{
  const auto dir = std::filesystem::temp_directory_path() / "dembridge_material_keys";
  std::filesystem::create_directories(dir);
  MaterialFile m;
  m.material.rate_fc = 48e6;
  m.material.rate_max = 100.0;
  m.material.contact_shear_limit = 1.68e8;
  m.material.rolling_friction = 0.15;
  m.material.rate_cohesion = false;
  m.material.rate_filter = 2e-6;
  m.material.rate_mean_tension = true;
  m.material.rate_current = true;
  m.material.compaction = {0.003, 0.5, 0.033};
  write_material(dir / "on.json", m);
  const Material a = read_material(dir / "on.json").material;
  CHECK(a.rate_fc == 48e6);
  CHECK(a.rate_max == 100.0);
  CHECK(a.contact_shear_limit == 1.68e8);
  CHECK(a.rolling_friction == 0.15);
  CHECK(!a.rate_cohesion);
  CHECK(a.rate_filter == 2e-6);
  CHECK(a.rate_mean_tension);
  CHECK(a.rate_current);
  CHECK(a.compaction.lock == 0.033);
  write_material(dir / "off.json", MaterialFile{});
  const Material b = read_material(dir / "off.json").material;
  CHECK(b.rate_fc == 0.0);
  CHECK(b.contact_shear_limit == 0.0);
  CHECK(b.rolling_friction == 0.0);
  CHECK(b.rate_cohesion);
  CHECK(b.rate_filter == 0.0);
  CHECK(!b.rate_mean_tension);
  CHECK(!b.rate_current);
  CHECK(!b.compaction.on());
  // the limit checked like every parameter
  m.material.contact_shear_limit = -1.0;
  CHECK_THROWS_WITH(m.material.validate(), Catch::Matchers::Contains("contacts' shear limit"));
  m.material.contact_shear_limit = 0.0;
  m.material.rolling_friction = -0.1;
  CHECK_THROWS_WITH(m.material.validate(), Catch::Matchers::Contains("rolling friction mu_r"));
}
