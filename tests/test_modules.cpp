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
