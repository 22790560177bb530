// Fictive elements and the interpolation operator G_FE of the bridge
// (paper's equations [5] and [6]).
#include "dembridge/bridge/fictive.h"
#include "dembridge/shell/mesh.h"
#include "dembridge/shell/model.h"

#include <cmath>
#include <dolfinx/mesh/Mesh.h>
#include <mpi.h>
#include <random>
// after DOLFINx: its logging header defines INFO
#include <catch2/catch.hpp>

using namespace dembridge;
using Catch::Contains;

namespace
{
/// A shell model on a 0.4 x 0.2 panel of nx x ny cells, optionally bent
/// into a cylinder of radius R about the y axis, then placed in space.
shell::FEModel panel(shell::Cell cell, double R, const shell::Placement& place, int nx = 8, int ny = 4)
{
  auto mesh = shell::create_shell_rectangle(MPI_COMM_WORLD, 0.4, 0.2, nx, ny, cell);
  auto x = mesh->geometry().x();
  for (std::size_t i = 0; i < x.size() / 3; ++i)
  {
    std::array<double, 3> p{x[3 * i], x[3 * i + 1], x[3 * i + 2]};
    if (R > 0.0)
      p = {R * std::sin(p[0] / R), p[1], R * std::cos(p[0] / R) - R};
    p = place.apply(p);
    std::copy(p.begin(), p.end(), x.begin() + 3 * i);
  }
  shell::Material m;
  m.thickness = 0.05;
  return shell::FEModel(mesh, m);
}

bridge::ShellGeometry geometry(const shell::FEModel& m)
{
  return {m.node_coordinates(), m.nodal_normals(), m.cell_nodes(), m.nodes_per_cell(),
          m.material().thickness};
}

/// Points at random reference coordinates strictly inside random fictive
/// elements (margin >= 0.05), and their (cell, reference coordinates).
struct Sample
{
  std::vector<double> x, ref;
  std::vector<std::int32_t> cell;
};
Sample sample_points(const bridge::ShellGeometry& g, int n, unsigned seed)
{
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(0.05, 0.95), z(-0.95, 0.95);
  std::uniform_int_distribution<int> pick(0, int(g.cells.size() / g.nodes_per_cell) - 1);
  const auto f = bridge::fictive_nodes(g);
  Sample s;
  for (int i = 0; i < n; ++i)
  {
    const int c = pick(gen);
    double a = u(gen), b = u(gen);
    if (g.nodes_per_cell == 3 && a + b > 0.95)
    {
      a = 0.5 * a;
      b = 0.5 * b;
    }
    const double zz = z(gen);
    double m[4];
    if (g.nodes_per_cell == 3)
    {
      m[0] = 1 - a - b;
      m[1] = a;
      m[2] = b;
    }
    else
    {
      m[0] = (1 - a) * (1 - b);
      m[1] = a * (1 - b);
      m[2] = (1 - a) * b;
      m[3] = a * b;
    }
    std::array<double, 3> x{0, 0, 0};
    for (int k = 0; k < g.nodes_per_cell; ++k)
    {
      const auto node = g.cells[c * g.nodes_per_cell + k];
      for (int d = 0; d < 3; ++d)
        x[d] += m[k] * (0.5 * (1 - zz) * f[6 * node + d] + 0.5 * (1 + zz) * f[6 * node + 3 + d]);
    }
    s.x.insert(s.x.end(), x.begin(), x.end());
    s.ref.insert(s.ref.end(), {a, b, zz});
    s.cell.push_back(c);
  }
  return s;
}
} // namespace

TEST_CASE("fictive elements: points are found where they are", "[bridge]")
{
  // 8 x 4 cells, and 48 x 24, narrower than the shell is thick (the search
  // inverts the map only in the cells whose box holds the point)
  for (auto cell : {shell::Cell::quadrilateral, shell::Cell::triangle})
    for (int nx : {8, 48})
    {
      const auto m = panel(cell, 0.3, shell::Placement::rotation_about({1, 2, 3}, 0.7, {1, 2, 3}), nx, nx / 2);
      const auto g = geometry(m);
      const auto s = sample_points(g, 300, 5);
      const auto op = bridge::locate(g, s.x);
      REQUIRE(op.size() == 300);
      CHECK(op.outside() == 0);
      for (std::size_t p = 0; p < op.size(); ++p)
      {
        CHECK(op.cells()[p] == s.cell[p]);
        for (int d = 0; d < 3; ++d) // Newton converges to round-off
          CHECK(std::abs(op.reference()[3 * p + d] - s.ref[3 * p + d]) < 1e-10);
      }
    }
}

