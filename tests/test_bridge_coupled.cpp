// The coupled explicit solver on a small bar: shell strip (x in [0, 0.12] m,
// clamped at x = 0) and DE box (x in [0.08, 0.2] m), overlap [0.08, 0.12].
#include "dembridge/bridge/coupled.h"
#include "dembridge/dem/material_file.h"
#include "dembridge/dem/packing.h"
#include "dembridge/shell/mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mpi.h>
#include <functional>
#include <numbers>
#include <numeric>
#include <random>
#include <filesystem>
#include <unistd.h>
// after DOLFINx headers (INFO)
#include <catch2/catch.hpp>

using namespace dembridge;
using Catch::Contains;

namespace
{
struct Bar
{
  std::unique_ptr<shell::FEModel> fe;
  dem::Particles p;
  dem::Links l;
  dem::Material mat;
};

/// All dofs of the FE nodes selected by pred (the clamped end).
std::vector<std::int32_t> clamp_dofs(const shell::FEModel& fe,
                                     const std::function<bool(const std::array<double, 3>&)>& pred)
{
  std::vector<int> all(fe.block_size());
  std::iota(all.begin(), all.end(), 0);
  return shell::node_dofs(shell::select_nodes(fe.node_coordinates(), pred, "clamped end"),
                          fe.block_size(), all);
}

Bar make_bar(shell::Cell cell)
{
  Bar b;
  const double w = 0.05, h = 0.05;
  shell::Material sm;
  sm.thickness = h;
  const bool is_solid = cell == shell::Cell::hexahedron || cell == shell::Cell::tetrahedron;
  auto mesh = is_solid ? shell::create_solid_box(MPI_COMM_WORLD, {0.12, w, h}, {12, 5, 5}, cell,
                                              shell::Placement::rotation_about({1, 0, 0}, 0.0,
                                                                               {0.0, 0.0, -0.5 * h}))
                    : shell::create_shell_rectangle(MPI_COMM_WORLD, 0.12, w, 12, 5, cell);
  b.fe = std::make_unique<shell::FEModel>(mesh, sm);
  dem::PackingOptions po;
  po.mean_radius = 3e-3;
  const auto pk = dem::generate_packing(dem::box_region({0.08, 0, -0.5 * h}, {0.2, w, 0.5 * h}), po);
  double solid = 0.0;
  for (double r : pk.r)
    solid += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  b.mat = dem::read_material(DEMBRIDGE_SOURCE_DIR "/demos/calibrate/materials/default.json").material;
  b.mat.tensile = b.mat.cohesion = 1e12; // elastic
  b.p = dem::make_particles(pk.x, pk.r, b.mat.density, solid / (0.12 * w * h));
  b.l = dem::create_links(b.p, dem::lambda_for_mean_links(b.p.x, b.p.r, 12.0), b.mat);
  return b;
}
} // namespace

TEST_CASE("coupled bar: constraint after every step, energy kept", "[bridge][coupled]")
{
  for (auto cell : {shell::Cell::quadrilateral, shell::Cell::triangle, shell::Cell::hexahedron})
  {
    auto b = make_bar(cell);
    bridge::CouplingOptions o;
    o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.12, 0.08}; // eta = 1 at x <= 0.08, 0 at x >= 0.12
    bridge::CoupledSolver s(*b.fe, b.p, b.l, b.mat, o);
    REQUIRE(s.constrained() > 0);
    CHECK(s.coupling().outside() == 0);
    CHECK(s.dt() == Approx(0.8 * s.dt_coupled()).epsilon(1e-12));
    const int bs = b.fe->block_size();
    const auto x = b.fe->node_coordinates();
    const auto clamp = clamp_dofs(*b.fe, [](const auto& q) { return q[0] < 1e-9; });
    s.fe().add_motion({"clamp", clamp, shell::MotionKind::fixed, {}});
    // axial velocity sin(pi x / (2 L)) on both sides (first axial mode shape)
    const double L = 0.2, V = 1e-3;
    std::vector<double> u(b.fe->num_dofs(), 0.0), v(b.fe->num_dofs(), 0.0);
    for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
      v[bs * k] = V * std::sin(0.5 * std::numbers::pi * x[3 * k] / L);
    for (std::size_t i = 0; i < b.p.size(); ++i)
      b.p.v[3 * i] = V * std::sin(0.5 * std::numbers::pi * b.p.x[3 * i] / L);
    s.start(u, v);
    const double e0 = s.energy().total();
    double worst = 0.0, drift = 0.0;
    // about two periods of the first axial mode (c / 4L ~ 4.4 kHz)
    const int steps = static_cast<int>(2.0 / 4400.0 / s.dt());
    for (int k = 0; k < steps; ++k)
    {
      worst = std::max(worst, s.step());
      if (k % 20 == 0)
      {
        const auto e = s.energy();
        drift = std::max(drift, std::abs(e.total() - e0) / e0);
      }
    }
    const auto e = s.energy();
    INFO(shell::to_string(cell) << ": " << s.constrained() << " constrained particles, dt " << s.dt()
                                << " s, " << steps << " steps, residual " << worst << ", drift "
                                << drift << ", multiplier work on the shell " << e.multiplier_work_fe / e0
                                << " E0, imbalance " << e.imbalance() / e0 << " E0");
    // the constraint holds to the solver's round-off (velocities ~ 1e-3 m/s)
    CHECK(worst < 1e-10);
    // total energy kept: the corrections only remove what the two
    // discretisations disagree on (bounded here by 0.5 %, the required bound
    // for 20 periods)
    CHECK(drift < 5e-3);
    // the two sides' budgets close together (each carries the multipliers'
    // work, which cancels): within the same integration error
    CHECK(std::abs(e.imbalance()) < 5e-3 * e0);
  }
}

namespace
{
/// Largest energy over `steps` steps relative to the initial one, from
/// random velocities (1e-3 m/s) of the particles.
template <class Solver>
double energy_growth(Solver& step_and_energy, int steps)
{
  const double e0 = step_and_energy.energy0();
  double worst = 1.0;
  for (int k = 0; k < steps; ++k)
  {
    try
    {
      step_and_energy.step();
    }
    catch (const std::runtime_error&)
    {
      return 1e300; // non-finite state: blown up
    }
    if (k % 50 == 0)
      worst = std::max(worst, step_and_energy.energy() / e0);
  }
  return worst;
}

void random_velocities(dem::Particles& p)
{
  std::mt19937 gen(17);
  std::uniform_real_distribution<double> d(-1e-3, 1e-3);
  for (auto& v : p.v)
    v = d(gen);
}

struct DemRun
{
  dem::DemSolver& s;
  double energy0() const { return s.energy().initial; }
  void step() { s.step(); }
  double energy() const
  {
    const auto e = s.energy();
    return e.kinetic + e.elastic;
  }
};

struct CoupledRun
{
  bridge::CoupledSolver& s;
  double energy0() const { return s.energy().total(); }
  void step() { s.step(); }
  double energy() const { return s.energy().total(); }
};
} // namespace

