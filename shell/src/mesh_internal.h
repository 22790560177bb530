#pragma once
// Internal to shell: a DOLFINx shell mesh from vertex coordinates and cells.
#include "dembridge/shell/mesh.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace dembridge::shell::impl
{
/// The mesh of `cells` (3 or 4 vertex indices each, quadrilaterals in
/// DOLFINx's tensor-product order v00, v10, v01, v11) over the vertices x
/// (3 per vertex), on one process.
std::shared_ptr<dolfinx::mesh::Mesh> shell_mesh(MPI_Comm comm, std::vector<double> x, std::vector<std::int64_t> cells,
                                                Cell cell);
} // namespace dembridge::shell::impl
