// Reinforced-concrete shell sections (shell/forms/shell.py, FEModel::set_reinforcement)
// against the transformed section, in closed form.
#include "dembridge/shell/mesh.h"
#include "dembridge/shell/model.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

using namespace dembridge;
using Catch::Matchers::Contains;
using Catch::Matchers::WithinRel;

namespace
{

/// A section with two layers along d1 (bottom and top, unequal: S != 0) and
/// one along d2, in a 0.2 m plate.
shell::Reinforcement two_way()
{
  shell::Reinforcement r;
  r.layers = {{0, 0.012, 0.10, -0.07}, {0, 0.008, 0.15, 0.06}, {1, 0.010, 0.12, -0.055}};
  return r;
}

std::array<double, 3> rotate(const shell::Placement& p, const std::array<double, 3>& v)
{
  const auto& R = p.rotation;
  return {R[0] * v[0] + R[1] * v[1] + R[2] * v[2], R[3] * v[0] + R[4] * v[1] + R[5] * v[2],
          R[6] * v[0] + R[7] * v[1] + R[8] * v[2]};
}

/// The strain energy 0.5 U . K U of the field with uniform membrane strains
/// (e1, e2) and curvatures (k1, k2) along the plate's local x and y, with
/// zero transverse shear: u = (e1 x, e2 y, -(k1 x^2 + k2 y^2) / 2) and
/// theta = (-k2 y, k1 x, 0) in the local frame (theta x n = (k1 x, k2 y, 0)),
/// placed by p. Both cell types reproduce it exactly (bilinear fields and a
/// quadratic w whose shear gaps vanish on every edge and at every centroid).
double field_energy(const shell::FEModel& m, const shell::Placement& p, double e1, double e2,
                    double k1, double k2)
{
  const auto X = m.node_coordinates();
  std::vector<double> u(m.num_dofs()), f(m.num_dofs());
  const auto& R = p.rotation;
  for (std::size_t n = 0; n < m.num_nodes(); ++n)
  {
    // local coordinates x = R^T (X - origin)
    std::array<double, 3> d{X[3 * n] - p.origin[0], X[3 * n + 1] - p.origin[1],
                            X[3 * n + 2] - p.origin[2]};
    const double x = R[0] * d[0] + R[3] * d[1] + R[6] * d[2];
    const double y = R[1] * d[0] + R[4] * d[1] + R[7] * d[2];
    const auto ug = rotate(p, {e1 * x, e2 * y, -0.5 * (k1 * x * x + k2 * y * y)});
    const auto tg = rotate(p, {-k2 * y, k1 * x, 0.0});
    for (int k = 0; k < 3; ++k)
    {
      u[6 * n + k] = ug[k];
      u[6 * n + 3 + k] = tg[k];
    }
  }
  m.internal_force(u, f);
  double e = 0.0;
  for (std::size_t i = 0; i < u.size(); ++i)
    e += 0.5 * u[i] * f[i];
  return e;
}
} // namespace