TEST_CASE("critical time steps by power iteration: stable below, unstable above", "[bridge]")
{
  // Central differences are stable for omega dt <= 2. The estimates are
  // lambda_max by power iteration to 1e-6, so at 0.97 x the estimate every
  // mode stays bounded (the energy oscillates by O((omega dt)^2) of the
  // highest modes' share, below a factor 2), while at 1.05 x the highest mode
  // grows by ~1.5 per step (omega dt = 2.1): 3000 steps blow it up from the
  // random start or round-off.
  SECTION("DE assembly alone")
  {
    for (double factor : {0.97, 1.05})
    {
      auto b = make_bar(shell::Cell::quadrilateral);
      const double dt_c = dem::particle_critical_time_step(b.p, b.l);
      // the Gershgorin bound is on the safe side of it
      CHECK(dem::critical_time_step(b.p, b.l) <= dt_c);
      random_velocities(b.p);
      dem::DemSolver s(b.p, b.l, b.mat, factor * dt_c, 0.0, 0.5e-3);
      s.start();
      DemRun run{s};
      const double g = energy_growth(run, 3000);
      INFO("factor " << factor << ": energy growth " << g);
      CHECK((factor < 1.0 ? g < 2.0 : g > 1e6));
    }
  }
  SECTION("coupled shell / DE bar, stable at 0.97 x the coupled estimate")
  {
    auto b = make_bar(shell::Cell::quadrilateral);
    random_velocities(b.p);
    bridge::CouplingOptions o;
    o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.12, 0.08};
    const double dt_c = bridge::CoupledSolver(*b.fe, b.p, b.l, b.mat, o).dt_coupled();
    o.dt = 0.97 * dt_c; // beyond the safety factors allowed (0.95), within the estimate
    bridge::CoupledSolver s(*b.fe, b.p, b.l, b.mat, o);
    s.start(std::vector<double>(b.fe->num_dofs(), 0.0), std::vector<double>(b.fe->num_dofs(), 0.0));
    CoupledRun run{s};
    const double g = energy_growth(run, 3000);
    INFO("coupled dt " << s.dt_coupled() << " s (alone: FE " << s.dt_fe() << ", DE " << s.dt_de()
                       << "), energy growth " << g);
    CHECK(g < 2.0);
  }
}

TEST_CASE("energy guards: unstable DE and coupled runs stop on their energy, before any NaN", "[bridge][errors]")
{
  // DE alone at 1.01 x its critical step (omega dt = 2.02: the highest mode
  // grows by about 1.15 a step): the DEM's guard stops it at a check, with
  // its state still finite. (At 1.05 x the growth, ~1.5 a step, turns a
  // sphere by more than 1 rad before the first check, and the force loop's
  // own check stops the run.)
  {
    auto b = make_bar(shell::Cell::quadrilateral);
    const double dt_c = dem::particle_critical_time_step(b.p, b.l);
    random_velocities(b.p);
    dem::DemSolver s(b.p, b.l, b.mat, 1.01 * dt_c, 0.0, 0.5e-3);
    s.start();
    CHECK_THROWS_WITH([&] { for (int k = 0; k < 3000; ++k) s.step(); }(),
                      Contains("energy grows without cause") && Contains("unstable"));
    CHECK(std::all_of(b.p.v.begin(), b.p.v.end(), [](double v) { return std::isfinite(v); }));
  }
  // Coupled: energy created from nothing (every sphere's velocity scaled by
  // 10 mid-run: 100 x the kinetic energy, no work) is caught by the
  // coupler's guard within 100 steps; the sides' own guards are off (each
  // side's budget carries the multipliers' work).
  {
    auto b = make_bar(shell::Cell::quadrilateral);
    random_velocities(b.p);
    bridge::CouplingOptions o;
    o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.12, 0.08};
    bridge::CoupledSolver s(*b.fe, b.p, b.l, b.mat, o);
    s.start(std::vector<double>(b.fe->num_dofs(), 0.0), std::vector<double>(b.fe->num_dofs(), 0.0));
    for (int k = 0; k < 150; ++k)
      s.step(false);
    for (auto& v : b.p.v)
      v *= 10.0;
    CHECK_THROWS_WITH([&] { for (int k = 0; k < 100; ++k) s.step(false); }(),
                      Contains("coupled system's energy grows without cause"));
    bridge::CouplingOptions bad = o;
    bad.safety = 1.0;
    auto c = make_bar(shell::Cell::quadrilateral);
    CHECK_THROWS_WITH(bridge::CoupledSolver(*c.fe, c.p, c.l, c.mat, bad), Contains("allowed is (0, 0.95]"));
  }
}

TEST_CASE("coupled solver: bad set-ups are refused", "[bridge][coupled][errors]")
{
  auto b = make_bar(shell::Cell::quadrilateral);
  bridge::CouplingOptions o;
  o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.5, 0.4}; // beyond both regions
  CHECK_THROWS_WITH(bridge::CoupledSolver(*b.fe, b.p, b.l, b.mat, o), Contains("overlap"));
  auto c = make_bar(shell::Cell::quadrilateral);
  o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.12, 0.08};
  o.dt = 1.0;
  CHECK_THROWS_WITH(bridge::CoupledSolver(*c.fe, c.p, c.l, c.mat, o), Contains("above the coupled estimate"));
  // spheres past the band's FE edge (x < 0.10 here: weight 1, the shell's
  // alone) are refused, counted and located, the caller's masses given back
  auto d = make_bar(shell::Cell::quadrilateral);
  o.dt = 0.0;
  o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.12, 0.10};
  std::size_t past = 0;
  for (std::size_t i = 0; i < d.p.size(); ++i)
    past += d.p.x[3 * i] < 0.10;
  REQUIRE(past > 0);
  const auto masses = d.p.m;
  CHECK_THROWS_WITH(bridge::CoupledSolver(*d.fe, d.p, d.l, d.mat, o),
                    Contains(std::to_string(past) + " of the " + std::to_string(d.p.size()) + " spheres lie beyond the overlap on the FE side")
                        && Contains("planar overlap from 0.12 m (DE side) to 0.1 m (FE side)"));
  CHECK(d.p.m == masses);
  // the same with a box core: the spheres round the core's corner, past its band
  o.overlap = bridge::Overlap::box({0.16, 0.025}, {0.04, 1.0}, 0.02);
  CHECK_THROWS_WITH(bridge::CoupledSolver(*d.fe, d.p, d.l, d.mat, o), Contains("box core"));
}

TEST_CASE("coupled solver: it holds the caller's weighted state and gives it back", "[bridge][coupled]")
{
  // The coupler scales the caller's masses and inertias and fills the
  // weights; while it lives a second coupler on the same arrays would scale
  // them again, so it is refused. Destroyed, or failing in its constructor,
  // the coupler leaves the arrays exactly as they were (bit for bit: the
  // originals are kept, not divided back).
  auto b = make_bar(shell::Cell::quadrilateral);
  const std::vector<double> m0 = b.p.m, inertia0 = b.p.inertia;
  auto given_back = [&]
  {
    CHECK(b.p.m == m0);
    CHECK(b.p.inertia == inertia0);
    CHECK(b.p.weight.empty());
    CHECK(b.l.weight.empty());
    const auto eta = b.fe->weight();
    CHECK(std::all_of(eta.begin(), eta.end(), [](double e) { return e == 1.0; }));
  };
  bridge::CouplingOptions o;
  o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.12, 0.08};
  {
    bridge::CoupledSolver s(*b.fe, b.p, b.l, b.mat, o);
    CHECK(b.p.m != m0); // the overlap's and the shell side's spheres are lighter
    CHECK(b.p.weight.size() == b.p.size());
    CHECK(b.l.weight.size() == b.l.size());
    CHECK_THROWS_WITH(bridge::CoupledSolver(*b.fe, b.p, b.l, b.mat, o), Contains("already carry energy weights"));
    CHECK(b.p.weight.size() == b.p.size()); // the refusal changed nothing of the first's
  }
  given_back();
  o.dt = 1.0; // above the coupled critical step: the constructor throws late
  CHECK_THROWS_WITH(bridge::CoupledSolver(*b.fe, b.p, b.l, b.mat, o), Contains("above the coupled estimate"));
  given_back();
  o.dt = 0.0;
  bridge::CoupledSolver again(*b.fe, b.p, b.l, b.mat, o);
  CHECK(again.constrained() > 0);
}

