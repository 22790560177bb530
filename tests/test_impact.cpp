// The impact demo's parts: the scenario file, the crater measurement, the
// projectile's surface for output, and a short perforation.
#include "impact.h"
#include "scenario.h"

#include "dembridge/dem/body.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

using namespace dembridge;
using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;

namespace
{
std::filesystem::path write_file(const std::string& name, const std::string& text)
{
  const auto dir = std::filesystem::temp_directory_path() / "dembridge_test_impact";
  std::filesystem::create_directories(dir);
  const auto file = dir / name;
  std::ofstream(file) << text;
  return file;
}

const char* small_case = R"(
[scenario]
name = "t"
[target]
size_m = [0.05, 0.05]
thickness_m = 0.02
mean_radius_m = 2.5e-3
[projectile]
mass_kg = 0.02
diameter_m = 0.01
length_m = 0.04
velocity_m_s = 400.0
)";
} // namespace

TEST_CASE("scenario: keys read with their defaults, --set overrides, every key recorded", "[impact][scenario]")
{
  const auto file = write_file("ok.toml", small_case);
  const auto s = demo::read_scenario(file, {"projectile.velocity_m_s=600", "run.frames=3", "projectile.nose=conical"});
  CHECK(s.name == "t");
  CHECK(s.target.size == std::array<double, 2>{0.05, 0.05});
  CHECK(s.projectile.velocity == 600.0); // --set wins over the file
  CHECK(s.projectile.nose == "conical"); // a bare word is a string
  CHECK(s.run.frames == 3);
  CHECK(s.projectile.crh == 3.0);        // a default
  CHECK(s.resolved.at("projectile.velocity_m_s") == 600.0);
  CHECK(s.resolved.at("target.supports") == "sides");
  CHECK(s.resolved.contains("material.tensile_strength_pa"));
  // every key the --keys listing shows is recorded, and the other way round
  const std::string keys = demo::scenario_keys();
  for (const auto& [key, value] : s.resolved.items())
    CHECK_THAT(keys, Contains(key.substr(key.find('.') + 1) + " = "));
}

TEST_CASE("scenario: bad files and keys are refused, naming the key and what is allowed", "[impact][scenario][errors]")
{
  const auto file = write_file("bad.toml", small_case);
  auto refused = [&](const std::vector<std::string>& sets, const std::string& message)
  {
    INFO(message);
    CHECK_THROWS_WITH(demo::read_scenario(file, sets), Contains(message));
  };
  refused({"projectile.velocty_m_s=1"}, "unknown key 'projectile.velocty_m_s' ([projectile] takes: ");
  refused({"projectil.velocity_m_s=1"}, "unknown section or key 'projectil'");
  refused({"projectile.velocity_m_s=\"fast\""}, "projectile.velocity_m_s must be a number, not a string");
  refused({"projectile.velocity_m_s=0"}, "projectile.velocity_m_s = 0: allowed (0, 10000]");
  refused({"projectile.mass_kg=-1"}, "projectile.mass_kg = -1: allowed (0, 1000000]; 0 = from density_kg_m3");
  refused({"projectile.crh=0.4"}, "projectile.crh = 0.4: allowed [0.5, 1000)");
  refused({"projectile.nose=\"round\""}, "projectile.nose = \"round\": allowed flat | hemispherical | conical | ogive");
  refused({"target.size_m=[0.1]"}, "target.size_m must be an array of 2 numbers");
  refused({"run.frames=2.5"}, "run.frames must be an integer, not a number");
  refused({"velocity=1"}, "--set 'velocity=1': expected section.key=value");
  refused({"material.file=\"/no/such.json\""}, "material.file = \"/no/such.json\": ");
  const auto broken = write_file("syntax.toml", "[target]\nthickness_m = = 1\n");
  CHECK_THROWS_WITH(demo::read_scenario(broken), Contains("line 2"));
  CHECK_THROWS_WITH(demo::read_scenario("/no/such.toml"), Contains("/no/such.toml"));
}

TEST_CASE("projectile surface: closed, outward, its volume the shape's", "[impact][body]")
{
  // The divergence theorem on the triangles gives the enclosed volume,
  // positive only if every triangle faces outward; on a fine mesh it
  // converges to the exact volume (inscribed polygons: error ~ (pi/n)^2).
  for (auto nose : {dem::Nose::flat, dem::Nose::hemispherical, dem::Nose::conical, dem::Nose::ogive})
  {
    dem::Shape s;
    s.diameter = 0.02;
    s.length = 0.1;
    s.nose = nose;
    const auto m = dem::body_surface(s, 200, 256);
    double v = 0.0;
    for (std::size_t t = 0; t < m.triangles.size(); t += 3)
    {
      const double* a = &m.x[3 * m.triangles[t]];
      const double* b = &m.x[3 * m.triangles[t + 1]];
      const double* c = &m.x[3 * m.triangles[t + 2]];
      v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
    }
    INFO("nose " << static_cast<int>(nose));
    CHECK_THAT(v, WithinRel(s.volume(), 3e-4));
  }
}

