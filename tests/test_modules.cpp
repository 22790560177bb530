// dem/ and bridge/ pieces that exist so far: equation [1] and the energy weight.
#include "dembridge/bridge/weight.h"
#include "dembridge/dem/stiffness.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

using Catch::Contains;
using Catch::Matchers::WithinRel;

TEST_CASE("equation [1]: micro-macro stiffnesses", "[dem]")
{
  using namespace dembridge::dem;
  // alpha = 0, beta = gamma = 1/2: K_n = E S / D / (1 + nu/2 + 1/2) ...
  // evaluated by hand for E = 30 GPa, nu = 0.2, R = 1 mm, D = 2 mm,
  // alpha = 0.2, beta = 0.9, gamma = 1.1:
  //   S = pi 1e-6, den = 0.9 * 1.2 + 1.1 * (1 - 0.04) = 2.136
  //   K_n = 30e9 * pi 1e-6 / 2e-3 * 1.2 / 2.136, K_s = K_n * 0.96 / 1.2
  const double S = interaction_surface(1e-3, 2e-3);
  CHECK_THAT(S, WithinRel(std::numbers::pi * 1e-6, 1e-15));
  const auto k = link_stiffness(30e9, 0.2, S, 2e-3, {0.2, 0.9, 1.1});
  const double kn = 30e9 * std::numbers::pi * 1e-6 / 2e-3 * 1.2 / 2.136;
  CHECK_THAT(k.kn, WithinRel(kn, 1e-14));
  CHECK_THAT(k.ks, WithinRel(kn * 0.96 / 1.2, 1e-14));
  CHECK_THROWS_WITH(interaction_surface(0.0, 1.0), Contains("radius"));
  CHECK_THROWS_WITH(link_stiffness(-1.0, 0.2, S, 1.0, {0, 1, 1}), Contains("Young"));
  CHECK_THROWS_WITH(link_stiffness(1.0, 0.6, S, 1.0, {0, 1, 1}), Contains("Poisson"));
  CHECK_THROWS_WITH(link_stiffness(1.0, 0.2, S, 1.0, {0, -1, -1}), Contains("beta"));
}

TEST_CASE("energy weight across a planar overlap", "[bridge]")
{
  using namespace dembridge::bridge;
  PlanarOverlap o{{1.0, 0.0, 0.0}, 0.6, 0.3};
  o.validate();
  CHECK(o.weight({0.7, 0, 0}) == 0.0);
  CHECK(o.weight({0.2, 5, 5}) == 1.0);
  CHECK_THAT(o.weight({0.4, 0, 0}), WithinRel(2.0 / 3.0, 1e-14));
  CHECK(o.contains({0.45, 1, 1}));
  CHECK(!o.contains({0.65, 0, 0}));
  CHECK(floored(0.0, 1e-3) == 1e-3);
  CHECK_THROWS_WITH(floored(1.2, 1e-3), Contains("[0, 1]"));
  CHECK_THROWS_WITH((PlanarOverlap{{1.0, 1.0, 0.0}, 0.0, 1.0}.validate()), Contains("unit"));
  CHECK_THROWS_WITH((PlanarOverlap{{1.0, 0.0, 0.0}, 0.5, 0.5}.validate()), Contains("coincide"));
}

TEST_CASE("overlaps of any shape: weights from the signed distance to the core", "[bridge]")
{
  using namespace dembridge::bridge;
  // a box core through the thickness (normal z): 0.2 x 0.1 m about (1, 2)
  const Overlap box = Overlap::box({1.0, 2.0}, {0.1, 0.05}, 0.04);
  box.validate();
  CHECK(box.distance({1.0, 2.0, 7.0}) == -0.05);                  // inside: minus the nearest side's distance
  CHECK_THAT(box.distance({1.1, 2.0, 0.0}), Catch::Matchers::WithinAbs(0.0, 1e-15)); // on a side (1.1 - 1 - 0.1 rounds)
  CHECK_THAT(box.distance({1.13, 2.09, 0.0}), WithinRel(0.05, 1e-12)); // past a corner: 3-4-5 (cm)
  CHECK_THAT(box.weight({1.12, 2.0, -3.0}), WithinRel(0.5, 1e-12));   // half-way across the band
  CHECK(box.weight({1.0, 2.0, 0.0}) == 0.0);
  CHECK(box.weight({1.2, 2.0, 0.0}) == 1.0);
  CHECK(box.contains({1.1, 2.0, 0.0}));
  CHECK(box.contains({1.14, 2.0, 0.0}));
  CHECK(!box.contains({1.15, 2.0, 0.0}));
  CHECK(box.beyond({1.15, 2.0, 0.0}));
  CHECK(!box.beyond({1.0, 2.0, 0.0})); // inside the core: DE side
  // a cylinder core about the y axis (normal 1: the in-plane axes x, z)
  const Overlap cyl = Overlap::cylinder({0.0, 0.0}, 0.3, 0.1, 1);
  cyl.validate();
  CHECK_THAT(cyl.weight({0.3 + 0.025, 5.0, 0.0}), WithinRel(0.25, 1e-12));
  CHECK_THAT(cyl.weight({0.0, -1.0, 0.35}), WithinRel(0.5, 1e-12));
  CHECK(cyl.weight({0.1, 0.0, 0.1}) == 0.0);
  CHECK(cyl.beyond({0.5, 0.0, 0.0}));
  // a user core: a ball of radius 0.5 m
  const Overlap ball([](const std::array<double, 3>& x) { return std::hypot(x[0], x[1], x[2]) - 0.5; }, 0.2,
                     "a ball core");
  ball.validate();
  CHECK_THAT(ball.weight({0.0, 0.6, 0.0}), WithinRel(0.5, 1e-12));
  // the planar overlap as an Overlap: PlanarOverlap's weights and membership, bit for bit
  const PlanarOverlap plane{{0.6, 0.8, 0.0}, 0.6, 0.3};
  const Overlap as_overlap = plane;
  for (int k = 0; k <= 100; ++k)
  {
    const std::array<double, 3> x{0.01 * k, 0.003 * k, 0.5};
    CHECK(as_overlap.weight(x) == plane.weight(x));
    CHECK(as_overlap.contains(x) == plane.contains(x));
  }
  CHECK(as_overlap.width() == 0.3);
  CHECK(as_overlap.beyond({0.0, 0.0, 0.0})); // s = 0 < s_fe = 0.3: the FE side
  // bad overlaps, each named
  CHECK_THROWS_WITH(Overlap::box({0, 0}, {0.1, 0.05}, 0.0).validate(), Contains("band width 0 m"));
  CHECK_THROWS_WITH(Overlap::box({0, 0}, {-0.1, 0.05}, 0.1).validate(), Contains("half sizes -0.1 x 0.05 m"));
  CHECK_THROWS_WITH(Overlap::cylinder({0, 0}, 0.0, 0.1).validate(), Contains("radius 0 m"));
  CHECK_THROWS_WITH(Overlap::cylinder({0, 0}, 0.2, 0.1, 3).validate(), Contains("normal axis 3"));
  CHECK_THROWS_WITH(Overlap(PlanarOverlap{{1, 0, 0}, 0.5, 0.5}).validate(), Contains("coincide"));
}