TEST_CASE("solid coupling: a rigid motion of the solid moves the particles rigidly", "[bridge]")
{
  // P1 tetrahedra and trilinear hexahedra reproduce affine fields exactly
  const std::array<double, 3> c{0.1, 0.2, -0.3}, th{0.4, -0.2, 0.6};
  for (auto cell : {shell::Cell::hexahedron, shell::Cell::tetrahedron})
  {
    auto mesh = shell::create_solid_box(MPI_COMM_WORLD, {0.2, 0.1, 0.1}, {4, 2, 2}, cell,
                                        shell::Placement::rotation_about({1, 1, 0}, 0.5, {1, 0, 0}));
    shell::FEModel m(mesh, shell::Material{});
    const auto x = m.node_coordinates();
    // points: random convex combinations of random cells' nodes
    std::mt19937 gen(7);
    std::uniform_real_distribution<double> u01(0.05, 1.0);
    std::uniform_int_distribution<int> pick(0, int(m.num_cells()) - 1);
    std::vector<double> pts;
    for (int i = 0; i < 200; ++i)
    {
      const int cc = pick(gen);
      double wsum = 0.0, p[3] = {0, 0, 0};
      for (int k = 0; k < m.nodes_per_cell(); ++k)
      {
        const double w = u01(gen);
        wsum += w;
        for (int d = 0; d < 3; ++d)
          p[d] += w * x[3 * m.cell_nodes()[cc * m.nodes_per_cell() + k] + d];
      }
      for (double& v : p)
        v /= wsum;
      pts.insert(pts.end(), p, p + 3);
    }
    const auto op = bridge::locate_in_solid(x, m.cell_nodes(), m.nodes_per_cell(), pts);
    CHECK(op.outside() == 0);
    std::vector<double> u(3 * m.num_nodes()), v(pts.size());
    for (std::size_t k = 0; k < m.num_nodes(); ++k)
    {
      const double* p = &x[3 * k];
      u[3 * k] = c[0] + th[1] * p[2] - th[2] * p[1];
      u[3 * k + 1] = c[1] + th[2] * p[0] - th[0] * p[2];
      u[3 * k + 2] = c[2] + th[0] * p[1] - th[1] * p[0];
    }
    op.interpolate(u, v);
    double worst = 0.0;
    for (std::size_t i = 0; i < pts.size() / 3; ++i)
    {
      const double* p = &pts[3 * i];
      worst = std::max({worst, std::abs(v[3 * i] - (c[0] + th[1] * p[2] - th[2] * p[1])),
                        std::abs(v[3 * i + 1] - (c[1] + th[2] * p[0] - th[0] * p[2])),
                        std::abs(v[3 * i + 2] - (c[2] + th[0] * p[1] - th[1] * p[0]))});
    }
    CHECK(worst < 1e-12);
  }
}

TEST_CASE("coupled patch test: a uniform velocity is carried unchanged", "[bridge][coupled]")
{
  // Both sides moving at V (no clamp): nothing deforms, no correction is
  // needed, and every velocity stays V (1e-10 relative).
  auto b = make_bar(shell::Cell::quadrilateral);
  bridge::CouplingOptions o;
  o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.12, 0.08};
  bridge::CoupledSolver s(*b.fe, b.p, b.l, b.mat, o);
  const std::array<double, 3> V{0.3, -0.2, 0.1};
  std::vector<double> u(b.fe->num_dofs(), 0.0), v(b.fe->num_dofs(), 0.0);
  for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
    for (int d = 0; d < 3; ++d)
      v[6 * k + d] = V[d];
  for (std::size_t i = 0; i < b.p.size(); ++i)
    for (int d = 0; d < 3; ++d)
      b.p.v[3 * i + d] = V[d];
  s.start(u, v);
  for (int k = 0; k < 200; ++k)
    s.step();
  // Everything keeps moving at V up to round-off. Three round-off sources
  // would make the links strain under a mere translation (each measured
  // here at 1e-10 of V or more over 200 steps), and the DEM avoids each:
  // - x + V dt rounded sphere by sphere, each position in its own binade,
  //   makes the branches between spheres jitter: positions are multiples
  //   of a common quantum and move by multiples of it (Particles::quantum),
  //   so their differences are exact and equal velocities leave them as
  //   they are;
  // - a trial shear that cancels terms of size K_s D gives a link at rest
  //   K_s D eps of shear each step: it is evaluated with R - I instead;
  // - a link's stored normal must have the force loop's bits.
  // What is left is the corrections' round-off, 5.3e-14 m/s on every
  // particle and on the shell nodes (1.8e-13 of V): G_FE sums node
  // velocities with weights adding up to 1 within eps.
  // Bound: the required 1e-10 of V, for every particle and node.
  double de = 0.0, fe = 0.0, spin = 0.0;
  for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
    for (int d = 0; d < 3; ++d)
    {
      fe = std::max(fe, std::abs(s.fe().v()[6 * k + d] - V[d]));
      spin = std::max(spin, std::abs(s.fe().v()[6 * k + 3 + d]));
    }
  double de_overlap = 0.0;
  for (std::size_t i = 0; i < b.p.size(); ++i)
    for (int d = 0; d < 3; ++d)
    {
      de = std::max(de, std::abs(b.p.v[3 * i + d] - V[d]));
      if (b.p.x[3 * i] > 0.08 && b.p.x[3 * i] < 0.12)
        de_overlap = std::max(de_overlap, std::abs(b.p.v[3 * i + d] - V[d]));
      spin = std::max(spin, std::abs(b.p.w[3 * i + d]));
    }
  // relative to |V|, as Euclidean norms per node / particle
  const double vn = std::sqrt(V[0] * V[0] + V[1] * V[1] + V[2] * V[2]);
  double rel_fe = 0.0, rel_de = 0.0;
  for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
  {
    double e2 = 0.0;
    for (int d = 0; d < 3; ++d)
      e2 += std::pow(s.fe().v()[6 * k + d] - V[d], 2);
    rel_fe = std::max(rel_fe, std::sqrt(e2) / vn);
  }
  for (std::size_t i = 0; i < b.p.size(); ++i)
    if (b.p.x[3 * i] > 0.08 && b.p.x[3 * i] < 0.12)
    {
      double e2 = 0.0;
      for (int d = 0; d < 3; ++d)
        e2 += std::pow(b.p.v[3 * i + d] - V[d], 2);
      rel_de = std::max(rel_de, std::sqrt(e2) / vn);
    }
  INFO("particles off by " << de << " m/s (in the overlap " << de_overlap << "), shell nodes by "
                           << fe << " m/s, largest rotation rate " << spin << " rad/s; relative "
                           << rel_de << " (overlap particles), " << rel_fe << " (shell nodes)");
  CHECK(de < 1e-10 * 0.3);
  CHECK(de_overlap < 1e-10 * 0.3);
  CHECK(fe < 1e-10 * 0.3);
  CHECK(rel_de < 1e-10);
  CHECK(rel_fe < 1e-10);
  // spins: the surface velocity they give, omega R_max (measured 8e-12
  // rad/s, 2e-14 m/s)
  const double rmax = *std::max_element(b.p.r.begin(), b.p.r.end());
  CHECK(spin * rmax < 1e-10 * 0.3);
}

