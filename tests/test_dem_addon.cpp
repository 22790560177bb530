// Add-ons of the DE step (addon.h): a tethered point mass plugged in from
// outside dem through DemSolver::add_addon. The two-body oscillator it makes
// with a sphere has a closed-form frequency; momentum and the energy budget
// must close with the add-on's terms; its fixed points are called in the
// documented order; its checkpoint group restarts bit for bit, and a restart
// with other add-ons is refused.
#include "dembridge/dem/addon.h"
#include "dembridge/dem/solver.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <memory>
#include <numbers>
#include <string>
#include <unistd.h>
#include <vector>

using namespace dembridge::dem;
using Catch::Contains;
using V3 = std::array<double, 3>;

namespace
{
/// A point mass tied to sphere 0 by a linear spring of zero rest length.
class Tether final : public AddOn
{
public:
  Tether(double mass, double stiffness, const V3& at, std::vector<std::string>* log = nullptr)
      : m(mass), k(stiffness), x(at), _log(log)
  {
  }
  std::string name() const override { return "tether"; }
  void start(const StepView& s) override
  {
    record("start");
    spring(s);
  }
  void begin(const StepView&) override { record("begin"); }
  void kick(const StepView& s, double h) override
  {
    record("kick");
    for (int i = 0; i < 3; ++i)
      v[i] += h * f[i] / m - s.damping * h * v[i];
  }
  double drift(const StepView& s) override
  {
    record("drift");
    double v2 = 0.0;
    for (int i = 0; i < 3; ++i)
    {
      x[i] += s.dt * v[i];
      v2 += v[i] * v[i];
    }
    return s.dt * s.damping * m * v2;
  }
  void forces(const StepView& s, DemEnergy&) override
  {
    record("forces");
    spring(s);
  }
  double reactions(const StepView&) override
  {
    record("reactions");
    return 0.0;
  }
  void check_finite(double, std::int64_t) const override { record("check_finite"); }
  void energy(const StepView& s, DemEnergy& e) const override
  {
    double d2 = 0.0, v2 = 0.0;
    for (int i = 0; i < 3; ++i)
    {
      const double d = s.p.x[i] - x[i];
      d2 += d * d;
      v2 += v[i] * v[i];
    }
    e.addons += 0.5 * m * v2 + 0.5 * k * d2;
  }
  void save(const dembridge::checkpoint::Group& g) const override
  {
    g.write("x", std::span<const double>(x.data(), 3));
    g.write("v", std::span<const double>(v.data(), 3));
    g.write("f", std::span<const double>(f.data(), 3));
  }
  void load(const dembridge::checkpoint::Group& g, const StepView&) override
  {
    g.read_exact("x", std::span<double>(x.data(), 3));
    g.read_exact("v", std::span<double>(v.data(), 3));
    g.read_exact("f", std::span<double>(f.data(), 3));
  }
  double m, k;
  V3 x, v{0, 0, 0}, f{0, 0, 0};

private:
  void spring(const StepView& s)
  {
    for (int i = 0; i < 3; ++i)
    {
      const double fi = k * (s.p.x[i] - x[i]);
      f[i] = fi;
      s.p.f[i] -= fi;
    }
  }
  void record(const char* what) const
  {
    if (_log)
      _log->push_back(what);
  }
  std::vector<std::string>* _log;
};

Material addon_concrete()
{
  Material m;
  m.micro = {0.2, 1.0, 1.0};
  return m;
}

constexpr double k_spring = 100.0; // N/m
constexpr double tether_mass = 2e-5;

struct TwoBody
{
  Particles p = make_particles(std::vector<double>{0, 0, 0}, std::vector<double>{1e-3}, 2400.0, 1.0);
  Material mat = addon_concrete();
  Links l;
  std::unique_ptr<DemSolver> s;
  Tether* tether = nullptr;
  double omega() const
  {
    const double mu = p.m[0] * tether_mass / (p.m[0] + tether_mass);
    return std::sqrt(k_spring / mu);
  }
  explicit TwoBody(bool with_tether = true, std::vector<std::string>* log = nullptr)
  {
    const double mu = p.m[0] * tether_mass / (p.m[0] + tether_mass);
    const double period = 2.0 * std::numbers::pi * std::sqrt(mu / k_spring);
    s = std::make_unique<DemSolver>(p, l, mat, period / 100.0, 0.0, 0.2e-3);
    if (with_tether)
      tether = static_cast<Tether*>(&s->add_addon(std::make_unique<Tether>(tether_mass, k_spring, V3{1e-3, 0, 0}, log)));
    s->start();
  }
};
} // namespace

