// Catch2 test main: initialises MPI/PETSc once for every test.
#include "catch_runner.h"

#include <dolfinx/common/log.h>
#include <petscsys.h>

int main(int argc, char* argv[])
{
  PetscInitializeNoArguments();
  loguru::g_stderr_verbosity = loguru::Verbosity_WARNING;
  const int result = dembridge::tests::run_catch(argc, argv);
  PetscFinalize();
  return result;
}