TEST_CASE("coupled patch test: a rigid rotation is carried by both sides", "[bridge][coupled]")
{
  // Both sides start with the velocity field of a rigid rotation omega about
  // a point c (shell nodes omega x (x - c) with rotation rates omega;
  // spheres the same, spinning at omega). An infinitesimal rotation strains
  // neither the linear shell nor the links, and the fictive nodes
  // u + z theta x n_bar interpolate omega x (x - c) exactly (checked alone
  // to 1e-12 in test_bridge_fictive), so to first order nothing changes.
  // What is left is second order in omega t: the spheres drift along
  // straight lines, a link of length l stretches by l (omega t)^2 / 2 and
  // its force K l (omega t)^2 / 2 changes velocities by about
  // (K / m) l (omega t)^2 t / 2 = 2.4e-7 m/s here (K / m <= 5e11 1/s^2,
  // l = 6 mm, |omega| t = 3.9e-6 rad over 10 steps), 1e-5 of the motion:
  // the required 1e-10 cannot hold through time stepping for a linear shell
  // and a finite-rotation DE. So the test checks that the deviation is below
  // that estimate and second order: halving omega divides it by about 4. A
  // wrong rotation convention or interpolation would show at first order,
  // ~1e-2 m/s. Before any step, the multiplier correction of start() must
  // leave both rigid fields as they are to the required 1e-10 (kinematic
  // patch test: nothing to correct).
  auto b = make_bar(shell::Cell::quadrilateral);
  const std::vector<double> x0 = b.p.x;
  const dem::Particles p0 = b.p;
  struct Off
  {
    double de, fe, vmax;
  };
  auto run = [&](double scale)
  {
    b.p = p0;
    dem::Links l = b.l;
    bridge::CouplingOptions o;
    o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.12, 0.08};
    bridge::CoupledSolver s(*b.fe, b.p, l, b.mat, o);
    const std::array<double, 3> om{0.2 * scale, -0.1 * scale, 0.3 * scale}, c{0.1, 0.02, 0.0};
    auto rigid = [&](const double* x)
    {
      const double r[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
      return std::array<double, 3>{om[1] * r[2] - om[2] * r[1], om[2] * r[0] - om[0] * r[2],
                                   om[0] * r[1] - om[1] * r[0]};
    };
    const auto xn = b.fe->node_coordinates();
    std::vector<double> u(b.fe->num_dofs(), 0.0), v(b.fe->num_dofs(), 0.0);
    for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
    {
      const auto vk = rigid(&xn[3 * k]);
      for (int d = 0; d < 3; ++d)
      {
        v[6 * k + d] = vk[d];
        v[6 * k + 3 + d] = om[d];
      }
    }
    for (std::size_t i = 0; i < b.p.size(); ++i)
    {
      const auto vi = rigid(&x0[3 * i]);
      for (int d = 0; d < 3; ++d)
      {
        b.p.v[3 * i + d] = vi[d];
        b.p.w[3 * i + d] = om[d];
      }
    }
    auto measure = [&]
    {
      Off off{0.0, 0.0, 0.0};
      for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
      {
        const auto vk = rigid(&xn[3 * k]);
        for (int d = 0; d < 3; ++d)
        {
          off.vmax = std::max(off.vmax, std::abs(vk[d]));
          off.fe = std::max({off.fe, std::abs(s.fe().v()[6 * k + d] - vk[d]),
                             std::abs(s.fe().v()[6 * k + 3 + d] - om[d]) * 0.05}); // x lever arm
        }
      }
      for (std::size_t i = 0; i < b.p.size(); ++i)
        if (x0[3 * i] > 0.08 && x0[3 * i] < 0.12)
        {
          const auto vi = rigid(&x0[3 * i]);
          for (int d = 0; d < 3; ++d)
            off.de = std::max({off.de, std::abs(b.p.v[3 * i + d] - vi[d]),
                               std::abs(b.p.w[3 * i + d] - om[d]) * 3e-3}); // x radius
        }
      return off;
    };
    // start() applies the multiplier correction: the two sides' rigid
    // fields already satisfy the constraint, so it must change nothing (the
    // kinematic patch test, the required 1e-10 of the motion)
    s.start(u, v);
    const Off at_start = measure();
    for (int k = 0; k < 10; ++k)
      s.step();
    return std::pair{at_start, measure()};
  };
  const auto [start_full, full] = run(1.0);
  const Off half = run(0.5).second;
  INFO("after the first correction: overlap spheres off by " << start_full.de
                                                             << " m/s, shell nodes by "
                                                             << start_full.fe << " m/s");
  CHECK(start_full.de < 1e-10 * start_full.vmax);
  CHECK(start_full.fe < 1e-10 * start_full.vmax);
  INFO("overlap spheres off by " << full.de << " m/s (half omega: " << half.de
                                 << "), shell nodes by " << full.fe << " m/s (" << half.fe
                                 << "), largest velocity " << full.vmax << " m/s");
  CHECK(full.de < 2.4e-7);
  CHECK(full.fe < 2.4e-7);
  // second order: x 1/4 with half omega (3 allows for round-off)
  CHECK(half.de < full.de / 3.0);
  CHECK(half.fe < full.fe / 3.0);
}

TEST_CASE("coupled bar: energy kept over 20 periods", "[bridge][coupled]")
{
  // undamped axial free vibration of the clamped coupled bar, 20 periods of
  // the first axial mode: total energy within 0.5 % (the required bound)
  auto b = make_bar(shell::Cell::quadrilateral);
  bridge::CouplingOptions o;
  o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.12, 0.08};
  bridge::CoupledSolver s(*b.fe, b.p, b.l, b.mat, o);
  const auto x = b.fe->node_coordinates();
  const auto clamp = clamp_dofs(*b.fe, [](const auto& q) { return q[0] < 1e-9; });
  s.fe().add_motion({"clamp", clamp, shell::MotionKind::fixed, {}});
  std::vector<double> u(b.fe->num_dofs(), 0.0), v(b.fe->num_dofs(), 0.0);
  for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
    v[6 * k] = 1e-3 * std::sin(0.5 * std::numbers::pi * x[3 * k] / 0.2);
  for (std::size_t i = 0; i < b.p.size(); ++i)
    b.p.v[3 * i] = 1e-3 * std::sin(0.5 * std::numbers::pi * b.p.x[3 * i] / 0.2);
  s.start(u, v);
  double e0 = s.energy().total();
  const int steps = static_cast<int>(20.0 / 4350.0 / s.dt());
  double drift = 0.0;
  for (int k = 0; k < steps; ++k)
  {
    s.step();
    if (k % 50 == 0)
      drift = std::max(drift, std::abs(s.energy().total() - e0) / e0);
  }
  INFO(steps << " steps, drift " << drift);
  CHECK(drift < 5e-3);
}

