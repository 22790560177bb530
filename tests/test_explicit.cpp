// The explicit integrator on spring-mass systems with closed-form solutions.
#include "dembridge/shell/explicit.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <filesystem>
#include <memory>
#include <unistd.h>

using namespace dembridge::shell;
using Catch::Matchers::WithinRel;

namespace
{
// Chain of n equal masses m and springs k, first spring to the ground.
InternalForceFn chain(double k)
{
  return [k](std::span<const double> u, std::span<double> f)
  {
    const std::size_t n = u.size();
    for (std::size_t i = 0; i < n; ++i)
    {
      const double left = i == 0 ? u[i] : u[i] - u[i - 1];
      const double right = i + 1 < n ? u[i] - u[i + 1] : 0.0;
      f[i] = k * (left + right);
    }
  };
}
} // namespace

TEST_CASE("single oscillator: central differences match the discrete closed form", "[explicit]")
{
  // x(t) = cos(w~ t) with the central-difference frequency
  // w~ = (2/dt) asin(w dt / 2): the scheme's exact solution (to round-off).
  const double m = 2.0, k = 800.0, w = std::sqrt(k / m), dt = 0.05;
  ExplicitSolver s({m}, chain(k), dt);
  std::vector<double> u0{1.0}, v0{0.0};
  s.set_state(u0, v0);
  const double wd = 2.0 / dt * std::asin(w * dt / 2.0);
  for (int i = 0; i < 200; ++i)
    s.step();
  CHECK(std::abs(s.u()[0] - std::cos(wd * s.time())) < 1e-10);
  // Energy of an undamped oscillator oscillates by O((w dt)^2 / 4) only.
  const auto e = s.energy();
  CHECK(std::abs(e.kinetic + e.strain - e.initial) < 0.25 * w * w * dt * dt * e.initial);
}

TEST_CASE("damping: mass-proportional damping decays as exp(-c t / 2)", "[explicit]")
{
  // Underdamped oscillator. The explicit damping force uses the half-step
  // velocity, a lag of dt/2 that shifts the frequency by about c dt / 4; with
  // the (w dt)^2 / 24 period error of central differences the phase error
  // after time t is w t (c dt / 4 + (w dt)^2 / 24). Bound: twice that, times
  // the envelope exp(-c t / 2).
  const double m = 1.0, k = 100.0, c = 0.4, dt = 1e-4, w = std::sqrt(k / m);
  ExplicitSolver s({m}, chain(k), dt, c);
  std::vector<double> u0{1.0}, v0{0.0};
  s.set_state(u0, v0);
  const double wd = std::sqrt(k / m - c * c / 4.0);
  while (s.time() < 10.0)
    s.step();
  const double t = s.time(), env = std::exp(-c * t / 2.0);
  const double exact = env * (std::cos(wd * t) + c / (2.0 * wd) * std::sin(wd * t));
  const double phase = w * t * (c * dt / 4.0 + w * w * dt * dt / 24.0);
  CHECK(std::abs(s.u()[0] - exact) < 2.0 * phase * env);
  // The dissipated energy closes the balance to the same order.
  const auto e = s.energy();
  CHECK(std::abs(e.imbalance()) < 2.0 * c * dt * e.initial);
}

TEST_CASE("prescribed velocity: reaction work equals the energy put in", "[explicit]")
{
  // Chain of 3 masses, the last dof pulled at constant velocity: the work of
  // the reaction equals kinetic + strain energy (no damping), to O(dt^2).
  ExplicitSolver s({1.0, 1.0, 1.0}, chain(1e4), 1e-4);
  s.add_motion({"pull", {2}, MotionKind::velocity, [](double) { return 0.01; }});
  std::vector<double> z(3, 0.0);
  s.set_state(z, z);
  for (int i = 0; i < 20000; ++i)
    s.step();
  CHECK_THAT(s.u()[2], WithinRel(0.01 * s.time(), 1e-12));
  const auto e = s.energy();
  REQUIRE(e.prescribed_work > 0.0);
  CHECK(std::abs(e.imbalance()) < 1e-3 * e.prescribed_work);
}