TEST_CASE("patch test: a rigid motion of the shell moves the particles rigidly", "[bridge]")
{
  // u_J = c + theta x x_J, rotation theta at every node: the fictive nodes
  // move rigidly (u + z theta x n = c + theta x (x + z n)) and the
  // isoparametric interpolation reproduces any affine field exactly.
  const std::array<double, 3> c{0.3, -0.2, 0.5}, th{0.7, -0.4, 0.25};
  for (auto cell : {shell::Cell::quadrilateral, shell::Cell::triangle})
    for (double R : {0.0, 0.25})
    {
      const auto m = panel(cell, R, shell::Placement::rotation_about({0, 1, 1}, 0.4, {0.5, 0, 0}));
      const auto g = geometry(m);
      const auto s = sample_points(g, 200, 9);
      const auto op = bridge::locate(g, s.x);
      const auto x = m.node_coordinates();
      std::vector<double> u(6 * m.num_nodes()), v(3 * op.size());
      for (std::size_t k = 0; k < m.num_nodes(); ++k)
      {
        const double* p = &x[3 * k];
        const double w[3] = {th[1] * p[2] - th[2] * p[1], th[2] * p[0] - th[0] * p[2],
                             th[0] * p[1] - th[1] * p[0]};
        for (int d = 0; d < 3; ++d)
        {
          u[6 * k + d] = c[d] + w[d];
          u[6 * k + 3 + d] = th[d];
        }
      }
      op.interpolate(u, v);
      double worst = 0.0;
      for (std::size_t p = 0; p < op.size(); ++p)
      {
        const double* q = &s.x[3 * p];
        const double w[3] = {th[1] * q[2] - th[2] * q[1], th[2] * q[0] - th[0] * q[2],
                             th[0] * q[1] - th[1] * q[0]};
        for (int d = 0; d < 3; ++d)
          worst = std::max(worst, std::abs(v[3 * p + d] - (c[d] + w[d])));
      }
      INFO("cell " << shell::to_string(cell) << ", R = " << R << ": worst " << worst);
      CHECK(worst < 1e-12);
    }
}

TEST_CASE("G_FE transpose: power of point forces equals that of nodal forces and moments",
          "[bridge]")
{
  const auto m = panel(shell::Cell::quadrilateral, 0.3, {});
  const auto g = geometry(m);
  const auto s = sample_points(g, 100, 3);
  const auto op = bridge::locate(g, s.x);
  std::mt19937 gen(1);
  std::uniform_real_distribution<double> r(-1, 1);
  std::vector<double> u(6 * m.num_nodes()), f(3 * op.size()), v(3 * op.size()),
      fs(6 * m.num_nodes(), 0.0);
  for (auto& a : u)
    a = r(gen);
  for (auto& a : f)
    a = r(gen);
  op.interpolate(u, v);
  op.add_transpose(f, fs);
  double lhs = 0, rhs = 0;
  for (std::size_t i = 0; i < v.size(); ++i)
    lhs += v[i] * f[i];
  for (std::size_t i = 0; i < u.size(); ++i)
    rhs += u[i] * fs[i];
  CHECK(std::abs(lhs - rhs) < 1e-12 * std::abs(lhs));
}

TEST_CASE("Figure 6: points outside every element or inside two are placed and counted",
          "[bridge][errors]")
{
  const auto m = panel(shell::Cell::quadrilateral, 0.0, {});
  const auto g = geometry(m);
  // flat panel in z = 0, h = 0.05: a point 1 mm above the top face lies in
  // no element; a point on the face shared by two cells lies in both
  std::vector<double> pts{0.125, 0.075, 0.026, 0.1, 0.075, 0.0};
  const auto op = bridge::locate(g, pts);
  CHECK(op.outside() == 1);
  CHECK(op.ambiguous() == 1);
  // the outside point follows the nearest point of its element (on the top face)
  CHECK(std::abs(op.reference()[2] - 1.0) < 1e-12);
  std::vector<double> far{0.2, 0.1, 0.5};
  CHECK_THROWS_WITH(bridge::locate(g, far), Contains("particle 0") && Contains("no fictive element"));
}

#include "dembridge/bridge/multipliers.h"

