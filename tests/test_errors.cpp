// Bad input gets a std::runtime_error naming the value and what is allowed.
#include "cantilever.h"
#include "dembridge/shell/mesh.h"
#include "dembridge/shell/model.h"

#include <catch2/catch.hpp>
#include <dolfinx/mesh/Mesh.h>
#include <dolfinx/mesh/generation.h>
#include <filesystem>
#include <fstream>
#include <mpi.h>

using namespace dembridge;
using Catch::Contains;

namespace
{
std::shared_ptr<dolfinx::mesh::Mesh> small_shell()
{
  return shell::create_shell_rectangle(MPI_COMM_WORLD, 1.0, 0.2, 4, 1, shell::Cell::quadrilateral);
}
} // namespace

TEST_CASE("material values out of range", "[errors]")
{
  auto mesh = small_shell();
  shell::Material m;
  m.thickness = 0.0;
  CHECK_THROWS_WITH(shell::FEModel(mesh, m), Contains("thickness") && Contains("> 0"));
  m = {};
  m.thickness = -0.1;
  CHECK_THROWS_WITH(shell::FEModel(mesh, m), Contains("thickness"));
  m = {};
  m.poisson_ratio = 0.5;
  CHECK_THROWS_WITH(shell::FEModel(mesh, m), Contains("Poisson") && Contains("(-1, 0.5)"));
  m.poisson_ratio = -1.0;
  CHECK_THROWS_WITH(shell::FEModel(mesh, m), Contains("Poisson"));
  m = {};
  m.youngs_modulus = 0.0;
  CHECK_THROWS_WITH(shell::FEModel(mesh, m), Contains("Young") && Contains("> 0 Pa"));
  m = {};
  m.density = -2400.0;
  CHECK_THROWS_WITH(shell::FEModel(mesh, m), Contains("density") && Contains("-2400"));
  m = {};
  m.youngs_modulus = std::nan("");
  CHECK_THROWS_WITH(shell::FEModel(mesh, m), Contains("Young"));
}

TEST_CASE("a 2D mesh given to the shell", "[errors]")
{
  auto mesh2d = std::make_shared<dolfinx::mesh::Mesh>(dolfinx::mesh::create_rectangle(
      MPI_COMM_WORLD, {{{0.0, 0.0}, {1.0, 0.2}}}, {4, 1}, dolfinx::mesh::CellType::triangle,
      dolfinx::mesh::GhostMode::none));
  CHECK_THROWS_WITH(shell::FEModel(mesh2d, shell::Material{}),
                    Contains("geometric dimension 3") && Contains("geometric dimension 2"));
}

TEST_CASE("time step above the critical one", "[errors]")
{
  demo::CantileverConfig c;
  c.nx = 8;
  c.ny = 2;
  c.quiet = true;
  c.dt = 1e-3;
  CHECK_THROWS_WITH(demo::run_cantilever(c), Contains("above the critical time step"));
}

TEST_CASE("a boundary region that selects no node", "[errors]")
{
  // A mesh moved 10 m along x, read from file while the experiment looks for
  // its clamped end at x = 0: the selection is empty.
  auto dir = std::filesystem::temp_directory_path() / "dembridge_test_err";
  std::filesystem::create_directories(dir);
  shell::Placement moved;
  moved.origin = {10.0, 0.0, 0.0};
  auto mesh = shell::create_shell_rectangle(MPI_COMM_WORLD, 0.85, 0.25, 8, 2,
                                            shell::Cell::quadrilateral, moved);
  shell::write_mesh(*mesh, dir / "moved.xdmf");
  demo::CantileverConfig c;
  c.quiet = true;
  c.mesh_file = (dir / "moved.xdmf").string();
  CHECK_THROWS_WITH(demo::run_cantilever(c), Contains("clamped end") && Contains("no node"));
}

TEST_CASE("unreadable mesh files", "[errors]")
{
  CHECK_THROWS_WITH(shell::read_mesh(MPI_COMM_WORLD, "/nonexistent/bar.xdmf"),
                    Contains("/nonexistent/bar.xdmf") && Contains("does not exist"));
  auto bad = std::filesystem::temp_directory_path() / "dembridge_bad_mesh.xdmf";
  std::ofstream(bad) << "this is not XDMF\n";
  CHECK_THROWS_WITH(shell::read_mesh(MPI_COMM_WORLD, bad), Contains("cannot read mesh"));
}

TEST_CASE("energy weights outside [0, 1]", "[errors]")
{
  shell::FEModel model(small_shell(), shell::Material{});
  std::vector<double> w(model.num_nodes(), 1.0);
  w[3] = 1.5;
  CHECK_THROWS_WITH(model.set_weight(w), Contains("1.5") && Contains("[0, 1]"));
  w.pop_back();
  CHECK_THROWS_WITH(model.set_weight(w), Contains("values given"));
}

TEST_CASE("unknown option values", "[errors]")
{
  demo::CantileverConfig c;
  c.quiet = true;
  c.load = "torsion";
  CHECK_THROWS_WITH(demo::run_cantilever(c), Contains("torsion") && Contains("axial"));
  c = {};
  c.cell = "pentagon";
  CHECK_THROWS_WITH(demo::run_cantilever(c), Contains("pentagon"));
  c = {};
  c.nx = 0;
  CHECK_THROWS_WITH(demo::run_cantilever(c), Contains("divisions 0"));
  c = {};
  c.force_method = "magic";
  CHECK_THROWS_WITH(demo::run_cantilever(c), Contains("magic"));
}