TEST_CASE("loads: work of a constant force", "[explicit]")
{
  // Constant force F on a spring from rest: static deflection F/k, peak 2F/k,
  // and the external work equals kinetic + strain.
  const double k = 100.0, F = 3.0;
  ExplicitSolver s({1.0}, chain(k), 1e-3);
  s.add_load({"F", {0}, {1.0}, [F](double) { return F; }});
  std::vector<double> z(1, 0.0);
  s.set_state(z, z);
  double peak = 0.0;
  while (s.time() < 1.0)
  {
    s.step();
    peak = std::max(peak, s.u()[0]);
  }
  CHECK_THAT(peak, WithinRel(2.0 * F / k, 1e-3));
  const auto e = s.energy();
  CHECK(std::abs(e.imbalance()) < 1e-4 * e.external_work);
}

TEST_CASE("power iteration: largest eigenvalue of a spring chain", "[explicit]")
{
  // Fixed-free chain of n masses: lambda_j = 4 k/m sin^2((2j-1) pi / (2(2n+1))).
  const int n = 40;
  const double k = 1e6, m = 2.0;
  const double exact = 4.0 * k / m
                       * std::pow(std::sin((2.0 * n - 1.0) * std::numbers::pi / (2.0 * (2 * n + 1))), 2);
  std::vector<double> mass(n, m);
  const double l = dembridge::core::max_eigenvalue(mass, chain(k), 1e-10, 100000);
  // The Rayleigh quotient approaches lambda_max from below; the top two
  // eigenvalues of the chain are close, so allow 1e-3.
  CHECK(l <= exact * (1 + 1e-12));
  CHECK_THAT(l, WithinRel(exact, 1e-3));
}

TEST_CASE("non-finite state stops the run with a message", "[explicit][errors]")
{
  // A step far above the critical 2/w makes the oscillator blow up (the
  // energy guard, which would stop it first, off).
  ExplicitSolver s({1.0}, chain(1e4), 0.1);
  s.set_energy_guard(0.0);
  std::vector<double> u0{1.0}, v0{0.0};
  s.set_state(u0, v0);
  CHECK_THROWS_WITH(
      [&] { for (int i = 0; i < 100000; ++i) s.step(); }(),
      Catch::Contains("non-finite") && Catch::Contains("dof 0"));
}

TEST_CASE("energy guard: an unstable run stops on its energy, before any NaN", "[explicit][errors]")
{
  // omega dt = 2.04, just above the limit 2: the oscillator's amplitude grows
  // by about 1.2 a step, and its energy is not explained by any work. The
  // guard (margin 0.5, every 100 steps) stops it at its first check; below
  // the limit (omega dt = 1.96) the energy oscillates by O((omega dt)^2) of
  // itself, within the margin, and 10,000 steps run.
  const double k = 1e4, w = std::sqrt(k);
  for (double wdt : {1.96, 2.04})
  {
    ExplicitSolver s({1.0}, chain(k), wdt / w);
    std::vector<double> u0{1.0}, v0{0.0};
    s.set_state(u0, v0);
    auto run = [&] { for (int i = 0; i < 10000; ++i) s.step(); };
    if (wdt < 2.0)
      CHECK_NOTHROW(run());
    else
    {
      CHECK_THROWS_WITH(run(), Catch::Contains("energy grows without cause") && Catch::Contains("step 100"));
      CHECK(std::isfinite(s.u()[0]));
    }
  }
  CHECK_THROWS_WITH(ExplicitSolver({1.0}, chain(k), 1e-3).set_energy_guard(-1.0), Catch::Contains("margin"));
}