namespace
{
/// The wave tests' strips: shells of the default concrete's E and nu (as
/// measured on its calibration sample), h thick ...
shell::Material strip_shell(double h)
{
  shell::Material sm;
  sm.thickness = h;
  const auto mf = dem::read_material(DEMBRIDGE_SOURCE_DIR "/demos/calibrate/materials/default.json");
  sm.youngs_modulus = mf.macroscopic.value("youngs_modulus_pa", 30e9);
  sm.poisson_ratio = mf.macroscopic.value("poisson_ratio", 0.2);
  return sm;
}

/// ... and its spheres: of mean radius strip_radius, packed in the box
/// [lo, hi], elastic links.
constexpr double strip_radius = 3e-3;

struct StripSpheres
{
  dem::Particles p;
  dem::Links l;
  dem::Material mat;
};

StripSpheres strip_spheres(const dem::Point& lo, const dem::Point& hi)
{
  dem::PackingOptions po;
  po.mean_radius = strip_radius;
  const auto region = dem::box_region(lo, hi);
  const auto pk = dem::generate_packing(region, po);
  double solid = 0.0;
  for (double r : pk.r)
    solid += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  StripSpheres b;
  b.mat = dem::read_material(DEMBRIDGE_SOURCE_DIR "/demos/calibrate/materials/default.json").material;
  b.mat.tensile = b.mat.cohesion = 1e12;
  b.p = dem::make_particles(pk.x, pk.r, b.mat.density, solid / region.volume);
  b.l = dem::create_links(b.p, dem::lambda_for_mean_links(b.p.x, b.p.r, 12.0), b.mat);
  return b;
}

/// Runs the pulse test: from the shell into the DE (fe_to_de) or back;
/// returns {reflected fraction, fraction that arrived on the far side}.
std::pair<double, double> pulse(bool fe_to_de)
{
  // Shell strip on [0, 0.3] m, DE box on [0.22, 0.5] m, overlap [0.22, 0.3]
  // (8 cm: about 13 mean DE diameters and 16 shell elements). A right-going
  // longitudinal pulse (cosine bell, 8 cm long) starts in the FE-only
  // region. Once it has crossed, the energy left in the FE-only region is
  // the reflected part: below 5 % of the pulse's energy (the required bound;
  // measured 2.5 %). A 4 cm overlap (7 diameters) reflects 9.7 %: the
  // overlap must span many DE diameters.
  const double w = 0.05, h = 0.05, L = 0.5, xfe = 0.3, xde = 0.22;
  const shell::Material sm = strip_shell(h);
  auto mesh = shell::create_shell_rectangle(MPI_COMM_WORLD, xfe, w, 60, 5, shell::Cell::quadrilateral);
  shell::FEModel fe(mesh, sm);
  auto spheres = strip_spheres({xde, 0, -0.5 * h}, {L, w, 0.5 * h});
  auto& p = spheres.p;
  auto& l = spheres.l;
  const auto& mat = spheres.mat;
  bridge::CouplingOptions o;
  o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, xfe, xde};
  bridge::CoupledSolver s(fe, p, l, mat, o);
  // bell u(x) = A (1 + cos(2 pi (x - x0) / lp)) / 2 on |x - x0| < lp / 2,
  // travelling towards the other side: v = -+ c du/dx
  const double c = std::sqrt(sm.youngs_modulus / sm.density), A = 1e-7, lp = 0.08;
  const double x0 = fe_to_de ? 0.1 : 0.42, dir = fe_to_de ? 1.0 : -1.0;
  auto bell = [&](double xx, double& uu, double& vv)
  {
    uu = vv = 0.0;
    const double d = xx - x0;
    if (std::abs(d) < 0.5 * lp)
    {
      const double ph = 2.0 * std::numbers::pi * d / lp;
      uu = 0.5 * A * (1.0 + std::cos(ph));
      vv = dir * c * 0.5 * A * 2.0 * std::numbers::pi / lp * std::sin(ph);
    }
  };
  const auto x = fe.node_coordinates();
  std::vector<double> u(fe.num_dofs(), 0.0), v(fe.num_dofs(), 0.0);
  if (fe_to_de)
    for (std::size_t k = 0; k < fe.num_nodes(); ++k)
      bell(x[3 * k], u[6 * k], v[6 * k]);
  else
  {
    // into the DE from its free end: the end layer pushed along -x with a
    // smooth velocity bell in time, lp / c long, then held (it is far from
    // the overlap; whatever the overlap reflects is still on its way back
    // when measured). A velocity field imposed on the particles themselves
    // would strain the disordered packing non-affinely: vibrations that are
    // no wave.
    const double T = lp / c, V = A * std::numbers::pi / lp * c;
    s.de().add_motion({"end", dem::DemSolver::select(p, [&](const auto& q) { return q[0] > L - 2 * strip_radius; }, "end"),
                       dem::MotionKind::velocity, {true, false, false},
                       [=](double t) { return t < T ? -V * 0.5 * (1.0 - std::cos(2.0 * std::numbers::pi * t / T)) : 0.0; }});
  }
  s.start(u, v);
  double e0 = s.energy().total();
  // run until the pulse has crossed: centre from 0.1 to ~0.41, or from the
  // the end (0.5 + lp / 2 at t = 0 for a bell in time) to ~0.04, in the
  // FE-only region also if the DE wave is a little slower than c
  const int steps = static_cast<int>(((fe_to_de ? 0.31 : 0.5) / c) / s.dt());
  for (int k = 0; k < steps; ++k)
    s.step();
  if (!fe_to_de)
    e0 = s.energy().de.prescribed_work; // what the end's motion put in
  // energy left in the region the pulse came from (FE-only x < xde, or
  // DE-only x > xfe): kinetic + strain ~ 2 x kinetic for travelling waves
  const auto m = fe.lumped_mass();
  double ke = 0.0;
  if (fe_to_de)
  {
    for (std::size_t k = 0; k < fe.num_nodes(); ++k)
      if (x[3 * k] < xde - 0.01)
        for (int d = 0; d < 3; ++d)
          ke += 0.5 * m[6 * k + d] * s.fe().v()[6 * k + d] * s.fe().v()[6 * k + d];
  }
  else
  {
    // the wave's kinetic energy in the DE: that of the mean velocity of
    // slabs 1 cm thick (3 diameters, ~170 spheres each). The particles'
    // own vibrations about it (excited at the start, where the bell's smooth
    // displacement field strains the disordered packing non-affinely) do not
    // travel as a wave and are no reflection.
    const int nslab = static_cast<int>(std::round((L - xfe - 0.01) / 0.01));
    std::vector<double> ms(nslab, 0.0), ps(3 * nslab, 0.0);
    double raw = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (p.x0[3 * i] > xfe + 0.01)
      {
        const int k = std::min(nslab - 1, static_cast<int>((p.x0[3 * i] - xfe - 0.01) / 0.01));
        ms[k] += p.m[i];
        for (int d = 0; d < 3; ++d)
        {
          ps[3 * k + d] += p.m[i] * p.v[3 * i + d];
          raw += 0.5 * p.m[i] * p.v[3 * i + d] * p.v[3 * i + d];
        }
      }
    for (int k = 0; k < nslab; ++k)
      for (int d = 0; d < 3; ++d)
        ke += 0.5 * ps[3 * k + d] * ps[3 * k + d] / ms[k];
    UNSCOPED_INFO("particle kinetic energy left in the DE-only region " << raw / e0
                  << " E0, of which the slabs' mean motion " << ke / e0 << " E0");
  }
  const auto e = s.energy();
  const double arrived = fe_to_de ? (e.de.kinetic + e.de.elastic) / e0 : (e.fe.kinetic + e.fe.strain) / e0;
  INFO("pulse " << (fe_to_de ? "FE -> DE" : "DE -> FE") << ": " << p.size() << " spheres, " << steps
                << " steps; reflected " << 2.0 * ke / e0 << " E0, arrived " << arrived << " E0");
  return {2.0 * ke / e0, arrived};
}
} // namespace

TEST_CASE("wave transmission: a pulse crosses the overlap with little reflection",
          "[bridge][coupled]")
{
  // reflected energy below 5 % (the required bound), most of it arrived.
  // Both ways: from the shell into the DE (measured: 2.5 % reflected, 83 %
  // arrived) and from the DE's free end into the shell (2.1 % reflected as a
  // wave, 83 % arrived; the DE-only region also keeps ~11 % as the
  // particles' own vibrations, scattered by the disordered packing, and the
  // overlap's projection filters what the shell cannot carry).
  const auto [reflected, arrived] = pulse(true);
  CHECK(reflected < 0.05);
  CHECK(arrived > 0.8);
  const auto [back, arrived_back] = pulse(false);
  CHECK(back < 0.05);
  CHECK(arrived_back > 0.8);
}

namespace
{
/// The shells' state of a strip of 5 mm quadrilaterals, 0.05 m wide and
/// thick, after `steps` steps from the bending pulse w(x) (a cosine bell
/// 12 cm long about x = 0.1 m, at rest): alone on [0, 0.5] m, or on [0, 0.3]
/// coupled to spheres of 3 mm on [0.22, 0.5] m (the strip of the pulse test
/// above). Returns the velocities of the nodes with x < 0.21 m, node by
/// node in order of x then y, and their lumped masses; `e0` the pulse's
/// energy.
struct StripState
{
  std::vector<double> v, m;
  double e0 = 0.0, dt = 0.0;
  int steps = 0;
};

/// `duration` [s] at the coupled step; alone, `steps` steps of `dt`.
StripState bending_strip(bool coupled, double duration, int steps = 0, double dt = 0.0)
{
  const double w = 0.05, h = 0.05, L = 0.5, xfe = 0.3, xde = 0.22, A = 1e-6, lp = 0.12, x0 = 0.1;
  const shell::Material sm = strip_shell(h);
  const double length = coupled ? xfe : L;
  shell::FEModel fe(shell::create_shell_rectangle(MPI_COMM_WORLD, length, w, static_cast<int>(std::round(length / 0.005)),
                                                  10, shell::Cell::quadrilateral),
                    sm);
  const auto x = fe.node_coordinates();
  std::vector<double> u(fe.num_dofs(), 0.0), v(fe.num_dofs(), 0.0);
  for (std::size_t k = 0; k < fe.num_nodes(); ++k)
  {
    const double d = x[3 * k] - x0;
    if (std::abs(d) < 0.5 * lp)
    {
      u[6 * k + 2] = 0.5 * A * (1.0 + std::cos(2.0 * std::numbers::pi * d / lp));
      u[6 * k + 4] = 0.5 * A * 2.0 * std::numbers::pi / lp * std::sin(2.0 * std::numbers::pi * d / lp); // -dw/dx
    }
  }
  StripState out;
  auto read = [&](std::span<const double> vel, const std::vector<double>& mass)
  {
    std::vector<std::size_t> order;
    for (std::size_t k = 0; k < fe.num_nodes(); ++k)
      if (x[3 * k] < xde - 0.01)
        order.push_back(k);
    std::sort(order.begin(), order.end(), [&](auto a, auto b)
              { return std::pair{x[3 * a], x[3 * a + 1]} < std::pair{x[3 * b], x[3 * b + 1]}; });
    for (auto k : order)
      for (int d = 0; d < 6; ++d)
      {
        out.v.push_back(vel[6 * k + d]);
        out.m.push_back(mass[6 * k + d]);
      }
  };
  if (!coupled)
  {
    out.steps = steps;
    shell::ExplicitSolver s(fe.lumped_mass(), fe.internal_force_fn(), dt);
    s.set_state(u, v);
    out.e0 = s.energy().initial;
    for (int k = 0; k < steps; ++k)
      s.step();
    read(s.v(), fe.lumped_mass());
    return out;
  }
  auto spheres = strip_spheres({xde, 0, -0.5 * h}, {L, w, 0.5 * h});
  auto& p = spheres.p;
  auto& l = spheres.l;
  const auto& mat = spheres.mat;
  bridge::CouplingOptions o;
  o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, xfe, xde};
  bridge::CoupledSolver s(fe, p, l, mat, o);
  out.dt = s.dt();
  out.steps = static_cast<int>(duration / s.dt());
  s.start(u, v);
  out.e0 = s.energy().total();
  for (int k = 0; k < out.steps; ++k)
    s.step(false);
  s.observe();
  read(s.fe().v(), fe.lumped_mass());
  return out;
}
} // namespace