TEST_CASE("craters: the equivalent diameters, depths and masses of detached layers", "[impact]")
{
  // A cubic lattice of spacing h (fraction pi/6): the front crater a
  // cylinder of radius 20 h three layers deep, then a tunnel of radius 2 h,
  // the rear scab of radius 15 h two layers deep. The equivalent diameter
  // of a disc of lattice points is its own within the lattice's
  // resolution (the points of a disc of radius 20 h fill it to ~1 %).
  const double h = 1e-3;
  const int n = 60, layers = 12;
  demo::CraterInput in;
  in.thickness = layers * h;
  in.layer = h;
  in.fraction = std::numbers::pi / 6.0;
  in.tunnel = 2.0 * 6.0 * h; // twice a projectile of diameter 6 h
  double front_mass = 0.0, rear_mass = 0.0;
  for (int k = 0; k < layers; ++k)
    for (int i = -n; i <= n; ++i)
      for (int j = -n; j <= n; ++j)
      {
        const double rho = std::hypot(i, j) * h, z = -(k + 0.5) * h;
        const double radius = k < 3 ? 20.0 * h : k >= layers - 2 ? 15.0 * h : 2.0 * h;
        in.x0.insert(in.x0.end(), {i * h, j * h, z});
        in.r.push_back(0.5 * h);
        in.m.push_back(1.0);
        const bool detached = rho <= radius;
        in.detached.push_back(detached);
        if (detached && k < 3)
          front_mass += 1.0;
        if (detached && k >= layers - 2)
          rear_mass += 1.0;
      }
  const auto [front, rear] = demo::measure_craters(in);
  CHECK_THAT(front.diameter, WithinRel(40.0 * h, 0.01));
  CHECK_THAT(front.depth, WithinAbs(3.0 * h, 1e-12));
  CHECK(front.mass == front_mass);
  CHECK_THAT(rear.diameter, WithinRel(30.0 * h, 0.01));
  CHECK_THAT(rear.depth, WithinAbs(2.0 * h, 1e-12));
  CHECK(rear.mass == rear_mass);
}

TEST_CASE("impact: a short perforation, its budget closed and its outcome consistent", "[impact]")
{
  // 400 m/s through a 20 mm slab of the default concrete: perforated, the
  // residual speed below the striking one, the projectile's lost energy
  // found in the target (the budget within 1 % of its initial kinetic
  // energy, the issue's figure; measured 0.4 %), craters front and rear.
  const auto file = write_file("run.toml", small_case);
  demo::ImpactConfig c;
  c.scenario = demo::read_scenario(file);
  c.quiet = true;
  const auto r = demo::run_impact(c);
  INFO(r.dump(1));
  CHECK(r.at("perforated") == true);
  const double vr = r.at("residual_velocity_m_s");
  CHECK(vr > 0.0);
  CHECK(vr < 400.0);
  const auto& e = r.at("energy");
  const double ke0 = e.at("projectile_initial_j");
  CHECK_THAT(ke0, WithinRel(0.5 * 0.02 * 400.0 * 400.0, 1e-12));
  CHECK(std::abs(e.at("imbalance_j").get<double>()) < 0.01 * ke0);
  CHECK(r.at("front_crater_diameter_m").get<double>() > 0.01);
  CHECK(r.at("penetration_depth_m") == 0.02);
  CHECK(r.at("links_broken").get<double>() > 0);
}

TEST_CASE("impact: a flat nose on a free cube closes its budget to 1 %", "[impact]")
{
  // A 4 g flat-nosed steel projectile at 100 m/s stopped by a free 40 mm
  // cube (no supports) of 2,460 spheres, at the default step: the bluntest
  // nose, so the most contacts opening and closing at once, each of whose
  // first and last steps the explicit scheme integrates to O(dt) (the
  // budget's error; on a 50 mm cube of 10,635 spheres the rounder noses give
  // 0.00-0.06 %, this one 0.54 %; here 0.45 %).
  // The impact work asks the budget to close to 1 % of the projectile's
  // energy; the cube is stopped with its contacts still loaded, where the
  // error is largest.
  const auto file = write_file("free_cube.toml", R"(
[scenario]
name = "free cube"
[target]
size_m = [0.04, 0.04]
thickness_m = 0.04
mean_radius_m = 1.5e-3
supports = "none"
[projectile]
mass_kg = 0.004
diameter_m = 0.006
length_m = 0.02
nose = "flat"
velocity_m_s = 100.0
standoff_m = 1e-4
[run]
duration_s = 3e-5
)");
  demo::ImpactConfig c;
  c.scenario = demo::read_scenario(file);
  c.quiet = true;
  const auto r = demo::run_impact(c);
  INFO(r.dump(1));
  CHECK(r.at("outcome") == "stopped");
  CHECK(r.at("supported_spheres") == 0);
  const auto& e = r.at("energy");
  const double ke0 = e.at("projectile_initial_j");
  // nearly all of it passed to the cube
  CHECK(e.at("projectile_lost_j").get<double>() > 0.9 * ke0);
  CHECK(std::abs(e.at("imbalance_j").get<double>()) < 0.01 * ke0);
}
