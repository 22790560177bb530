#include "fe_runtime.h"

#include <dolfinx/common/log.h>
#include <petscsys.h>

namespace dembridge::demo
{
Runtime petsc_runtime()
{
  Runtime r;
  r.start = [](int& argc, char**& argv)
  {
    PetscInitialize(&argc, &argv, nullptr, nullptr);
    loguru::g_stderr_verbosity = loguru::Verbosity_WARNING; // DOLFINx INFO off
  };
  r.finish = [] { PetscFinalize(); };
  return r;
}
} // namespace dembridge::demo