TEST_CASE("wave transmission: a bending pulse crosses the overlap with little reflection", "[bridge][coupled]")
{
  // A bending pulse (w a cosine bell 12 cm long, at rest, with the matching
  // rotation) splits into two waves; the right-going one crosses the 8 cm
  // overlap into the spheres. Bending waves disperse, and part of the bell
  // lingers, so the energy left in the FE-only region says nothing alone:
  // the reflection is the kinetic energy of the difference between the
  // coupled strip's shells and the all-shell strip's, node by node in the
  // FE-only region (x < 0.21 m), times 2 (a wave's energy is half kinetic),
  // over the energy the right-going wave carries (half the pulse's). Bound
  // 5 %, as for the membrane pulse; measured 2.9 %. Shorter pulses reflect
  // more (6, 8, 12, 16 cm: 6.9, 6.1, 2.9, 1.9 %; validation.md 5.5): the
  // bound holds for bending waves 1.5 overlap widths long and longer. The
  // run lasts until the fastest part, at the shear wave speed, has crossed
  // the overlap and come back to the FE-only region.
  const double c_shear = std::sqrt(30e9 / (2.0 * 1.2 * 2400.0));
  const auto coupled = bending_strip(true, (0.18 + 0.24) / c_shear);
  const auto alone = bending_strip(false, 0.0, coupled.steps, coupled.dt);
  const int steps = coupled.steps;
  REQUIRE(coupled.v.size() == alone.v.size());
  double ke = 0.0;
  for (std::size_t i = 0; i < coupled.v.size(); ++i)
    ke += 0.5 * coupled.m[i] * (coupled.v[i] - alone.v[i]) * (coupled.v[i] - alone.v[i]);
  const double reflected = 2.0 * ke / (0.5 * alone.e0);
  INFO("bending pulse FE -> DE: " << steps << " steps; reflected " << reflected << " of the right-going wave's energy");
  CHECK(reflected < 0.05);
  CHECK(std::abs(coupled.e0 / alone.e0 - 1.0) < 1e-6); // the same pulse in both
}

TEST_CASE("the coupled model rotated and moved in space gives the same results", "[bridge][coupled]")
{
  // Same bar, same packing, rigidly placed elsewhere; same time step. The
  // axial tip displacement (projected on the bar axis) after 400 steps of
  // free vibration agrees to 1e-8 relative (round-off only).
  auto run = [](const shell::Placement& place)
  {
    auto b = make_bar(shell::Cell::quadrilateral);
    // move the shell mesh and the particles
    auto mesh = shell::create_shell_rectangle(MPI_COMM_WORLD, 0.12, 0.05, 12, 5,
                                              shell::Cell::quadrilateral, place);
    shell::Material sm;
    sm.thickness = 0.05;
    b.fe = std::make_unique<shell::FEModel>(mesh, sm);
    for (std::size_t i = 0; i < b.p.size(); ++i)
    {
      const auto y = place.apply({b.p.x[3 * i], b.p.x[3 * i + 1], b.p.x[3 * i + 2]});
      for (int d = 0; d < 3; ++d)
        b.p.x[3 * i + d] = b.p.x0[3 * i + d] = y[d];
    }
    // the links' stored normals turn with the assembly
    for (std::size_t k = 0; k < b.l.size(); ++k)
    {
      const auto& R = place.rotation;
      const double n[3] = {b.l.n[3 * k], b.l.n[3 * k + 1], b.l.n[3 * k + 2]};
      for (int d = 0; d < 3; ++d)
        b.l.n[3 * k + d] = R[3 * d] * n[0] + R[3 * d + 1] * n[1] + R[3 * d + 2] * n[2];
    }
    const std::array<double, 3> ax{place.rotation[0], place.rotation[3], place.rotation[6]};
    const double s0 = ax[0] * place.origin[0] + ax[1] * place.origin[1] + ax[2] * place.origin[2];
    bridge::CouplingOptions o;
    o.overlap = bridge::PlanarOverlap{ax, s0 + 0.12, s0 + 0.08};
    o.dt = 1e-7;
    bridge::CoupledSolver s(*b.fe, b.p, b.l, b.mat, o);
    const auto x = b.fe->node_coordinates();
    auto axial = [&](const double* p)
    { return ax[0] * p[0] + ax[1] * p[1] + ax[2] * p[2] - s0; };
    const auto clamp = clamp_dofs(*b.fe, [&](const auto& q) { return std::abs(axial(q.data())) < 1e-9; });
    s.fe().add_motion({"clamp", clamp, shell::MotionKind::fixed, {}});
    std::vector<double> u(b.fe->num_dofs(), 0.0), v(b.fe->num_dofs(), 0.0);
    for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
      for (int d = 0; d < 3; ++d)
        v[6 * k + d] = 1e-3 * std::sin(0.5 * std::numbers::pi * axial(&x[3 * k]) / 0.2) * ax[d];
    for (std::size_t i = 0; i < b.p.size(); ++i)
      for (int d = 0; d < 3; ++d)
        b.p.v[3 * i + d] = 1e-3 * std::sin(0.5 * std::numbers::pi * axial(&b.p.x[3 * i]) / 0.2) * ax[d];
    s.start(u, v);
    for (int k = 0; k < 400; ++k)
      s.step();
    double tip = 0.0;
    int n = 0;
    for (std::size_t i = 0; i < b.p.size(); ++i)
      if (axial(&b.p.x0[3 * i]) > 0.19)
      {
        for (int d = 0; d < 3; ++d)
          tip += (b.p.x[3 * i + d] - b.p.x0[3 * i + d]) * ax[d];
        ++n;
      }
    return tip / n;
  };
  const double a = run({}), b = run(shell::Placement::rotation_about({1, 2, 3}, 0.9, {0.4, -0.3, 1.1}));
  INFO("tip " << a << " vs " << b);
  CHECK(std::abs(a) > 0.0);
  CHECK(std::abs(b / a - 1.0) < 1e-8);
}

