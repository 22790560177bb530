// Catch2 main for the DEM tests (no MPI/PETSc: dem/ knows nothing of DOLFINx).
#define CATCH_CONFIG_MAIN
#include <catch2/catch.hpp>