TEST_CASE("add-on: a tethered mass oscillates at the two-body frequency, momentum and budget closed",
          "[dem][addon]")
{
  TwoBody b;
  const double e0 = b.s->energy().initial;
  // both at rest: the initial energy is the spring's, k (1 mm)^2 / 2
  CHECK(e0 == b.s->energy().addons);
  CHECK(std::abs(e0 / (0.5 * k_spring * 1e-6) - 1.0) < 1e-12);
  // relative displacement d = x_sphere - x_tether starts at -1 mm at rest:
  // d(t) = -A cos(omega t); its upward zero crossings are one period apart
  std::vector<double> crossings;
  double d_old = b.p.x[0] - b.tether->x[0], worst = 0.0, momentum = 0.0;
  for (int n = 0; n < 1000; ++n) // ten periods
  {
    b.s->step();
    const double d = b.p.x[0] - b.tether->x[0];
    if (d_old < 0.0 && d >= 0.0) // linear interpolation of the crossing
      crossings.push_back(b.s->time() - b.s->dt() * d / (d - d_old));
    d_old = d;
    worst = std::max(worst, std::abs(b.s->energy().imbalance()));
    momentum = std::max(momentum, std::abs(b.p.m[0] * b.p.v[0] + b.tether->m * b.tether->v[0]));
  }
  REQUIRE(crossings.size() >= 9);
  const double period = (crossings.back() - crossings.front()) / double(crossings.size() - 1);
  const double exact = 2.0 * std::numbers::pi / b.omega();
  // velocity Verlet's frequency error is (omega dt)^2 / 24 = 1.6e-4 at 100
  // steps per period; the crossings' interpolation is within that
  INFO("period " << period << " s, closed form " << exact << " s");
  CHECK(std::abs(period / exact - 1.0) < 1e-3);
  // the budget includes the add-on's kinetic and spring energy: Verlet's
  // energy error is bounded, about (omega dt)^2 / 4 = 1e-3 of the energy
  INFO("worst imbalance " << worst << " J of " << e0 << " J");
  CHECK(worst < 2e-3 * e0);
  // equal and opposite forces, both kicked by the same rule: the total
  // momentum stays zero to rounding (the scale: m v at 1 mm amplitude)
  const double scale = b.tether->m * b.omega() * 1e-3;
  CHECK(momentum < 1e-12 * scale);
}

TEST_CASE("add-on: its fixed points are called in the documented order", "[dem][addon]")
{
  std::vector<std::string> log;
  TwoBody b(true, &log);
  CHECK(log == std::vector<std::string>{"start"});
  log.clear();
  b.s->step();
  const std::vector<std::string> step{"begin", "kick", "drift", "forces", "reactions", "kick", "check_finite"};
  CHECK(log == step);
}

TEST_CASE("add-on: restart bit for bit; other add-ons or late ones refused", "[dem][addon][restart]")
{
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / ("dembridge-addon-" + std::to_string(::getpid()) + ".h5");
  TwoBody whole;
  for (int n = 0; n < 300; ++n)
    whole.s->step();
  {
    TwoBody first;
    for (int n = 0; n < 123; ++n)
      first.s->step();
    auto f = dembridge::checkpoint::File::create(file, "addon test");
    first.s->save(f.root().group("dem"));
    f.commit();
  }
  TwoBody resumed;
  resumed.s->load(dembridge::checkpoint::File::open(file, "addon test").root().group("dem"));
  for (int n = 123; n < 300; ++n)
    resumed.s->step();
  CHECK(resumed.p.x == whole.p.x);
  CHECK(resumed.p.v == whole.p.v);
  CHECK(resumed.tether->x == whole.tether->x);
  CHECK(resumed.tether->v == whole.tether->v);
  CHECK(resumed.s->energy().imbalance() == whole.s->energy().imbalance());

  TwoBody bare(false);
  CHECK_THROWS_WITH(bare.s->load(dembridge::checkpoint::File::open(file, "addon test").root().group("dem")),
                    Contains("add-ons") && Contains("[tether]") && Contains("[]"));
  fs::remove(file);

  CHECK_THROWS_WITH(whole.s->add_addon(std::make_unique<Tether>(1.0, 1.0, V3{0, 0, 0})),
                    Contains("'tether'") && Contains("before start()"));
  Particles p = make_particles(std::vector<double>{0, 0, 0}, std::vector<double>{1e-3}, 2400.0, 1.0);
  Links l;
  DemSolver s(p, l, addon_concrete(), 1e-7, 0.0, 0.2e-3);
  s.add_addon(std::make_unique<Tether>(1.0, 1.0, V3{0, 0, 0}));
  CHECK_THROWS_WITH(s.add_addon(std::make_unique<Tether>(1.0, 1.0, V3{0, 0, 0})), Contains("name is in use"));
  CHECK_THROWS_WITH(s.bar_reaction(0), Contains("bar node group 0"));
  CHECK_THROWS_WITH(s.body(0), Contains("rigid body 0") && Contains("has 0"));
}
