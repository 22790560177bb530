// The rc_beam demo's reading of the cracking point on a load-deflection
// curve (change_of_slope), and the packing round the bars it uses.
#include "beam.h"

#include "dembridge/dem/bars.h"
#include "dembridge/dem/packing.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>
#include <span>
#include <vector>

using namespace dembridge;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;

TEST_CASE("change of slope: the kink of a two-branch curve, with and without noise", "[rc_beam]")
{
  // y = 2 x up to x = 1, then 2 + 0.5 (x - 1), sampled on (0, 4]: the fit
  // is exact at the kink, found to the search's step (0.25 % of x_end =
  // 0.01); with +-10 % uniform noise on y (the load's vibration; standard
  // deviation 5.8 % of y, 0.12-0.2), 800 points, the breakpoint's standard
  // deviation from the fit's covariance is sigma / sqrt(~100) ~ 1.1-1.5 %
  // of xb, and the kink's load a xb moves with it: 5 % allowed (3.5 sd).
  std::vector<double> x, y, noisy;
  std::mt19937 gen(3);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  for (int i = 1; i <= 800; ++i)
  {
    x.push_back(4.0 * i / 800.0);
    y.push_back(x.back() < 1.0 ? 2.0 * x.back() : 2.0 + 0.5 * (x.back() - 1.0));
    noisy.push_back(y.back() * (1.0 + u(gen)));
  }
  const auto exact = demo::change_of_slope(x, y, 4.0);
  CHECK_THAT(exact[0], WithinAbs(1.0, 0.01));
  CHECK_THAT(exact[1], WithinAbs(2.0, 0.02));
  const auto rough = demo::change_of_slope(x, noisy, 4.0);
  CHECK_THAT(rough[0], WithinRel(1.0, 0.05));
  CHECK_THAT(rough[1], WithinRel(2.0, 0.05));
  // only the points up to x_end count: the kink of the first 3 units
  CHECK_THAT(demo::change_of_slope(x, y, 3.0)[0], WithinAbs(1.0, 0.0075));
  // too few points: no reading
  CHECK(demo::change_of_slope(std::span(x).first(3), std::span(y).first(3), 4.0)[0] == 0.0);
}

TEST_CASE("packing round the bars: no sphere on a bar, the fraction over the concrete's volume", "[rc_beam][bars]")
{
  // a 16 mm bar through a 60 mm cube, leaving it through two faces (5.6 %
  // of the cube's volume); its elements (5 mm) end on the faces, so that
  // the bar's volume inside is pi r^2 60 mm exactly
  using namespace dem;
  const Region cube = box_region({0, 0, 0}, {0.06, 0.06, 0.06});
  BarLine line{{{-0.01, 0.03, 0.03}, {0.07, 0.03, 0.03}}, 0.016, 0, 0};
  const Bars bars = make_bars(std::span<const BarLine>(&line, 1), {Steel{}}, {BondLaw{}}, 5e-3);
  PackingOptions po;
  po.mean_radius = 3e-3;
  const ConcretePacking c = pack_around_bars(cube, bars, po);
  REQUIRE(c.packing.size() > 700); // ~950: 0.6 of the concrete's volume over a sphere's
  INFO("removed " << c.removed << ", added " << c.added << ", fraction " << c.solid_fraction);
  // no sphere closer to the axis than its radius plus the bar's
  const auto on = spheres_on_bars(bars, c.packing.x, c.packing.r);
  CHECK(std::count(on.begin(), on.end(), 1) == 0);
  double solid = 0.0;
  for (double r : c.packing.r)
    solid += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  const double concrete = std::pow(0.06, 3) - std::numbers::pi * 0.008 * 0.008 * 0.06;
  CHECK_THAT(c.solid_fraction, WithinRel(solid / concrete, 1e-12));
  CHECK_THAT(concrete_fraction(c.packing, cube, Bars{}), WithinRel(solid / std::pow(0.06, 3), 1e-12));
  // the concrete round the bar is packed as the plain cube is: a surface
  // loosens the layer against it, which costs the plain cube ~6 % of the
  // bulk's fraction (0.58 against 0.62); the bar adds 14 % to the faces' area
  // over 5.6 % less volume, 1.2 times the loss: ~1.3 % lower (measured
  // 1.7 %, the bar's convex surface packing a little less well). 3 %
  // allowed; a fraction over the whole cube's volume would be 5.6 % lower
  const Packing plain = generate_packing(cube, po);
  const double f_plain = concrete_fraction(plain, cube, Bars{});
  INFO("plain cube's fraction " << f_plain);
  CHECK_THAT(c.solid_fraction, WithinRel(f_plain, 0.03));
}