TEST_CASE("coupled step: skipping the full-step projection leaves the motion unchanged", "[bridge][coupled]")
{
  // CoupledSolver::step(false) leaves v(n+1) unprojected; the next half-step
  // velocities are projected anyway (the projection is linear), so without
  // damping the positions, and the velocities once projected at the last
  // step, are the same to round-off. With damping the solver projects
  // anyway: skipping would change the path (the two sides damp with
  // different velocities -- the shell's acceleration holds -c v(n+1/2), the
  // spheres' kick -c v(n+1); measured 2e-4 to 9e-4 of the largest after 300
  // steps at c = 2000 1/s with the projection skipped). From the first axial mode's
  // velocities, 300 steps.
  struct End
  {
    std::vector<double> x, v, u;
    std::vector<double> residual; // step()'s return value at each step
  };
  auto run = [](bool skip, double c)
  {
    auto b = make_bar(shell::Cell::quadrilateral);
    bridge::CouplingOptions o;
    o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.12, 0.08};
    o.damping_fe = o.damping_de = c;
    bridge::CoupledSolver s(*b.fe, b.p, b.l, b.mat, o);
    const int bs = b.fe->block_size();
    const auto x = b.fe->node_coordinates();
    s.fe().add_motion({"clamp", clamp_dofs(*b.fe, [](const auto& q) { return q[0] < 1e-9; }),
                       shell::MotionKind::fixed, {}});
    std::vector<double> u(b.fe->num_dofs(), 0.0), v(b.fe->num_dofs(), 0.0);
    for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
      v[bs * k] = 1e-3 * std::sin(0.5 * std::numbers::pi * x[3 * k] / 0.2);
    for (std::size_t i = 0; i < b.p.size(); ++i)
      b.p.v[3 * i] = 1e-3 * std::sin(0.5 * std::numbers::pi * b.p.x[3 * i] / 0.2);
    s.start(u, v);
    std::vector<double> r;
    for (int k = 1; k <= 300; ++k)
      r.push_back(s.step(!skip || k == 300));
    End e{{b.p.x.begin(), b.p.x.end()}, {b.p.v.begin(), b.p.v.end()}, {s.fe().u().begin(), s.fe().u().end()}, r};
    for (std::size_t i = 0; i < e.x.size(); ++i)
      e.x[i] -= b.p.x0[i];
    return e;
  };
  // largest difference over the largest value
  auto diff = [](const std::vector<double>& a, const std::vector<double>& b)
  {
    double d = 0.0, m = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i)
    {
      d = std::max(d, std::abs(a[i] - b[i]));
      m = std::max(m, std::abs(a[i]));
    }
    return d / m;
  };
  for (double c : {0.0, 2000.0}) // 1/s; c dt ~ 1e-3 a step
  {
    const End all = run(false, c), skipped = run(true, c);
    INFO("damping " << c << " 1/s: largest differences, particle displacement " << diff(all.x, skipped.x)
                    << ", velocity " << diff(all.v, skipped.v) << ", shell " << diff(all.u, skipped.u));
    // round-off over 300 steps of sums over ~1,000 particles: 1e-9 of the
    // largest (measured 1.3e-12 undamped)
    CHECK(diff(all.x, skipped.x) < 1e-9);
    CHECK(diff(all.v, skipped.v) < 1e-9);
    CHECK(diff(all.u, skipped.u) < 1e-9);
    // the residual: computed where observed, round-off of velocities
    // ~1e-3 m/s; unobserved steps return the last observed one (here the
    // start's correction) and do not compute a new one
    for (int k = 0; k < 300; ++k)
    {
      INFO("step " << k + 1);
      CHECK(all.residual[k] < 1e-12);
      if (k < 299)
        CHECK(skipped.residual[k] == skipped.residual[0]);
    }
    CHECK(skipped.residual[299] < 1e-12);
  }
}

TEST_CASE("restart: a coupled run continued from a checkpoint is the uninterrupted run bit for bit",
          "[bridge][coupled][restart]")
{
  // The damped coupled bar from its first axial mode's velocities: 300
  // steps, or 140, a checkpoint, a new coupler set up alike and 160 more.
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / ("dembridge-coupled-restart-" + std::to_string(::getpid()) + ".h5");
  struct Run
  {
    Bar b = make_bar(shell::Cell::quadrilateral);
    std::unique_ptr<bridge::CoupledSolver> s;
    Run()
    {
      bridge::CouplingOptions o;
      o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.12, 0.08};
      o.damping_fe = o.damping_de = 2000.0;
      s = std::make_unique<bridge::CoupledSolver>(*b.fe, b.p, b.l, b.mat, o);
      const int bs = b.fe->block_size();
      const auto x = b.fe->node_coordinates();
      s->fe().add_motion({"clamp", clamp_dofs(*b.fe, [](const auto& q) { return q[0] < 1e-9; }),
                          shell::MotionKind::fixed, {}});
      std::vector<double> u(b.fe->num_dofs(), 0.0), v(b.fe->num_dofs(), 0.0);
      for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
        v[bs * k] = 1e-3 * std::sin(0.5 * std::numbers::pi * x[3 * k] / 0.2);
      for (std::size_t i = 0; i < b.p.size(); ++i)
        b.p.v[3 * i] = 1e-3 * std::sin(0.5 * std::numbers::pi * b.p.x[3 * i] / 0.2);
      s->start(u, v);
    }
  };
  const int total = 300, at = 140;
  Run whole;
  for (int k = 0; k < total; ++k)
    whole.s->step(k % 7 == 0);
  {
    Run first;
    for (int k = 0; k < at; ++k)
      first.s->step(k % 7 == 0);
    auto f = checkpoint::File::create(file, "coupled test");
    first.s->save(f.root().group("coupled"));
    f.commit();
  }
  Run resumed;
  resumed.s->load(checkpoint::File::open(file, "coupled test").root().group("coupled"));
  for (int k = at; k < total; ++k)
    resumed.s->step(k % 7 == 0);
  fs::remove(file);
  // exact comparisons on purpose: a restart must be bit for bit
  CHECK(resumed.b.p.x == whole.b.p.x);
  CHECK(resumed.b.p.v == whole.b.p.v);
  auto vec = [](std::span<const double> s) { return std::vector<double>(s.begin(), s.end()); };
  CHECK(vec(resumed.s->fe().u()) == vec(whole.s->fe().u()));
  CHECK(vec(resumed.s->fe().v()) == vec(whole.s->fe().v()));
  const auto a = whole.s->energy(), e = resumed.s->energy();
  CHECK(e.total() == a.total());
  CHECK(e.imbalance() == a.imbalance());
}