TEST_CASE("layered section: membrane, coupling and bending stiffness of the transformed section", "[shell][rc]")
{
  // A uniform field stores (1/2)(e A e + 2 e B k + k D k) per unit area: the
  // concrete's plane-stress plate plus, along each bar direction, (E_s - E)
  // (A, S, I). The form integrates constants exactly, so the energies agree
  // to round-off (1e-6 asked; 1e-9 holds).
  const double E = 30e9, nu = 0.2, h = 0.2, lx = 1.2, ly = 0.8;
  const auto place = shell::Placement::rotation_about({1, 2, 0.5}, 0.7, {0.3, -0.2, 0.1});
  shell::Material mat;
  mat.youngs_modulus = E;
  mat.poisson_ratio = nu;
  mat.thickness = h;
  auto r = two_way();
  r.direction = rotate(place, {1, 0, 0}); // d1 along the plate's local x
  const auto s = shell::section_sums(r);
  const double es = r.youngs_modulus - E, C = E / (1 - nu * nu);
  for (auto cell : {shell::Cell::quadrilateral, shell::Cell::triangle})
  {
    auto mesh = shell::create_shell_rectangle(MPI_COMM_WORLD, lx, ly, 6, 4, cell, place);
    shell::FEModel model(mesh, mat);
    const double plain = field_energy(model, place, 1e-4, 0, 0, 0);
    CHECK_THAT(plain, WithinRel(0.5 * C * h * 1e-8 * lx * ly, 1e-9));
    model.set_reinforcement(r);
    const double e1 = 2e-4, e2 = -1.5e-4, k1 = 3e-3, k2 = -2e-3;
    struct Case
    {
      const char* what;
      double e1, e2, k1, k2;
    };
    for (const Case& c : {Case{"membrane along d1", e1, 0, 0, 0}, Case{"membrane along d2", 0, e2, 0, 0},
                          Case{"bending along d1", 0, 0, k1, 0}, Case{"bending along d2", 0, 0, 0, k2},
                          Case{"everything", e1, e2, k1, k2}})
    {
      const double concrete = 0.5 * C * h * (c.e1 * c.e1 + 2 * nu * c.e1 * c.e2 + c.e2 * c.e2)
                              + 0.5 * C * h * h * h / 12
                                    * (c.k1 * c.k1 + 2 * nu * c.k1 * c.k2 + c.k2 * c.k2);
      const double steel = 0.5 * es * (s[0][0] * c.e1 * c.e1 + 2 * s[0][1] * c.e1 * c.k1 + s[0][2] * c.k1 * c.k1)
                           + 0.5 * es * (s[1][0] * c.e2 * c.e2 + 2 * s[1][1] * c.e2 * c.k2 + s[1][2] * c.k2 * c.k2);
      INFO(shell::to_string(cell) << ", " << c.what);
      CHECK_THAT(field_energy(model, place, c.e1, c.e2, c.k1, c.k2),
                 WithinRel((concrete + steel) * lx * ly, 1e-9));
    }
    // the coupling term alone: (e, k) and (e, -k) differ by 4 e B k
    const double plus = field_energy(model, place, e1, 0, k1, 0);
    const double minus = field_energy(model, place, e1, 0, -k1, 0);
    CHECK_THAT(plus - minus, WithinRel(2 * es * s[0][1] * e1 * k1 * lx * ly, 1e-6));
  }
}

TEST_CASE("layered section: mass, nodal measure and regions", "[shell][rc]")
{
  // Row sums of the lumped mass are exact totals: (rho h + (rho_s - rho) A)
  // per translation and (rho h^3/12 + (rho_s - rho) I) per rotation, with
  // A, I summed over both directions; the tributary areas stay the plate's.
  const double lx = 1.0, ly = 0.5, h = 0.2, rho = 2400;
  auto mesh = shell::create_shell_rectangle(MPI_COMM_WORLD, lx, ly, 10, 5, shell::Cell::quadrilateral);
  shell::Material mat;
  mat.thickness = h;
  shell::FEModel model(mesh, mat);
  const auto r = two_way();
  // the steel in the cells of the left half only (a region)
  std::vector<std::int32_t> left;
  const auto X = model.node_coordinates();
  const auto cn = model.cell_nodes();
  for (std::size_t c = 0; c < model.num_cells(); ++c)
  {
    double xc = 0.0;
    for (int k = 0; k < model.nodes_per_cell(); ++k)
      xc += X[3 * cn[c * model.nodes_per_cell() + k]] / model.nodes_per_cell();
    if (xc < 0.5 * lx)
      left.push_back(static_cast<std::int32_t>(c));
  }
  model.set_reinforcement(r, left);
  const auto s = shell::section_sums(r);
  const auto m = model.lumped_mass();
  const auto a = model.nodal_measure();
  double mt = 0.0, mr = 0.0, area = 0.0;
  for (std::size_t n = 0; n < model.num_nodes(); ++n)
  {
    mt += m[6 * n];
    mr += m[6 * n + 3];
    area += a[n];
  }
  const double half = 0.5 * lx * ly;
  CHECK_THAT(area, WithinRel(lx * ly, 1e-12));
  CHECK_THAT(mt, WithinRel(rho * h * lx * ly + (7850 - rho) * (s[0][0] + s[1][0]) * half, 1e-12));
  CHECK_THAT(mr, WithinRel(rho * h * h * h / 12 * lx * ly + (7850 - rho) * (s[0][2] + s[1][2]) * half, 1e-12));
  // an empty reinforcement makes the cells plain again
  model.set_reinforcement(shell::Reinforcement{});
  const auto m0 = model.lumped_mass();
  double m0t = 0.0;
  for (std::size_t n = 0; n < model.num_nodes(); ++n)
    m0t += m0[6 * n];
  CHECK_THAT(m0t, WithinRel(rho * h * lx * ly, 1e-12));
}

