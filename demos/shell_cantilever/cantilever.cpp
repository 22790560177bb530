#include "cantilever.h"
#include "support.h"

#include "dembridge/shell/analytic.h"
#include "dembridge/shell/explicit.h"
#include "dembridge/shell/output.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <mpi.h>
#include <numbers>
#include <stdexcept>

namespace dembridge::demo
{
using namespace dembridge::shell;

namespace
{
std::array<double, 3> column(const Placement& p, int j)
{
  return {p.rotation[j], p.rotation[3 + j], p.rotation[6 + j]};
}
std::array<double, 3> to_local(const Placement& p, std::span<const double> x)
{
  std::array<double, 3> d = {x[0] - p.origin[0], x[1] - p.origin[1], x[2] - p.origin[2]};
  std::array<double, 3> l{};
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
      l[j] += p.rotation[3 * i + j] * d[i];
  return l;
}
} // namespace

nlohmann::json run_cantilever(const CantileverConfig& cfg)
{
  Stopwatch clock;
  if (cfg.load != "axial" && cfg.load != "bending" && cfg.load != "static-tip")
    throw std::runtime_error("load '" + cfg.load + "': allowed are axial, bending, static-tip");
  if (cfg.solver != "explicit" && cfg.solver != "direct" && cfg.solver != "both")
    throw std::runtime_error("solver '" + cfg.solver + "': allowed are explicit, direct, both");
  if (!(cfg.safety > 0.0 && cfg.safety <= 1.0))
    throw std::runtime_error("safety factor " + std::to_string(cfg.safety)
                             + ": must be in (0, 1]");
  if (cfg.dt < 0.0)
    throw std::runtime_error("time step " + std::to_string(cfg.dt) + " s: must be > 0 (or 0 for automatic)");
  if (!(cfg.periods > 0.0))
    throw std::runtime_error("periods " + std::to_string(cfg.periods) + ": must be > 0");
  const Cell cell = parse_cell(cfg.cell);
  const bool solid = cell == Cell::hexahedron || cell == Cell::tetrahedron;
  const double L = cfg.length, b = cfg.width, h = cfg.material.thickness;
  validate(cfg.material, !solid);

  // Mesh: structured, or read (assumed to lie along local x from 0 to length).
  Placement place = cfg.placement;
  std::shared_ptr<dolfinx::mesh::Mesh> mesh;
  if (!cfg.mesh_file.empty())
    mesh = read_mesh(MPI_COMM_WORLD, cfg.mesh_file);
  else if (solid)
  {
    Placement p = place;
    const auto ez = column(place, 2);
    for (int i = 0; i < 3; ++i)
      p.origin[i] -= 0.5 * h * ez[i];
    mesh = create_solid_box(MPI_COMM_WORLD, {L, b, h}, {cfg.nx, cfg.ny, cfg.nz}, cell, p);
  }
  else
    mesh = create_shell_rectangle(MPI_COMM_WORLD, L, b, cfg.nx, cfg.ny, cell, place);

  FEModel model(mesh, cfg.material, parse_force_method(cfg.force_method));
  const int bs = model.block_size();
  const auto x = model.node_coordinates();
  const double tol = 1e-8 * L;
  auto clamp = select_nodes(x, [&](const auto& p) { return std::abs(to_local(place, p)[0]) < tol; },
                            "clamped end x = 0");
  auto tip = select_nodes(x, [&](const auto& p) { return std::abs(to_local(place, p)[0] - L) < tol; },
                          "loaded end x = length");
  std::vector<int> all(bs);
  for (int i = 0; i < bs; ++i)
    all[i] = i;
  const auto fixed = node_dofs(clamp, bs, all);
  const auto ex = column(place, 0), ey = column(place, 1), ez = column(place, 2);

  // References.
  const double E = cfg.material.youngs_modulus, nu = cfg.material.poisson_ratio,
               rho = cfg.material.density, k = cfg.material.shear_factor;
  const analytic::BeamSection sec{b, h};
  const double f_bend = analytic::timoshenko_cantilever_frequency(E, nu, rho, sec, L, k);
  double f_ref = cfg.load == "axial" ? analytic::axial_clamped_free_frequency(E, rho, L) : f_bend;
  const double d_ref = analytic::timoshenko_tip_deflection(cfg.tip_load, E, nu, sec, L, k);

  nlohmann::json out;
  out["load"] = cfg.load;
  out["cell"] = cfg.cell;
  out["model"] = solid ? "solid" : "shell";
  out["nodes"] = model.num_nodes();
  out["dofs"] = model.num_dofs();
  out["cells"] = model.num_cells();
  out["reference_frequency_hz"] = cfg.load == "static-tip" ? f_bend : f_ref;
  // static-tip: Timoshenko tip deflection; dynamic: the imposed modal amplitude
  out["reference_deflection_m"] = cfg.load == "static-tip" ? d_ref : cfg.amplitude;

  const auto direction = cfg.load == "axial" ? ex : ez;
  auto tip_value = [&](std::span<const double> u)
  {
    double s = 0.0;
    for (auto n : tip)
      for (int i = 0; i < 3; ++i)
        s += u[n * bs + i] * direction[i];
    return s / tip.size();
  };

  // Tip load vector (static-tip): P along local z, spread over the end.
  std::vector<std::int32_t> load_dofs;
  std::vector<double> load_w;
  if (cfg.load == "static-tip")
  {
    const auto w = model.boundary_load_weights(tip);
    for (std::size_t t = 0; t < tip.size(); ++t)
      for (int i = 0; i < 3; ++i)
      {
        load_dofs.push_back(tip[t] * bs + i);
        load_w.push_back(w[t] * ez[i]);
      }
  }

  if (cfg.load == "static-tip" && cfg.solver != "explicit")
  {
    std::vector<double> f(model.num_dofs(), 0.0);
    for (std::size_t i = 0; i < load_dofs.size(); ++i)
      f[load_dofs[i]] += cfg.tip_load * load_w[i];
    const auto u = model.solve_static(f, fixed);
    out["direct_tip_deflection_m"] = tip_value(u);
    out["tip_deflection_m"] = tip_value(u);
    out["relative_error"] = tip_value(u) / d_ref - 1.0;
    if (cfg.solver == "direct")
    {
      out["steps"] = 0;
      out["dt_s"] = 0.0;
      out["first_frequency_hz"] = nullptr;
      out["wall_s"] = clock.seconds();
      return out;
    }
  }

  // Explicit run.
  const auto mass = model.lumped_mass();
  const double dt_crit = model.critical_time_step(mass);
  if (cfg.dt > dt_crit)
  {
    std::ostringstream s;
    s << "time step " << cfg.dt << " s is above the critical time step " << dt_crit
      << " s of this mesh: use --dt below it, or 0 for " << cfg.safety << " x critical";
    throw std::runtime_error(s.str());
  }
  const double dt = cfg.dt > 0.0 ? cfg.dt : cfg.safety * dt_crit;
  const double omega_b = 2.0 * std::numbers::pi * f_bend;
  double damping = cfg.damping;
  if (damping < 0.0)
    damping = cfg.load == "static-tip" ? 2.0 * omega_b : 0.0;
  double t_end = cfg.end_time;
  if (!(t_end > 0.0))
    t_end = cfg.load == "static-tip" ? 16.0 / omega_b : cfg.periods / f_ref;
  const auto nsteps = static_cast<std::int64_t>(std::ceil(t_end / dt));

  ExplicitSolver solver(mass, model.internal_force_fn(), dt, damping);
  solver.add_motion({"clamp", fixed, MotionKind::fixed, {}});
  if (cfg.load == "static-tip")
  {
    const double P = cfg.tip_load;
    solver.add_load({"tip load", load_dofs, load_w, [P](double) { return P; }});
  }
  std::vector<double> u0(model.num_dofs(), 0.0), v0(model.num_dofs(), 0.0);
  const double A = cfg.amplitude;
  for (std::size_t n = 0; n < model.num_nodes(); ++n)
  {
    const auto xl = to_local(place, x.subspan(3 * n, 3));
    double* u = &u0[n * bs];
    if (cfg.load == "axial")
      for (int i = 0; i < 3; ++i)
        u[i] = A * std::sin(0.5 * std::numbers::pi * xl[0] / L) * ex[i];
    else if (cfg.load == "bending")
    {
      const double w = A * analytic::cantilever_mode_shape(xl[0], L);
      const double slope = A * analytic::cantilever_mode_slope(xl[0], L);
      for (int i = 0; i < 3; ++i)
      {
        u[i] = w * ez[i];
        if (solid)
          u[i] -= slope * xl[2] * ex[i];
        else
          u[3 + i] = -slope * ey[i];
      }
    }
  }
  if (cfg.load != "static-tip" && cfg.initial != "analytic")
  {
    if (cfg.initial == "mode")
    {
      auto [mode, lambda] = model.lowest_mode(mass, fixed, u0, 4);
      u0 = std::move(mode);
      out["mode_frequency_hz"] = std::sqrt(lambda) / (2.0 * std::numbers::pi);
    }
    else if (cfg.initial == "static")
    {
      std::vector<double> f(model.num_dofs(), 0.0);
      const auto w = model.boundary_load_weights(tip);
      for (std::size_t t = 0; t < tip.size(); ++t)
        for (int i = 0; i < 3; ++i)
          f[tip[t] * bs + i] = w[t] * direction[i];
      u0 = model.solve_static(f, fixed);
    }
    else
      throw std::runtime_error("initial shape '" + cfg.initial
                               + "': allowed are mode, analytic, static");
    const double scale = A / tip_value(u0);
    for (double& v : u0)
      v *= scale;
  }
  solver.set_state(u0, v0);
  const auto e0 = solver.energy();
  const double E0 = e0.kinetic + e0.strain;

  std::unique_ptr<XdmfWriter> writer;
  int frames_written = 0;
  std::ofstream csv;
  const std::int64_t every = std::max<std::int64_t>(1, nsteps / std::max(1, cfg.frames));
  if (!cfg.output_dir.empty())
  {
    std::filesystem::create_directories(cfg.output_dir);
    writer = std::make_unique<XdmfWriter>(model, std::filesystem::path(cfg.output_dir) / "cantilever.xdmf");
    writer->write(0.0, solver.u(), solver.v());
    ++frames_written;
    csv.open(std::filesystem::path(cfg.output_dir) / "history.csv");
    csv << "t_s,tip_m,kinetic_J,strain_J,external_work_J,prescribed_work_J,damping_J,imbalance_J\n";
  }
  if (!cfg.quiet)
    std::cout << "dt = " << dt << " s (critical " << dt_crit << " s), " << nsteps
              << " steps to t = " << t_end << " s, damping " << damping << " 1/s\n"
              << "      t [s]     kinetic [J]      strain [J]    ext.work [J]   presc.work [J]"
                 "     damping [J]   imbalance [J]\n";

  std::vector<double> ts, tipv;
  ts.reserve(nsteps + 1);
  tipv.reserve(nsteps + 1);
  ts.push_back(0.0);
  tipv.push_back(tip_value(solver.u()));
  double drift = 0.0, imbalance = 0.0, emax = E0;
  auto report = [&](const EnergyBudget& e, bool print)
  {
    if (csv.is_open())
      csv << solver.time() << "," << tipv.back() << "," << e.kinetic << "," << e.strain << ","
          << e.external_work << "," << e.prescribed_work << "," << e.damping << ","
          << e.imbalance() << "\n";
    if (print && !cfg.quiet)
      std::cout << std::scientific << std::setprecision(5) << std::setw(11) << solver.time()
                << std::setw(16) << e.kinetic << std::setw(16) << e.strain << std::setw(16)
                << e.external_work << std::setw(16) << e.prescribed_work << std::setw(16)
                << e.damping << std::setw(16) << e.imbalance() << std::defaultfloat << "\n";
  };
  report(e0, true);
  const std::int64_t print_every = std::max<std::int64_t>(1, nsteps / 10);
  for (std::int64_t s = 1; s <= nsteps; ++s)
  {
    solver.step();
    ts.push_back(solver.time());
    tipv.push_back(tip_value(solver.u()));
    const bool frame = s % every == 0 || s == nsteps;
    if (s % 10 == 0 || frame)
    {
      const auto e = solver.energy();
      const double tot = e.kinetic + e.strain;
      emax = std::max({emax, tot, e.external_work});
      if (damping == 0.0 && cfg.load != "static-tip" && E0 > 0.0)
        drift = std::max(drift, std::abs(tot - E0) / E0);
      imbalance = std::max(imbalance, std::abs(e.imbalance()));
      if (frame)
      {
        if (writer)
        {
          writer->write(solver.time(), solver.u(), solver.v());
          ++frames_written;
        }
        report(e, s % print_every == 0 || s == nsteps);
      }
    }
  }
  if (writer)
    writer->close();

  out["frames_written"] = frames_written;
  out["dt_s"] = dt;
  out["dt_critical_s"] = dt_crit;
  out["steps"] = solver.steps();
  out["end_time_s"] = solver.time();
  out["damping_per_s"] = damping;
  out["energy_balance_error"] = emax > 0.0 ? imbalance / emax : 0.0;
  if (cfg.load == "static-tip")
  {
    const double d = tipv.back();
    out["explicit_tip_deflection_m"] = d;
    if (cfg.solver == "explicit")
    {
      out["tip_deflection_m"] = d;
      out["relative_error"] = d / d_ref - 1.0;
    }
    else
      out["explicit_vs_direct"] = d / out["direct_tip_deflection_m"].get<double>() - 1.0;
    const auto e = solver.energy();
    out["final_kinetic_over_strain"] = e.strain > 0.0 ? e.kinetic / e.strain : 0.0;
    out["first_frequency_hz"] = nullptr;
  }
  else
  {
    const double f = crossing_frequency(ts, tipv);
    out["first_frequency_hz"] = f;
    out["relative_error"] = f / f_ref - 1.0;
    out["tip_deflection_m"] = amplitude(tipv);
    out["energy_drift"] = drift;
  }
  out["wall_s"] = clock.seconds();
  return out;
}

} // namespace dembridge::demo