TEST_CASE("bars across the overlap: a load on the shells reaches the bar's anchor through the tied bar nodes",
          "[bridge][coupled][bars][long]")
{
  // The small bar: shells on [0, 0.12] m, spheres on [0.08, 0.2] m, the
  // overlap [0.08, 0.12]. A 6 mm steel bar along the axis from the band's
  // FE edge (x = 0.08) into the DE end, bonded to the spheres (embedded),
  // its last node held (the anchor). The shells' free end is pulled by
  // F = 1 kN, ramped over 0.2 ms and held, with damping at about half the
  // first mode's critical. The concrete's far end is free, so in statics
  // the whole load reaches the anchor: its reaction must balance F within
  // 1 % (the bound; measured 0.7 % off at 1.2 ms, 2e-5 at 2.4 ms:
  // what is left is the motion the damping has not yet taken out). The bar's nodes in the overlap are tied to the
  // shells like the spheres, and the bar's elements are weighted (1 - eta).
  auto b = make_bar(shell::Cell::quadrilateral);
  dem::Steel steel;
  steel.yield = 1e10; // elastic here
  steel.rupture_strain = 0.5;
  const dem::BarLine line{{{0.08, 0.025, 0.0}, {0.196, 0.025, 0.0}}, 0.006, 0, 0};
  dem::Bars bars = dem::make_bars(std::span<const dem::BarLine>(&line, 1), {steel}, {dem::BondLaw{}}, 4e-3);
  bars.sphere_contacts = false;
  REQUIRE(dem::create_bonds(bars, b.p, 1e-3) > 10);
  const double full_area = bars.area[0];
  bridge::CouplingOptions o;
  o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.12, 0.08};
  o.damping_fe = o.damping_de = 3e4; // 1/s: the first axial mode, about 4.4 kHz, damped at about 0.5 critical
  bridge::CoupledSolver s(*b.fe, b.p, b.l, b.mat, o, bars);
  CHECK(s.constrained_bar_nodes() >= 10); // the band's 40 mm at 4 mm elements
  // the weights: an element's area scales with 1 - eta at its middle (the
  // first element's about 2 mm into the band of 40 mm: about 0.05)
  const dem::Bars& w = s.de().bars();
  const double mid = 0.5 * (w.x[3 * w.a[0]] + w.x[3 * w.b[0]]);
  CHECK(std::abs(w.area[0] / full_area - (mid - 0.08) / 0.04) < 1e-12);
  CHECK(w.area.back() == full_area);
  const std::int32_t anchor = static_cast<std::int32_t>(w.nodes() - 1);
  const std::size_t g = s.de().move_bar_nodes(std::span<const std::int32_t>(&anchor, 1), {0.0, 0.0, 0.0});
  // the load on the shells' free end, shared by its nodes
  const auto x = b.fe->node_coordinates();
  std::vector<std::int32_t> dofs;
  for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
    if (x[3 * k] < 1e-9)
      dofs.push_back(static_cast<std::int32_t>(6 * k));
  const double F = 1e3, ramp = 2e-4;
  s.fe().add_load({"pull", dofs, std::vector<double>(dofs.size(), -1.0 / double(dofs.size())),
                   [=](double t) { return F * std::min(t / ramp, 1.0); }});
  std::vector<double> u(b.fe->num_dofs(), 0.0), v(b.fe->num_dofs(), 0.0);
  s.start(u, v);
  double residual = 0.0;
  while (s.de().time() < 2.4e-3)
    residual = std::max(residual, s.step());
  const double reaction = s.de().bar_reaction(g)[0];
  const auto e = s.energy();
  // the bars' share of the constraint: the multipliers' force along the bar
  // on the tied bar nodes over that on every tied point
  const auto lambda = s.multipliers();
  double on_bars = 0.0, on_all = 0.0;
  for (std::size_t q = 0; 3 * q < lambda.size(); ++q)
  {
    on_all += lambda[3 * q];
    if (q >= s.constrained())
      on_bars += lambda[3 * q];
  }
  INFO("the tied bar nodes take " << on_bars << " N of the multipliers' " << on_all << " N along the bar");
  INFO("anchor reaction " << reaction << " N against the load " << F << " N; " << s.constrained_bar_nodes()
                          << " bar nodes tied; largest residual " << residual << " m/s; energy imbalance "
                          << e.imbalance() << " J of work " << e.fe.external_work << " J; step " << s.dt() << " s");
  CHECK(std::abs(reaction / F - 1.0) < 0.01);
  CHECK(residual < 1e-10);
  // the coupled budget (with the bars' energies) closes: the damping and
  // the multipliers' work booked on both sides
  CHECK(std::abs(e.imbalance()) < 1e-2 * std::abs(e.fe.external_work));
}

TEST_CASE("bars across the overlap: a uniform velocity is carried unchanged by spheres, bar nodes and shells",
          "[bridge][coupled][bars]")
{
  // the patch test of the planar overlap with a bar through it: nothing
  // deforms, so the tied bar nodes, like the spheres, keep V. The constraint
  // holds to round-off (1e-10 of V, as without bars). The velocities keep V
  // to the bars' round-off: the spheres move by multiples of a common
  // quantum (Particles::quantum), so a translation leaves their links
  // unstrained to the bit, but the bar nodes move by dt v rounded each in
  // its own binade, and a bond's offset is taken from the interpolated
  // point: strains of order ulp(0.2 m) / 4 mm = 7e-15 per step, which the
  // steel (E / rho / l^2 = 1.6e12 1/s^2) and the bonds turn into velocity
  // errors of about 1e-9 m/s over 200 steps. Bound: 1e-8 of V; measured
  // 4e-10 m/s (1.4e-9 of V).
  auto b = make_bar(shell::Cell::quadrilateral);
  const dem::BarLine line{{{0.08, 0.025, 0.0}, {0.196, 0.025, 0.0}}, 0.006, 0, 0};
  dem::Bars bars = dem::make_bars(std::span<const dem::BarLine>(&line, 1), {dem::Steel{}}, {dem::BondLaw{}}, 4e-3);
  bars.sphere_contacts = false;
  dem::create_bonds(bars, b.p, 1e-3);
  const std::array<double, 3> V{0.3, -0.2, 0.1};
  for (std::size_t n = 0; n < bars.nodes(); ++n)
    for (int d = 0; d < 3; ++d)
      bars.v[3 * n + d] = V[d];
  for (std::size_t i = 0; i < b.p.size(); ++i)
    for (int d = 0; d < 3; ++d)
      b.p.v[3 * i + d] = V[d];
  bridge::CouplingOptions o;
  o.overlap = bridge::PlanarOverlap{{1.0, 0.0, 0.0}, 0.12, 0.08};
  bridge::CoupledSolver s(*b.fe, b.p, b.l, b.mat, o, bars);
  std::vector<double> u(b.fe->num_dofs(), 0.0), v(b.fe->num_dofs(), 0.0);
  for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
    for (int d = 0; d < 3; ++d)
      v[6 * k + d] = V[d];
  s.start(u, v);
  double residual = 0.0;
  for (int k = 0; k < 200; ++k)
    residual = std::max(residual, s.step());
  double off_bars = 0.0, off_spheres = 0.0, off_shells = 0.0;
  const dem::Bars& w = s.de().bars();
  for (std::size_t n = 0; n < w.nodes(); ++n)
    for (int d = 0; d < 3; ++d)
      off_bars = std::max(off_bars, std::abs(w.v[3 * n + d] - V[d]));
  for (std::size_t i = 0; i < b.p.size(); ++i)
    for (int d = 0; d < 3; ++d)
      off_spheres = std::max(off_spheres, std::abs(b.p.v[3 * i + d] - V[d]));
  for (std::size_t k = 0; k < b.fe->num_nodes(); ++k)
    for (int d = 0; d < 3; ++d)
      off_shells = std::max(off_shells, std::abs(s.fe().v()[6 * k + d] - V[d]));
  INFO("off by " << off_bars << " m/s (bar nodes), " << off_spheres << " (spheres), " << off_shells
                 << " (shells); residual " << residual << " m/s; " << s.constrained_bar_nodes() << " bar nodes tied");
  CHECK(s.constrained_bar_nodes() >= 10);
  const double vn = std::sqrt(0.14);
  CHECK(off_shells < 1e-8 * vn);
  CHECK(off_spheres < 1e-8 * vn);
  CHECK(off_bars < 1e-8 * vn);
  CHECK(residual < 1e-10 * vn);
  // bar nodes past the band's FE edge are refused, named
  auto c = make_bar(shell::Cell::quadrilateral);
  const dem::BarLine far{{{0.07, 0.025, 0.0}, {0.196, 0.025, 0.0}}, 0.006, 0, 0};
  dem::Bars too_long = dem::make_bars(std::span<const dem::BarLine>(&far, 1), {dem::Steel{}}, {dem::BondLaw{}}, 4e-3);
  CHECK_THROWS_WITH(bridge::CoupledSolver(*c.fe, c.p, c.l, c.mat, o, too_long),
                    Contains("bar nodes lie beyond the overlap on the FE side"));
  // a bar along the band's FE edge would carry nothing (weight 0): refused
  const dem::BarLine edge{{{0.08, 0.005, 0.0}, {0.08, 0.045, 0.0}}, 0.006, 0, 0};
  dem::Bars on_edge = dem::make_bars(std::span<const dem::BarLine>(&edge, 1), {dem::Steel{}}, {dem::BondLaw{}}, 4e-3);
  CHECK_THROWS_WITH(bridge::CoupledSolver(*c.fe, c.p, c.l, c.mat, o, on_edge), Contains("lies along the overlap's FE edge"));
  // a bar that ends halfway across the band would leave the steel's force
  // short there (its share 1 - eta, the shells' eta): refused, named
  const dem::BarLine short_bar{{{0.1, 0.025, 0.0}, {0.196, 0.025, 0.0}}, 0.006, 0, 0};
  dem::Bars ends_inside = dem::make_bars(std::span<const dem::BarLine>(&short_bar, 1), {dem::Steel{}}, {dem::BondLaw{}}, 4e-3);
  CHECK_THROWS_WITH(bridge::CoupledSolver(*c.fe, c.p, c.l, c.mat, o, ends_inside),
                    Contains("an end of its bar, lies inside the overlap at (0.1, 0.025, 0) m (the shells' weight 0.5")
                        && Contains("must run on to its FE edge"));
}
