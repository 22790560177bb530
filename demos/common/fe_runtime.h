#pragma once
/// @file fe_runtime.h
/// The runtime of the programs with finite elements (DOLFINx): PETSc and
/// MPI, for run_guarded. The programs of discrete elements alone do without
/// it, and so without DOLFINx.

#include "support.h"

namespace dembridge::demo
{
/// PetscInitialize (which starts MPI) with DOLFINx's log at warnings, and
/// PetscFinalize.
Runtime petsc_runtime();
} // namespace dembridge::demo