TEST_CASE("multipliers: constraint exact, momentum kept, no kinetic energy created", "[bridge]")
{
  for (auto cell : {shell::Cell::quadrilateral, shell::Cell::triangle})
  {
    const auto m = panel(cell, 0.3, shell::Placement::rotation_about({1, 0, 1}, 0.3, {0.2, 0.1, 0}));
    const auto g = geometry(m);
    const auto s = sample_points(g, 150, 21);
    const auto op = bridge::locate(g, s.x);
    std::mt19937 gen(4);
    std::uniform_real_distribution<double> r(-1, 1), mass(0.5e-3, 2e-3);
    std::vector<double> m_de(op.size()), v_de(3 * op.size());
    for (auto& x : m_de)
      x = mass(gen);
    for (auto& x : v_de)
      x = r(gen);
    auto m_fe = m.lumped_mass();
    for (auto& x : m_fe)
      x *= 0.5 + 0.5 * std::abs(r(gen)); // weighted masses, weights in [0.5, 1]
    std::vector<double> v_fe(m.num_dofs());
    for (auto& x : v_fe)
      x = r(gen);
    const double dt = 1e-6;
    bridge::MultiplierSolver solver(op, m_de, m_fe, dt);

    auto momentum = [&](const std::vector<double>& vd, const std::vector<double>& vf)
    {
      // linear and angular (about the origin) momentum of both sides
      std::array<double, 6> P{0, 0, 0, 0, 0, 0};
      auto add = [&](const double* x, const double* mv, const double* Iw)
      {
        for (int i = 0; i < 3; ++i)
          P[i] += mv[i];
        P[3] += x[1] * mv[2] - x[2] * mv[1] + (Iw ? Iw[0] : 0.0);
        P[4] += x[2] * mv[0] - x[0] * mv[2] + (Iw ? Iw[1] : 0.0);
        P[5] += x[0] * mv[1] - x[1] * mv[0] + (Iw ? Iw[2] : 0.0);
      };
      for (std::size_t p = 0; p < op.size(); ++p)
      {
        const double mv[3] = {m_de[p] * vd[3 * p], m_de[p] * vd[3 * p + 1], m_de[p] * vd[3 * p + 2]};
        add(&s.x[3 * p], mv, nullptr);
      }
      const auto x = m.node_coordinates();
      for (std::size_t k = 0; k < m.num_nodes(); ++k)
      {
        double mv[3], Iw[3];
        for (int i = 0; i < 3; ++i)
        {
          mv[i] = m_fe[6 * k + i] * vf[6 * k + i];
          Iw[i] = m_fe[6 * k + 3 + i] * vf[6 * k + 3 + i];
        }
        add(&x[3 * k], mv, Iw);
      }
      return P;
    };
    auto kinetic = [&](const std::vector<double>& vd, const std::vector<double>& vf)
    {
      double e = 0.0;
      for (std::size_t p = 0; p < op.size(); ++p)
        for (int i = 0; i < 3; ++i)
          e += 0.5 * m_de[p] * vd[3 * p + i] * vd[3 * p + i];
      for (std::size_t i = 0; i < vf.size(); ++i)
        e += 0.5 * m_fe[i] * vf[i] * vf[i];
      return e;
    };
    const auto P0 = momentum(v_de, v_fe);
    const double K0 = kinetic(v_de, v_fe);
    const double res = solver.correct(v_de, v_fe);
    // the constraint holds to the solver's round-off (velocities are O(1))
    CHECK(res < 1e-10);
    const auto P1 = momentum(v_de, v_fe);
    for (int i = 0; i < 6; ++i)
      CHECK(std::abs(P1[i] - P0[i]) < 1e-12 * (std::abs(P0[i]) + 1e-3));
    // an M-orthogonal projection onto the constraint: kinetic energy can
    // only drop
    CHECK(kinetic(v_de, v_fe) <= K0 * (1 + 1e-14));
    // a second correction has nothing left to do
    const auto before = v_de;
    solver.correct(v_de, v_fe);
    for (std::size_t i = 0; i < v_de.size(); ++i)
      CHECK(std::abs(v_de[i] - before[i]) < 1e-10);
  }
}

TEST_CASE("multipliers: bad masses are refused", "[bridge][errors]")
{
  const auto m = panel(shell::Cell::quadrilateral, 0.0, {});
  const auto g = geometry(m);
  const auto s = sample_points(g, 5, 2);
  const auto op = bridge::locate(g, s.x);
  std::vector<double> m_de(5, 1e-3), m_fe = m.lumped_mass();
  m_de[2] = 0.0;
  CHECK_THROWS_WITH(bridge::MultiplierSolver(op, m_de, m_fe, 1e-6),
                    Contains("constrained particle 2") && Contains("weight floor"));
}
