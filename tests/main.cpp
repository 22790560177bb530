// Catch2 test main: initialises MPI/PETSc once for every test.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>
#include <dolfinx/common/log.h>
#include <petscsys.h>

int main(int argc, char* argv[])
{
  PetscInitializeNoArguments();
  loguru::g_stderr_verbosity = loguru::Verbosity_WARNING;
  const int result = Catch::Session().run(argc, argv);
  PetscFinalize();
  return result;
}