TEST_CASE("selections: a region with no node is an error", "[explicit][errors]")
{
  std::vector<double> x{0, 0, 0, 1, 0, 0};
  CHECK_THROWS_WITH(select_nodes(x, [](const auto& p) { return p[0] > 5.0; }, "far end"),
                    Catch::Contains("far end") && Catch::Contains("no node"));
  CHECK(select_nodes(x, [](const auto& p) { return p[0] > 0.5; }, "end").size() == 1);
  std::vector<int> comps{0, 7};
  std::vector<std::int32_t> nodes{1};
  CHECK_THROWS_WITH(node_dofs(nodes, 6, comps), Catch::Contains("component 7"));
  CHECK_THROWS_WITH(ExplicitSolver({1.0}, chain(1.0), -1.0), Catch::Contains("time step"));
  CHECK_THROWS_WITH(ExplicitSolver({0.0}, chain(1.0), 1.0), Catch::Contains("mass"));
}

TEST_CASE("restart: a run continued from a checkpoint is the uninterrupted run bit for bit", "[explicit][restart]")
{
  // A damped chain of 6 masses: one end held, the other pulled at a varying
  // velocity, a sinusoidal load inside; 3,000 steps, or 1,234 then a
  // checkpoint, a new solver set up alike and 1,766 more.
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / ("dembridge-shell-restart-" + std::to_string(::getpid()) + ".h5");
  auto make = []
  {
    auto s = std::make_unique<ExplicitSolver>(std::vector<double>{1.0, 2.0, 1.5, 1.0, 3.0, 1.0}, chain(1e4), 1e-3, 0.7);
    s->add_motion({"held", {0}, MotionKind::fixed, {}});
    s->add_motion({"pull", {5}, MotionKind::velocity, [](double t) { return 0.01 * std::sin(3.0 * t); }});
    s->add_load({"F", {2, 3}, {1.0, -0.5}, [](double t) { return std::cos(7.0 * t); }});
    std::vector<double> u{0.0, 1e-3, -2e-3, 0.0, 1e-3, 0.0}, v(6, 0.0);
    s->set_state(u, v);
    return s;
  };
  const int total = 3000, at = 1234;
  auto whole = make();
  for (int k = 0; k < total; ++k)
    whole->step();
  {
    auto first = make();
    for (int k = 0; k < at; ++k)
      first->step();
    auto f = dembridge::checkpoint::File::create(file, "shell test");
    first->save(f.root().group("shell"));
    f.commit();
  }
  auto resumed = make();
  resumed->load(dembridge::checkpoint::File::open(file, "shell test").root().group("shell"));
  for (int k = at; k < total; ++k)
    resumed->step();
  // exact comparisons on purpose: a restart must be bit for bit
  CHECK(std::vector<double>(resumed->u().begin(), resumed->u().end())
        == std::vector<double>(whole->u().begin(), whole->u().end()));
  CHECK(std::vector<double>(resumed->v().begin(), resumed->v().end())
        == std::vector<double>(whole->v().begin(), whole->v().end()));
  CHECK(std::vector<double>(resumed->reactions().begin(), resumed->reactions().end())
        == std::vector<double>(whole->reactions().begin(), whole->reactions().end()));
  CHECK(resumed->time() == whole->time());
  CHECK(resumed->steps() == whole->steps());
  const auto a = whole->energy(), b = resumed->energy();
  CHECK(b.kinetic == a.kinetic);
  CHECK(b.damping == a.damping);
  CHECK(b.external_work == a.external_work);
  CHECK(b.prescribed_work == a.prescribed_work);
  // another set-up is refused, naming what differs
  ExplicitSolver other({1.0, 2.0, 1.5, 1.0, 3.0, 2.0}, chain(1e4), 1e-3, 0.7);
  other.add_motion({"held", {0}, MotionKind::fixed, {}});
  other.add_motion({"pull", {5}, MotionKind::velocity, [](double) { return 0.0; }});
  CHECK_THROWS_WITH(other.load(dembridge::checkpoint::File::open(file, "shell test").root().group("shell")),
                    Catch::Contains("/shell/mass: the lumped masses differ"));
  fs::remove(file);
}
