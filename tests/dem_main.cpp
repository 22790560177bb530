// Catch2 main for the DEM tests (no MPI/PETSc: dem/ knows nothing of DOLFINx).
#include "catch_runner.h"

int main(int argc, char* argv[])
{
  return dembridge::tests::run_catch(argc, argv);
}
