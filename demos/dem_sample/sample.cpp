#include "sample.h"
#include "support.h"

#include "dembridge/dem/output.h"
#include "dembridge/dem/packing.h"
#include "dembridge/dem/solver.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace dembridge::demo
{
using namespace dembridge::dem;

namespace
{
/// The links for which cut(a, b) is false, in the same order.
template <typename Cut>
Links remove_links(const Links& l, Cut cut)
{
  Links out;
  for (std::size_t k = 0; k < l.size(); ++k)
  {
    if (cut(l.a[k], l.b[k]))
      continue;
    out.a.push_back(l.a[k]);
    out.b.push_back(l.b[k]);
    out.d0.push_back(l.d0[k]);
    out.kn.push_back(l.kn[k]);
    out.ks.push_back(l.ks[k]);
    out.delta_max.push_back(l.delta_max[k]);
    out.state.push_back(l.state[k]);
    for (int q = 0; q < 3; ++q)
    {
      out.fs.push_back(l.fs[3 * k + q]);
      out.n.push_back(l.n[3 * k + q]);
    }
    if (!l.weight.empty())
      out.weight.push_back(l.weight[k]);
  }
  return out;
}

/// Least-squares slope of y(x) through the points.
double slope(const std::vector<double>& x, const std::vector<double>& y)
{
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
  {
    sx += x[i];
    sy += y[i];
    sxx += x[i] * x[i];
    sxy += x[i] * y[i];
  }
  const double den = n * sxx - sx * sx;
  return den != 0.0 ? (n * sxy - sx * sy) / den : 0.0;
}
} // namespace

Region sample_region(const SampleConfig& cfg)
{
  if (cfg.shape == "cylinder")
    return cylinder_region({0.0, 0.0, 0.0}, 0.5 * cfg.diameter, cfg.height);
  if (cfg.shape == "prism")
    return box_region({0.0, 0.0, 0.0}, {cfg.diameter, cfg.diameter, cfg.height});
  throw std::runtime_error("shape '" + cfg.shape + "': allowed are cylinder, prism");
}

Packing sample_packing(const SampleConfig& cfg)
{
  if (!cfg.packing_file.empty())
    return read_packing(cfg.packing_file);
  PackingOptions po;
  po.mean_radius = cfg.mean_radius;
  po.radius_ratio = cfg.radius_ratio;
  po.seed = cfg.seed;
  return generate_packing(sample_region(cfg), po);
}

nlohmann::json run_sample(const SampleConfig& cfg)
{
  Stopwatch clock;
  if (cfg.shape != "cylinder" && cfg.shape != "prism")
    throw std::runtime_error("shape '" + cfg.shape + "': allowed are cylinder, prism");
  if (cfg.test != "tension" && cfg.test != "compression")
    throw std::runtime_error("test '" + cfg.test + "': allowed are tension, compression");
  if (!(cfg.diameter > 0.0) || !(cfg.height > 0.0))
    throw std::runtime_error("sample size: diameter and height must be > 0 m");
  if (!(cfg.strain_rate > 0.0))
    throw std::runtime_error("strain rate " + std::to_string(cfg.strain_rate) + " 1/s: must be > 0");
  if (!(cfg.safety > 0.0 && cfg.safety <= 1.0))
    throw std::runtime_error("safety factor " + std::to_string(cfg.safety) + ": must be in (0, 1]");
  if (!(cfg.stop_ratio >= 0.0 && cfg.stop_ratio < 1.0))
    throw std::runtime_error("stop ratio " + std::to_string(cfg.stop_ratio) + ": must be in [0, 1)");
  if (cfg.to_separation && cfg.test != "tension")
    throw std::runtime_error("a run to separation is a tension test, not " + cfg.test);
  if (cfg.dt < 0.0)
    throw std::runtime_error("time step " + std::to_string(cfg.dt) + " s: must be > 0 (0: automatic)");
  cfg.material.validate();
  const double D = cfg.diameter, H = cfg.height;
  const bool cyl = cfg.shape == "cylinder";
  const Region region = sample_region(cfg);
  if (!(cfg.ligament > 0.0 && cfg.ligament <= 1.0))
    throw std::runtime_error("ligament " + std::to_string(cfg.ligament)
                             + ": the notched section's share must be in (0, 1] (1: no notch)");
  const double area = (cyl ? std::numbers::pi * D * D / 4.0 : D * D) * cfg.ligament;

  const Packing pk = sample_packing(cfg);
  double solid = 0.0;
  for (double r : pk.r)
    solid += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  const double fraction = solid / region.volume;
  Particles p = make_particles(pk.x, pk.r, cfg.material.density, fraction);
  const auto bulk = bulk_spheres(region, p.x, p.r);
  const double lambda = cfg.lambda > 0.0 ? cfg.lambda
                                         : lambda_for_mean_links(p.x, p.r, cfg.links_per_sphere, bulk);
  Links links = create_links(p, lambda, cfg.material);
  if (cfg.ligament < 1.0)
  {
    // the ligament: a disc (square) of the same centre, ligament x area
    const double half = 0.5 * D * std::sqrt(cfg.ligament);
    links = remove_links(links, [&](std::int32_t a, std::int32_t b)
    {
      const double za = p.x[3 * a + 2], zb = p.x[3 * b + 2];
      if ((za < 0.5 * H) == (zb < 0.5 * H))
        return false;
      const double s = (0.5 * H - za) / (zb - za); // where the link crosses mid-height
      const double cx = p.x[3 * a] + s * (p.x[3 * b] - p.x[3 * a]) - (cyl ? 0.0 : 0.5 * D);
      const double cy = p.x[3 * a + 1] + s * (p.x[3 * b + 1] - p.x[3 * a + 1]) - (cyl ? 0.0 : 0.5 * D);
      return cyl ? std::hypot(cx, cy) > half : std::max(std::abs(cx), std::abs(cy)) > half;
    });
  }
  const double rmax = *std::max_element(p.r.begin(), p.r.end());
  const double rmin = *std::min_element(p.r.begin(), p.r.end());

  const double dt_crit = critical_time_step(p, links);
  if (cfg.dt > dt_crit)
  {
    std::ostringstream s;
    s << "time step " << cfg.dt << " s is above the critical time step " << dt_crit
      << " s of this sample: use --dt below it, or 0 for " << cfg.safety << " x critical";
    throw std::runtime_error(s.str());
  }
  const double dt = cfg.dt > 0.0 ? cfg.dt : cfg.safety * dt_crit;
  const double c_wave = std::sqrt(cfg.material.youngs_modulus / cfg.material.density);
  const double omega1 = std::numbers::pi / (2.0 * H) * c_wave;
  const double damping = cfg.damping >= 0.0 ? cfg.damping : omega1;
  const double sign = cfg.test == "tension" ? 1.0 : -1.0;
  const double max_strain = cfg.max_strain > 0.0 ? cfg.max_strain
                                                 : (cfg.test == "tension" && !cfg.to_separation ? 5e-4 : 5e-3);
  const double v_top = sign * cfg.strain_rate * H;
  const double t_ramp = 20.0 * H / c_wave;

  DemSolver solver(p, links, cfg.material, dt, damping, 0.5 * rmin);
  const double layer = 0.05 * rmax;
  auto bottom = DemSolver::select(p, [&](const auto& x) { return x[2] < layer + rmax; }, "bottom face");
  auto top = DemSolver::select(p, [&](const auto& x) { return x[2] > H - layer - rmax; }, "top face");
  // keep the spheres that touch the faces (centre within r + layer)
  auto touching = [&](std::vector<std::int32_t> ids, bool low)
  {
    std::vector<std::int32_t> out;
    for (auto i : ids)
      if (low ? p.x[3 * i + 2] - p.r[i] < layer : p.x[3 * i + 2] + p.r[i] > H - layer)
        out.push_back(i);
    if (out.empty())
      throw std::runtime_error(std::string("no sphere touches the ") + (low ? "bottom" : "top")
                               + " face: is the packing made for this sample size?");
    return out;
  };
  bottom = touching(bottom, true);
  top = touching(top, false);
  solver.add_motion({"bottom", bottom, MotionKind::velocity, {false, false, true},
                     [](double) { return 0.0; }});
  solver.add_motion({"top", top, MotionKind::velocity, {false, false, true},
                     [=](double t) { return v_top * std::min(1.0, t / t_ramp); }});
  // lateral gauges: spheres on the lateral surface in the middle third
  std::vector<std::int32_t> gauge;
  std::vector<std::array<double, 3>> gauge_dir;
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    const double* x = &p.x[3 * i];
    if (x[2] < H / 3.0 || x[2] > 2.0 * H / 3.0)
      continue;
    if (region.sdf({x[0], x[1], x[2]}) + p.r[i] < -layer)
      continue;
    std::array<double, 3> dir{0.0, 0.0, 0.0};
    if (cyl)
    {
      const double rr = std::hypot(x[0], x[1]);
      dir = {x[0] / rr, x[1] / rr, 0.0};
    }
    else
    {
      // outward normal of the nearest side face
      const double d[4] = {x[0], D - x[0], x[1], D - x[1]};
      const int k = static_cast<int>(std::min_element(d, d + 4) - d);
      dir[k / 2] = k % 2 == 0 ? -1.0 : 1.0;
    }
    gauge.push_back(static_cast<std::int32_t>(i));
    gauge_dir.push_back(dir);
  }
  if (gauge.empty())
    throw std::runtime_error("no sphere on the lateral face at mid-height to measure the lateral strain");
  const double half_width = 0.5 * D;
  // axial gauge: every sphere centred within Rmax of z = H/4 and of z = 3H/4;
  // the strain of the middle half is the change of the two slabs' mean
  // distance over its initial value. The platen strain (u_top - u_bot) / H
  // also counts the spheres' layers at both ends, which the links do not
  // strain like the bulk (the centres of the held spheres lie ~R inside the
  // faces): it overestimated E by 5-9 % on small samples, depending on
  // their height. E and nu are taken on the gauge, as a laboratory does.
  std::vector<std::int32_t> g_lo, g_hi;
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    const double z = p.x[3 * i + 2];
    if (std::abs(z - 0.25 * H) < rmax)
      g_lo.push_back(static_cast<std::int32_t>(i));
    else if (std::abs(z - 0.75 * H) < rmax)
      g_hi.push_back(static_cast<std::int32_t>(i));
  }
  if (g_lo.empty() || g_hi.empty())
    throw std::runtime_error("no sphere at a quarter of the height to measure the axial strain");
  auto mean_z = [&](const std::vector<std::int32_t>& ids, const std::vector<double>& x) {
    double s = 0.0;
    for (auto i : ids)
      s += x[3 * i + 2];
    return s / ids.size();
  };
  const double gauge_length = mean_z(g_hi, p.x0) - mean_z(g_lo, p.x0);
  solver.track_cohesion_demand();
  solver.start();

  nlohmann::json out;
  out["test"] = cfg.test;
  out["shape"] = cfg.shape;
  out["particles"] = p.size();
  out["links"] = links.size();
  out["ligament"] = cfg.ligament;
  out["lambda"] = lambda;
  out["mean_links_per_particle"] = 2.0 * links.size() / p.size();
  {
    // in the bulk, where --links-per-sphere applies
    std::size_t nb = 0, lb = 0;
    for (std::size_t k = 0; k < links.size(); ++k)
      lb += bulk[links.a[k]] + bulk[links.b[k]];
    for (auto f : bulk)
      nb += f;
    out["bulk_links_per_particle"] = nb ? static_cast<double>(lb) / nb : 0.0;
  }
  out["packing_fraction"] = fraction;
  out["dt_s"] = dt;
  out["dt_critical_s"] = dt_crit;
  out["damping_per_s"] = damping;
  out["packing_sweeps"] = pk.sweeps;

  std::unique_ptr<ParticleWriter> writer;
  std::ofstream csv;
  if (!cfg.output_dir.empty())
  {
    std::filesystem::create_directories(cfg.output_dir);
    writer = std::make_unique<ParticleWriter>(std::filesystem::path(cfg.output_dir) / "particles.xdmf",
                                              links, p.size());
    writer->write(0.0, p, links);
    csv.open(std::filesystem::path(cfg.output_dir) / "stress_strain.csv");
    csv << "time_s,strain,stress_pa,lateral_strain,bottom_reaction_n,links_broken_tension,"
           "links_broken_shear,kinetic_j,elastic_j,softening_j,breakage_j,friction_j,damping_j,"
           "work_j,imbalance_j,gauge_strain,top_reaction_n\n";
  }
  const double t_end = max_strain / cfg.strain_rate + t_ramp / 2.0;
  const auto nsteps = static_cast<std::int64_t>(std::ceil(t_end / dt));
  const std::int64_t sample_every = std::max<std::int64_t>(1, nsteps / 2000);
  const std::int64_t frame_every = std::max<std::int64_t>(1, nsteps / std::max(1, cfg.frames));
  if (!cfg.quiet)
  {
    const auto& mt = cfg.material;
    std::cout << "# material: E " << mt.youngs_modulus << " Pa, nu " << mt.poisson_ratio
              << ", density " << mt.density << " kg/m^3, alpha " << mt.micro.alpha << ", beta "
              << mt.micro.beta << ", gamma " << mt.micro.gamma << ", T " << mt.tensile
              << " Pa, C0 " << mt.cohesion << " Pa, zeta " << mt.zeta << ", phi_i "
              << mt.phi_i_deg << " deg, phi_c " << mt.phi_c_deg << " deg\n";
  }
  if (!cfg.quiet)
    std::cout << p.size() << " spheres, " << links.size() << " links (lambda " << lambda
              << "), dt " << dt << " s (critical " << dt_crit << "), up to " << nsteps
              << " steps, damping " << damping << " 1/s\n"
              << "      strain    stress [Pa]  broken t/s       kinetic [J]     elastic [J]"
                 "   dissipated [J]      work [J]   imbalance [J]\n";

  std::vector<double> eps, sig, lat, ax;
  double peak = 0.0, eps_peak = 0.0;
  double dissipated_at_peak = 0.0; // by the links (softening + breakage) [J]
  double demand_at_peak = 0.0;     // the solver's cohesion demand then [Pa]
  bool after_peak = false, separated = false;
  double t_low = -1.0; // since when the force through the crack is below 1 % of the peak
  auto measure = [&](bool print, bool frame)
  {
    double u_top = 0.0;
    for (auto i : top)
      u_top += p.x[3 * i + 2] - p.x0[3 * i + 2];
    u_top /= top.size();
    double u_bot = 0.0;
    for (auto i : bottom)
      u_bot += p.x[3 * i + 2] - p.x0[3 * i + 2];
    u_bot /= bottom.size();
    const double strain = (u_top - u_bot) / H;
    // the stress averaged over the gauge: damping (c m v) and inertia load
    // the sample in proportion to the velocity and acceleration, both
    // linear in z, so the axial stress grows as z^2 from the bottom platen
    // to the top one, and its mean over [H/4, 3H/4] is s_bot + 13/48 (s_top
    // - s_bot). The top platen's stress alone made E and sigma_t depend on
    // the loading rate by ~2 % when it was halved.
    const double s_top = solver.reaction("top")[2] / area, s_bot = -solver.reaction("bottom")[2] / area;
    const double stress = s_bot + 13.0 / 48.0 * (s_top - s_bot);
    double ul = 0.0;
    for (std::size_t g = 0; g < gauge.size(); ++g)
      for (int k = 0; k < 3; ++k)
        ul += (p.x[3 * gauge[g] + k] - p.x0[3 * gauge[g] + k]) * gauge_dir[g][k];
    const double lateral = ul / gauge.size() / half_width;
    const double axial = (mean_z(g_hi, p.x) - mean_z(g_lo, p.x)) / gauge_length - 1.0;
    eps.push_back(strain);
    ax.push_back(axial);
    sig.push_back(stress);
    lat.push_back(lateral);
    if (std::abs(stress) > peak)
    {
      peak = std::abs(stress);
      eps_peak = std::abs(strain);
      const auto e = solver.energy();
      dissipated_at_peak = e.softening + e.breakage;
      demand_at_peak = solver.cohesion_demand();
    }
    else if (cfg.to_separation)
    {
      // separated: the force through the crack, which the bottom platen
      // carries (the top one also pulls the top part through the damping,
      // c m v), stays below 1 % of the peak for two periods of the first
      // axial mode (4H/c each), so that no snap-back oscillation passing
      // through zero counts. (Intact links may still join the two parts:
      // chains of links that rotate with their spheres carry almost no
      // force.) Afterwards the links can dissipate at most 1 % of the peak
      // force times the further opening.
      if (std::abs(s_bot) < 0.01 * peak)
      {
        if (t_low < 0.0)
          t_low = solver.time();
        if (solver.time() - t_low >= 8.0 * H / c_wave)
          after_peak = separated = true;
      }
      else
        t_low = -1.0;
    }
    else if (peak > 0.0 && std::abs(stress) < cfg.stop_ratio * peak)
      after_peak = true;
    if (csv.is_open() || print)
    {
      const auto e = solver.energy();
      const auto bt = links.count(LinkState::broken_tension), bs = links.count(LinkState::broken_shear);
      if (csv.is_open())
        csv << solver.time() << ',' << strain << ',' << stress << ',' << lateral << ','
            << solver.reaction("bottom")[2] << ',' << bt << ',' << bs << ',' << e.kinetic << ','
            << e.elastic << ',' << e.softening << ',' << e.breakage << ',' << e.friction << ','
            << e.damping << ',' << e.external_work + e.prescribed_work << ',' << e.imbalance()
            << ',' << axial << ',' << s_top * area << '\n';
      if (print && !cfg.quiet)
        std::cout << std::scientific << std::setprecision(4) << std::setw(12) << strain
                  << std::setw(15) << stress << std::setw(7) << bt << "/" << std::left
                  << std::setw(6) << bs << std::right << std::setw(16) << e.kinetic
                  << std::setw(16) << e.elastic << std::setw(16)
                  << e.softening + e.breakage + e.friction + e.damping << std::setw(16)
                  << e.external_work + e.prescribed_work << std::setw(16) << e.imbalance()
                  << std::defaultfloat << "\n";
    }
    if (frame && writer)
      writer->write(solver.time(), p, links);
  };
  const std::int64_t print_every = std::max<std::int64_t>(1, nsteps / 20);
  std::int64_t s = 0;
  for (s = 1; s <= nsteps && !after_peak; ++s)
  {
    solver.step();
    if (s % sample_every == 0 || s % frame_every == 0)
      measure(s % print_every == 0, s % frame_every == 0);
  }
  measure(true, true);
  if (writer)
    writer->close();

  // Elastic moduli from the initial part: points with |stress| between 5 %
  // and 30 % of the peak, before the peak, on the axial gauge.
  std::vector<double> e1, s1, l1, ep;
  for (std::size_t i = 0; i < eps.size(); ++i)
  {
    if (std::abs(eps[i]) > eps_peak)
      break;
    if (std::abs(sig[i]) >= 0.05 * peak && std::abs(sig[i]) <= 0.3 * peak)
    {
      e1.push_back(ax[i]);
      ep.push_back(eps[i]);
      s1.push_back(sig[i]);
      l1.push_back(lat[i]);
    }
  }
  const double E = e1.size() >= 3 ? slope(e1, s1) : 0.0;
  const double nu = e1.size() >= 3 ? -slope(e1, l1) : 0.0;
  out["youngs_modulus_pa"] = E;
  out["gauge_length_m"] = gauge_length;
  out["platen_modulus_pa"] = e1.size() >= 3 ? slope(ep, s1) : 0.0; // for comparison
  out["poisson_ratio"] = nu;
  out["peak_stress_pa"] = peak;
  out["strain_at_peak"] = eps_peak;
  out["final_strain"] = eps.back();
  out["links_broken_tension"] = links.count(LinkState::broken_tension);
  out["links_broken_shear"] = links.count(LinkState::broken_shear);
  out["cohesion_demand_pa"] = solver.cohesion_demand();
  out["cohesion_demand_at_peak_pa"] = demand_at_peak;
  const auto e = solver.energy();
  out["energy"] = {{"kinetic_j", e.kinetic},       {"elastic_j", e.elastic},
                   {"softening_j", e.softening},   {"breakage_j", e.breakage},
                   {"friction_j", e.friction},     {"damping_j", e.damping},
                   {"work_j", e.external_work + e.prescribed_work}, {"imbalance_j", e.imbalance()}};
  // Fracture energy: what the links dissipate (softening and the energy
  // left in a link when it breaks) per unit of cross-section, once the
  // sample is separated (to_separation: the force through the crack below
  // 1 % of the peak). The platen's work also pays the damping of the
  // snap-back (the elastic energy the sample releases faster than the crack
  // absorbs it, which a laboratory's closed-loop test avoids), so it is
  // reported apart, not counted.
  out["separated"] = separated;
  out["dissipated_links_j"] = e.softening + e.breakage;
  out["dissipated_before_peak_j"] = dissipated_at_peak;
  out["fracture_energy_j_m2"] = (e.softening + e.breakage) / area;
  out["work_per_area_j_m2"] = (e.external_work + e.prescribed_work) / area;
  out["cross_section_m2"] = area;
  out["steps"] = solver.steps();
  out["reached_peak"] = after_peak;
  out["wall_s"] = clock.seconds();
  if (writer)
    out["frames"] = writer->frames();
  return out;
}

} // namespace dembridge::demo