TEST_CASE("layered cantilever: first bending frequency within 1 % of beam theory", "[shell][rc]")
{
  // A plate strip with nu = 0 bends as a beam. With steel on one face only
  // the section bends about its neutral axis: EI = b (D - B^2 / A) with
  // A = E h + E' A_s, B = E' S, D = E h^3 / 12 + E' I; its mass per length is
  // b (rho h + (rho_s - rho) A_s). Euler-Bernoulli:
  // f = 1.8751^2 / (2 std::numbers::pi L^2) sqrt(EI / m). L / h = 20 keeps shear and
  // rotary inertia below 0.5 %, 60 cells along the length the discretisation
  // error below 0.1 %: 1 % is the bound.
  const double L = 3.0, b = 0.3, h = 0.15, E = 30e9, rho = 2400;
  shell::Material mat;
  mat.youngs_modulus = E;
  mat.poisson_ratio = 0.0;
  mat.thickness = h;
  mat.density = rho;
  shell::Reinforcement r;
  r.layers = {{0, 0.020, 0.08, -0.05}, {1, 0.010, 0.2, -0.05}};
  const auto s = shell::section_sums(r);
  const double es = r.youngs_modulus - E;
  const double A = E * h + es * s[0][0], B = es * s[0][1], D = E * h * h * h / 12 + es * s[0][2];
  const double EI = b * (D - B * B / A);
  const double m_len = b * (rho * h + (r.density - rho) * (s[0][0] + s[1][0]));
  const double f_eb = 1.8751040687 * 1.8751040687 / (2 * std::numbers::pi * L * L) * std::sqrt(EI / m_len);
  // the plain strip's, to show that the steel matters (well beyond the tolerance)
  const double f_plain = 1.8751040687 * 1.8751040687 / (2 * std::numbers::pi * L * L)
                         * std::sqrt(E * h * h * h / 12 / (rho * h));
  REQUIRE(f_eb / f_plain > 1.03);
  for (auto cell : {shell::Cell::quadrilateral, shell::Cell::triangle})
  {
    auto mesh = shell::create_shell_rectangle(MPI_COMM_WORLD, L, b, 60, 3, cell);
    shell::FEModel model(mesh, mat);
    model.set_reinforcement(r);
    const auto X = model.node_coordinates();
    std::vector<std::int32_t> fixed;
    std::vector<double> x0(model.num_dofs(), 0.0);
    for (std::size_t n = 0; n < model.num_nodes(); ++n)
    {
      if (X[3 * n] < 1e-9)
        for (int k = 0; k < 6; ++k)
          fixed.push_back(static_cast<std::int32_t>(6 * n + k));
      x0[6 * n + 2] = X[3 * n] * X[3 * n];
    }
    const auto mass = model.lumped_mass();
    const auto [mode, lambda] = model.lowest_mode(mass, fixed, x0, 30);
    const double f = std::sqrt(lambda) / (2 * std::numbers::pi);
    INFO(shell::to_string(cell) << ": " << f << " Hz against " << f_eb << " Hz");
    CHECK(std::abs(f / f_eb - 1.0) < 0.01);
  }
}

TEST_CASE("layered section: bad input is refused with the value named", "[shell][rc][errors]")
{
  auto mesh = shell::create_shell_rectangle(MPI_COMM_WORLD, 1.0, 0.5, 4, 2, shell::Cell::quadrilateral);
  shell::Material mat;
  mat.thickness = 0.2;
  shell::FEModel model(mesh, mat);
  auto bad = [&](auto change, const std::string& text)
  {
    shell::Reinforcement r = two_way();
    change(r);
    CHECK_THROWS_WITH(model.set_reinforcement(r), Contains(text));
  };
  bad([](auto& r) { r.layers[1].z = 0.098; }, "layer 1 height z = 0.098"); // 0.098 + 0.004 > 0.1
  bad([](auto& r) { r.layers[0].spacing = 0.012; }, "layer 0 spacing = 0.012");
  bad([](auto& r) { r.layers[2].diameter = 0.0; }, "layer 2 bar diameter = 0");
  bad([](auto& r) { r.layers[0].direction = 2; }, "layer 0 direction = 2");
  bad([](auto& r) { r.youngs_modulus = -1.0; }, "steel Young's modulus E_s = -1");
  bad([](auto& r) { r.density = 0.0; }, "steel density rho_s = 0");
  bad([](auto& r) { r.direction = {0, 0, 0}; }, "length of the bar direction = 0");
  bad([](auto& r) { r.direction = {0, 0, 1}; }, "normal to cell 0");
  const std::vector<std::int32_t> out{99};
  CHECK_THROWS_WITH(model.set_reinforcement(two_way(), out), Contains("cell 99 out of range"));
  auto box = shell::create_solid_box(MPI_COMM_WORLD, {1, 1, 1}, {1, 1, 1}, shell::Cell::hexahedron);
  shell::FEModel solid(box, mat);
  CHECK_THROWS_WITH(solid.set_reinforcement(two_way()), Contains("only shell models"));
}
