// Catch2's whole implementation, compiled once for both test programs
// (unit_tests and dem_tests): the single header's runner costs about 20 s of
// compile time per translation unit.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include "catch_runner.h"

int dembridge::tests::run_catch(int argc, char* argv[])
{
  return Catch::Session().run(argc, argv);
}
