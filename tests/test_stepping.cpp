// The stepping contract shared by every stepper (core/stepping.h): the
// energy guard's arithmetic and messages, on budgets given by hand (the
// steppers' own guards are tested on unstable runs in test_explicit.cpp
// and test_bridge_coupled.cpp).
#include "dembridge/core/stepping.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

using dembridge::core::EnergyGuard;
using Catch::Contains;

TEST_CASE("energy guard: due on its cadence, throws past its margin, refuses bad settings", "[stepping]")
{
  EnergyGuard g;
  CHECK(g.on());
  CHECK(g.due(100));
  CHECK_FALSE(g.due(150));
  g.set(0.5, 10);
  CHECK(g.due(30));
  CHECK_FALSE(g.due(35));
  // imbalance 0.5 x scale is allowed, a hair more is not
  EnergyGuard::Budget b{1e-3, 40, "the energy", "kinetic + elastic", 3.0, 1.0, 0.0, 1.0, 2.0};
  CHECK_NOTHROW(g.check(b));
  b.imbalance = 1.0 + 1e-12;
  CHECK_THROWS_WITH(g.check(b), Contains("the energy grows without cause at t = 0.001 s (step 40)")
                                    && Contains("kinetic + elastic 3 J against initial 1 J")
                                    && Contains("more than 0.5 x the energy scale"));
  // a NaN imbalance is caught too (the comparison is written so)
  b.imbalance = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS(g.check(b));
  // no energy at all: nothing to compare with
  b.scale = 0.0;
  CHECK_NOTHROW(g.check(b));
  // margin 0 turns it off
  g.set(0.0);
  CHECK_FALSE(g.on());
  CHECK_FALSE(g.due(100));
  CHECK_THROWS_WITH(g.set(-1.0), Contains("margin") && Contains(">= 0"));
  CHECK_THROWS_WITH(g.set(std::nan("")), Contains("margin"));
  CHECK_THROWS_WITH(g.set(0.5, 0), Contains("every 0 steps >= 1"));
}
