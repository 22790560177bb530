#pragma once
// Internal to the dem_sample demo: one sample test as a class (SampleRun),
// its set-up, loading and checkpoint here, its measurements in
// sample_measure.cpp.
#include "sample.h"
#include "support.h"
#include "time_loop.h"

#include "dembridge/dem/output.h"
#include "dembridge/dem/packing.h"
#include "dembridge/dem/solver.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace dembridge::demo::sample_detail
{
using namespace dembridge::dem;

/// The links for which cut(a, b) is false, in the same order.
template <typename Cut>
inline Links remove_links(const Links& l, Cut cut)
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
inline double slope(const std::vector<double>& x, const std::vector<double>& y)
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

/// One sample test, in the phases of a run: set-up (checks, the sample and
/// its notch, time step and loading rate, platens, gauges, output), the
/// loading, and the measurement of the moduli, peak and fracture energy.
class SampleRun
{
public:
  explicit SampleRun(const SampleConfig& cfg) : _cfg(cfg) {}

  nlohmann::json run()
  {
    check();
    if (_cfg.restart)
      _ckpt = std::make_unique<Checkpointer>(*_cfg.restart, _cfg.output_dir);
    build_sample();
    resolve_time_step();
    set_up_platens();
    set_up_confinement();
    set_up_gauges();
    _solver->track_cohesion_demand();
    _solver->start();
    describe();
    start_or_resume(_ckpt.get(), [this] { resume(); }, [this] { open_output(); });
    print_header();
    load();
    measure_moduli();
    report();
    return _out;
  }

private:
  // ---- set-up ---------------------------------------------------------------
  void check() const
  {
    const SampleConfig& cfg = _cfg;
    if (cfg.shape != "cylinder" && cfg.shape != "prism")
      throw std::runtime_error("shape '" + cfg.shape + "': allowed are cylinder, prism");
    if (cfg.test != "tension" && cfg.test != "compression" && cfg.test != "triaxial")
      throw std::runtime_error("test '" + cfg.test + "': allowed are tension, compression, triaxial");
    const bool triaxial = cfg.test == "triaxial";
    if (triaxial && cfg.shape != "prism")
      throw std::runtime_error("a triaxial test needs shape prism (its four side faces take the confining "
                               "plates), not " + cfg.shape);
    if (triaxial && !(cfg.confinement > 0.0))
      throw std::runtime_error("confinement " + std::to_string(cfg.confinement)
                               + " Pa: a triaxial test needs a lateral pressure > 0");
    if (!triaxial && cfg.confinement != 0.0)
      throw std::runtime_error("confinement " + std::to_string(cfg.confinement) + " Pa: only a triaxial test has one, not "
                               + cfg.test);
    if (triaxial && (cfg.ligament != 1.0 || cfg.uniform_start))
      throw std::runtime_error("a triaxial test takes neither a notch (ligament " + std::to_string(cfg.ligament)
                               + ", must be 1) nor a uniform start");
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
  }

  /// The packing, its spheres and links, and the notch's links removed.
  void build_sample()
  {
    const SampleConfig& cfg = _cfg;
    const double D = cfg.diameter, H = cfg.height;
    _cyl = cfg.shape == "cylinder";
    _region = sample_region(cfg);
    if (!(cfg.ligament > 0.0 && cfg.ligament <= 1.0))
      throw std::runtime_error("ligament " + std::to_string(cfg.ligament)
                               + ": the notched section's share must be in (0, 1] (1: no notch)");
    _area = (_cyl ? std::numbers::pi * D * D / 4.0 : D * D) * cfg.ligament;
    std::ostringstream keys;
    keys << "--mean-radius " << cfg.mean_radius << " m in the " << cfg.shape << " (--diameter " << cfg.diameter
         << " m, --height " << cfg.height << " m)";
    _pk = cfg.packing_file.empty() ? with_context(keys.str(), [&] { return sample_packing(cfg); })
                                   : sample_packing(cfg);
    double solid = 0.0;
    for (double r : _pk.r)
      solid += 4.0 / 3.0 * std::numbers::pi * r * r * r;
    _fraction = solid / _region.volume;
    _p = make_particles(_pk.x, _pk.r, cfg.material.density, _fraction);
    _bulk = with_context(keys.str(), [&] { return bulk_spheres(_region, _p.x, _p.r); });
    _lambda = cfg.lambda > 0.0 ? cfg.lambda : lambda_for_mean_links(_p.x, _p.r, cfg.links_per_sphere, _bulk);
    _links = create_links(_p, _lambda, cfg.material);
    if (cfg.ligament < 1.0)
    {
      // the ligament: a disc (square) of the same centre, ligament x area
      const double half = 0.5 * D * std::sqrt(cfg.ligament);
      const bool cyl = _cyl;
      const Particles& p = _p;
      _links = remove_links(_links, [&](std::int32_t a, std::int32_t b)
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
    _rmax = *std::max_element(_p.r.begin(), _p.r.end());
    _rmin = *std::min_element(_p.r.begin(), _p.r.end());
  }

  /// Time step, damping, the platen's velocity and its ramp, the run's length.
  void resolve_time_step()
  {
    const SampleConfig& cfg = _cfg;
    const double H = cfg.height;
    _dt_crit = critical_time_step(_p, _links, cfg.material.rolling_friction > 0.0);
    if (cfg.dt > _dt_crit)
    {
      std::ostringstream s;
      s << "time step " << cfg.dt << " s is above the critical time step " << _dt_crit
        << " s of this sample: use --dt below it, or 0 for " << cfg.safety << " x critical";
      throw std::runtime_error(s.str());
    }
    _dt = cfg.dt > 0.0 ? cfg.dt : cfg.safety * _dt_crit;
    _c_wave = std::sqrt(cfg.material.youngs_modulus / cfg.material.density);
    const double omega1 = std::numbers::pi / (2.0 * H) * _c_wave;
    // (damping of the absolute velocity would resist the affine motion of a
    // uniform start: none unless asked for)
    _damping = cfg.damping >= 0.0 ? cfg.damping : (cfg.uniform_start ? 0.0 : omega1);
    const double sign = cfg.test == "tension" ? 1.0 : -1.0;
    _max_strain = cfg.max_strain > 0.0              ? cfg.max_strain
                  : cfg.test == "triaxial"          ? 3e-2
                  : cfg.test == "tension" && !cfg.to_separation ? 5e-4
                                                    : 5e-3;
    _v_top = sign * cfg.strain_rate * H;
    _t_ramp = cfg.uniform_start ? 0.0 : 20.0 * H / _c_wave;
  }

  /// The solver, and the platens: the spheres touching the bottom face held
  /// axially, those touching the top face moved axially (ramped in).
  void set_up_platens()
  {
    const double H = _cfg.height, rmax = _rmax;
    _solver = std::make_unique<DemSolver>(_p, _links, _cfg.material, _dt, _damping, 0.5 * _rmin);
    _layer = 0.05 * rmax;
    const double layer = _layer;
    auto bottom = DemSolver::select(_p, [&](const auto& x) { return x[2] < layer + rmax; }, "bottom face");
    auto top = DemSolver::select(_p, [&](const auto& x) { return x[2] > H - layer - rmax; }, "top face");
    // keep the spheres that touch the faces (centre within r + layer)
    auto touching = [&](const std::vector<std::int32_t>& ids, bool low)
    {
      std::vector<std::int32_t> kept;
      for (auto i : ids)
        if (low ? _p.x[3 * i + 2] - _p.r[i] < layer : _p.x[3 * i + 2] + _p.r[i] > H - layer)
          kept.push_back(i);
      if (kept.empty())
        throw std::runtime_error(std::string("no sphere touches the ") + (low ? "bottom" : "top")
                                 + " face: is the packing made for this sample size?");
      return kept;
    };
    _bottom = touching(bottom, true);
    _top = touching(top, false);
    const double v_top = _v_top, t_ramp = _t_ramp;
    _solver->add_motion({"bottom", _bottom, MotionKind::velocity, {false, false, true},
                         [](double) { return 0.0; }});
    _solver->add_motion({"top", _top, MotionKind::velocity, {false, false, true},
                         [=](double t) { return t_ramp > 0.0 ? v_top * std::min(1.0, t / t_ramp) : v_top; }});
    if (_cfg.uniform_start)
    {
      // the bulk at the affine velocity (bottom face z = 0 held), the
      // platens' spheres at their own: no jump at the first step
      for (std::size_t i = 0; i < _p.size(); ++i)
        _p.v[3 * i + 2] = v_top * _p.x[3 * i + 2] / H;
      for (auto i : _bottom)
        _p.v[3 * i + 2] = 0.0;
      for (auto i : _top)
        _p.v[3 * i + 2] = v_top;
    }
  }

  /// Triaxial test: four loading plates (dem::ParticleForce::plate), one
  /// per side face of the prism, of the spheres touching it (centre within
  /// r + layer): those at a vertical edge belong to both faces, the
  /// platens' spheres (held axially only) too, so that no sphere is squeezed
  /// out between two plates or between a plate and a platen. Each pushes its face inwards with the
  /// lateral stress times the face's current area (side_force): the sample
  /// is first compressed hydrostatically, then axially under the constant
  /// lateral pressure.
  void set_up_confinement()
  {
    if (_cfg.test != "triaxial")
      return;
    const double D = _cfg.diameter;
    for (std::size_t i = 0; i < _p.size(); ++i)
    {
      const double* x = &_p.x[3 * i];
      const double d[4] = {x[0], D - x[0], x[1], D - x[1]};
      for (int k = 0; k < 4; ++k)
        if (d[k] - _p.r[i] < _layer)
          _side[k].push_back(static_cast<std::int32_t>(i));
    }
    static const char* names[4] = {"side x-", "side x+", "side y-", "side y+"};
    for (int k = 0; k < 4; ++k)
    {
      if (_side[k].empty())
        throw std::runtime_error(std::string("no sphere touches the ") + names[k]
                                 + " face: is the packing made for this sample size?");
      std::array<double, 3> inward{0.0, 0.0, 0.0};
      inward[k / 2] = k % 2 == 0 ? 1.0 : -1.0;
      const double share = 1.0 / static_cast<double>(_side[k].size());
      _solver->add_force({names[k], _side[k], inward,
                          [this, k, share](double t) { return side_force(k, t) * share; }, true});
    }
  }

  /// The force on side face k at time t [N]: the lateral stress times the
  /// face's current area (the four computed once per time). The lateral
  /// stress is the axial compressive stress at the last step until it
  /// reaches the confinement, the confinement from then on.
  double side_force(int k, double t)
  {
    if (t != _side_t)
    {
      _side_t = t;
      const auto w = widths();
      const double P = _cfg.confinement, h = _cfg.height + mean_uz(_top) - mean_uz(_bottom);
      _lateral = _confined ? P : std::clamp(-axial_stress(w[0] * w[1]), 0.0, P);
      _confined = _lateral == P;
      // faces x- and x+ span the width along y, faces y- and y+ along x
      for (int q = 0; q < 4; ++q)
        _side_f[q] = _lateral * (w[q / 2 == 0 ? 1 : 0] * h);
    }
    return _side_f[k];
  }

  /// The mean outward displacement of side face k's plate [m].
  double side_displacement(int k) const
  {
    const int c = k / 2;
    const double out = k % 2 == 0 ? -1.0 : 1.0;
    double u = 0.0;
    for (auto i : _side[k])
      u += _p.x[3 * i + c] - _p.x0[3 * i + c];
    return out * u / static_cast<double>(_side[k].size());
  }
  /// Current widths of the prism along x and y [m] (the side plates' distance).
  std::array<double, 2> widths() const
  {
    const double D = _cfg.diameter;
    return {D + side_displacement(0) + side_displacement(1), D + side_displacement(2) + side_displacement(3)};
  }
  /// The axial stress [Pa] (> 0 in tension), averaged over the gauge: the
  /// platens' reactions at the last step (see measure()) over the cross
  /// section `area`.
  double axial_stress(double area) const
  {
    const double s_top = _solver->reaction("top")[2] / area, s_bot = -_solver->reaction("bottom")[2] / area;
    return s_bot + 13.0 / 48.0 * (s_top - s_bot);
  }
  /// The same over the initial section, or the current one in a triaxial
  /// test (its strains reach several %).
  double axial_stress() const
  {
    if (_cfg.test != "triaxial")
      return axial_stress(_area);
    const auto w = widths();
    return axial_stress(w[0] * w[1]);
  }

  void set_up_gauges()
  {
    const double D = _cfg.diameter, H = _cfg.height;
    // lateral gauges: spheres on the lateral surface in the middle third
    for (std::size_t i = 0; i < _p.size(); ++i)
    {
      const double* x = &_p.x[3 * i];
      if (x[2] < H / 3.0 || x[2] > 2.0 * H / 3.0)
        continue;
      if (_region.sdf({x[0], x[1], x[2]}) + _p.r[i] < -_layer)
        continue;
      std::array<double, 3> dir{0.0, 0.0, 0.0};
      if (_cyl)
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
      _gauge.push_back(static_cast<std::int32_t>(i));
      _gauge_dir.push_back(dir);
    }
    if (_gauge.empty())
      throw std::runtime_error("no sphere on the lateral face at mid-height to measure the lateral strain");
    _half_width = 0.5 * D;
    // axial gauge: every sphere centred within Rmax of z = H/4 and of
    // z = 3H/4; the strain of the middle half is the change of the two
    // slabs' mean distance over its initial value. The platen strain
    // (u_top - u_bot) / H also counts the spheres' layers at both ends,
    // which the links do not strain like the bulk (the centres of the held
    // spheres lie ~R inside the faces): it overestimates E by 5-9 % on small
    // samples, depending on their height. E and nu are taken on the gauge,
    // as a laboratory does.
    for (std::size_t i = 0; i < _p.size(); ++i)
    {
      const double z = _p.x[3 * i + 2];
      if (std::abs(z - 0.25 * H) < _rmax)
        _g_lo.push_back(static_cast<std::int32_t>(i));
      else if (std::abs(z - 0.75 * H) < _rmax)
        _g_hi.push_back(static_cast<std::int32_t>(i));
    }
    if (_g_lo.empty() || _g_hi.empty())
      throw std::runtime_error("no sphere at a quarter of the height to measure the axial strain");
    _gauge_length = mean_z(_g_hi, _p.x0) - mean_z(_g_lo, _p.x0);
  }

  /// The summary's description of the sample and the run.
  void describe()
  {
    _out["test"] = _cfg.test;
    _out["shape"] = _cfg.shape;
    _out["particles"] = _p.size();
    _out["links"] = _links.size();
    _out["floppy_spheres"] = floppy_spheres(_p, _links).size();
    _out["ligament"] = _cfg.ligament;
    _out["lambda"] = _lambda;
    _out["mean_links_per_particle"] = 2.0 * _links.size() / _p.size();
    {
      // in the bulk, where --links-per-sphere applies
      std::size_t nb = 0, lb = 0;
      for (std::size_t k = 0; k < _links.size(); ++k)
        lb += _bulk[_links.a[k]] + _bulk[_links.b[k]];
      for (auto f : _bulk)
        nb += f;
      _out["bulk_links_per_particle"] = nb ? static_cast<double>(lb) / nb : 0.0;
    }
    _out["packing_fraction"] = _fraction;
    _out["dt_s"] = _dt;
    _out["dt_critical_s"] = _dt_crit;
    _out["damping_per_s"] = _damping;
    _out["packing_sweeps"] = _pk.sweeps;
  }

  void open_output()
  {
    if (_cfg.output_dir.empty())
      return;
    const std::filesystem::path dir(_cfg.output_dir);
    std::filesystem::create_directories(dir);
    _writer = std::make_unique<ParticleWriter>(dir / "particles.xdmf", _links, _p.size());
    _writer->write(0.0, _p, _links);
    _csv.open(dir / "stress_strain.csv");
    _csv << "time_s,strain,stress_pa,lateral_strain,bottom_reaction_n,links_broken_tension,"
            "links_broken_shear,kinetic_j,elastic_j,softening_j,breakage_j,friction_j,damping_j,"
            "work_j,imbalance_j,gauge_strain,top_reaction_n,lateral_stress_pa\n";
  }

  /// The curves, by their names in the checkpoint's /run group.
  std::array<std::pair<const char*, std::vector<double>*>, 5> curves()
  {
    return {{{"strain", &_eps}, {"stress", &_sig}, {"lateral_strain", &_lat}, {"gauge_strain", &_ax},
             {"lateral_stress", &_conf}}};
  }

  /// Continues from the checkpoint: the solver's state, the curves and
  /// what is tracked along them, and the output files up to the checkpoint.
  void resume()
  {
    const auto file = _ckpt->open_restart();
    const auto root = file.root();
    _solver->load(root.group("dem"));
    const auto run = root.group("run");
    for (const auto& [name, curve] : curves())
      run.read(name, *curve);
    std::vector<double> tracked;
    run.read("tracked", tracked);
    if (tracked.size() != 11)
      run.fail("tracked", "not the 11 values of the peak tracking (file damaged, or of another version?)");
    _peak = tracked[0];
    _eps_peak = tracked[1];
    _dissipated_at_peak = tracked[2];
    _demand_at_peak = tracked[3];
    _after_peak = tracked[4] != 0.0;
    _separated = tracked[5] != 0.0;
    _t_low = tracked[6];
    _axial_at_peak = tracked[7];
    _lateral_at_peak = tracked[8];
    _confined = tracked[9] != 0.0;
    _lateral = tracked[10];
    _out["restarted_from_step"] = _solver->steps();
    if (_cfg.output_dir.empty())
      return;
    const std::filesystem::path dir(_cfg.output_dir);
    _writer = std::make_unique<ParticleWriter>(dir / "particles.xdmf", _links, _p.size(), true,
                                               root.group("particles_xdmf"));
    reopen_text(_csv, dir / "stress_strain.csv", run.read_int("csv_bytes"));
  }

  /// The checkpoint: the solver, the curves, the output files' extent.
  void save(const checkpoint::Group& root)
  {
    _solver->save(root.group("dem"));
    const auto run = root.group("run");
    for (const auto& [name, curve] : curves())
      run.write(name, *curve);
    run.write("tracked", std::vector<double>{_peak, _eps_peak, _dissipated_at_peak, _demand_at_peak,
                                             _after_peak ? 1.0 : 0.0, _separated ? 1.0 : 0.0, _t_low,
                                             _axial_at_peak, _lateral_at_peak, _confined ? 1.0 : 0.0,
                                             _lateral});
    if (_writer)
      _writer->save(root.group("particles_xdmf"));
    if (_csv.is_open())
      run.write_int("csv_bytes", flushed_size(_csv, std::filesystem::path(_cfg.output_dir) / "stress_strain.csv"));
  }

  void print_header()
  {
    const double t_end = _max_strain / _cfg.strain_rate + _t_ramp / 2.0;
    _nsteps = static_cast<std::int64_t>(std::ceil(t_end / _dt));
    if (_cfg.quiet)
      return;
    const auto& mt = _cfg.material;
    std::cout << "# material: E " << mt.youngs_modulus << " Pa, nu " << mt.poisson_ratio
              << ", density " << mt.density << " kg/m^3, alpha " << mt.micro.alpha << ", beta "
              << mt.micro.beta << ", gamma " << mt.micro.gamma << ", T " << mt.tensile
              << " Pa, C0 " << mt.cohesion << " Pa, zeta " << mt.zeta << ", phi_i "
              << mt.phi_i_deg << " deg, phi_c " << mt.phi_c_deg << " deg\n";
    std::cout << _p.size() << " spheres, " << _links.size() << " links (lambda " << _lambda
              << "), dt " << _dt << " s (critical " << _dt_crit << "), up to " << _nsteps
              << " steps, damping " << _damping << " 1/s\n"
              << "      strain    stress [Pa]  broken t/s       kinetic [J]     elastic [J]"
                 "   dissipated [J]      work [J]   imbalance [J]\n";
  }

  // ---- loading --------------------------------------------------------------
  static double mean_z(const std::vector<std::int32_t>& ids, const std::vector<double>& x)
  {
    double s = 0.0;
    for (auto i : ids)
      s += x[3 * i + 2];
    return s / ids.size();
  }
  double mean_uz(const std::vector<std::int32_t>& ids) const
  {
    double u = 0.0;
    for (auto i : ids)
      u += _p.x[3 * i + 2] - _p.x0[3 * i + 2];
    return u / ids.size();
  }

  void load()
  {
    const std::int64_t nsteps = _nsteps;
    const std::int64_t sample_every = std::max<std::int64_t>(1, nsteps / 2000);
    const std::int64_t frame_every = std::max<std::int64_t>(1, nsteps / std::max(1, _cfg.frames));
    const std::int64_t print_every = std::max<std::int64_t>(1, nsteps / 20);
    // the shared time loop (time_loop.h); the measurement points drive the
    // end condition (past the peak) and write the rows and frames
    const LoopPlan plan{
        .done = _solver->steps(), .last = nsteps, .rows = {}, .frames = {}, .prints = {}, .checkpoints = _ckpt.get()};
    LoopHooks h = solver_hooks(*_solver);
    h.after_step = [&](std::int64_t s)
    {
      if (s % sample_every == 0 || s % frame_every == 0)
        measure(s % print_every == 0, s % frame_every == 0);
    };
    h.finished = [this](std::int64_t) { return _after_peak; };
    h.save = [this](const checkpoint::Group& g) { save(g); };
    run_time_loop(plan, h);
    measure(true, true);
    if (_writer)
      _writer->close();
  }

  /// One point of the curves: platen strain, gauge stress and strains; the
  /// peak, the stop criteria; the CSV row, the progress line, the frame.
  void measure(bool print, bool frame);

  /// The peak of |axial stress| (of the deviator, |axial stress| less the
  /// lateral one, in a triaxial test), the stop criteria.
  void track_peak(double strain, double stress, double confining, double s_bot);

  void write_point(bool print, double strain, double stress, double lateral, double axial, double f_top,
                   double confining)
  {
    const auto e = _solver->energy();
    const auto bt = _links.count(LinkState::broken_tension), bs = _links.count(LinkState::broken_shear);
    if (_csv.is_open())
      _csv << _solver->time() << ',' << strain << ',' << stress << ',' << lateral << ','
           << _solver->reaction("bottom")[2] << ',' << bt << ',' << bs << ',' << e.kinetic << ','
           << e.elastic << ',' << e.softening << ',' << e.breakage << ',' << e.friction << ','
           << e.damping << ',' << e.external_work + e.prescribed_work << ',' << e.imbalance()
           << ',' << axial << ',' << f_top << ',' << confining << '\n' << std::flush; // whole rows if killed
    if (print && !_cfg.quiet)
      std::cout << std::scientific << std::setprecision(4) << std::setw(12) << strain
                << std::setw(15) << stress << std::setw(7) << bt << "/" << std::left
                << std::setw(6) << bs << std::right << std::setw(16) << e.kinetic
                << std::setw(16) << e.elastic << std::setw(16)
                << e.softening + e.breakage + e.friction + e.damping << std::setw(16)
                << e.external_work + e.prescribed_work << std::setw(16) << e.imbalance()
                << std::defaultfloat << "\n";
  }

  // ---- measurement ----------------------------------------------------------
  /// Elastic moduli from the initial part: points with |stress| between 5 %
  /// and 30 % of the peak, before the peak, on the axial gauge.
  void measure_moduli();

  /// Triaxial test: the bulk modulus of the hydrostatic phase, the slope of
  /// the mean stress (|axial| + 2 lateral) / 3 against the volumetric strain
  /// (the axial gauge's and twice the lateral gauge's, shortening > 0), over
  /// the points with the lateral pressure between 10 % and 50 % of the
  /// confinement; and Young's modulus and Poisson's ratio of the deviatoric
  /// phase (the lateral pressure held), the slopes of the deviator and of
  /// the lateral strain against the axial gauge strain over the points with
  /// the deviator between 5 % and 30 % of its peak, before the peak. An
  /// isotropic elastic solid has K = E / (3 (1 - 2 nu)), and the deviatoric
  /// phase's E and nu are the uniaxial test's.
  void measure_triaxial_moduli();

  void report();

  /// Where the links broke: the median height of the broken links' mid-points
  /// (the crack's height in a tension test) and how many broke within 2 Rmax
  /// of either platen (a crack there would be the platens', not the
  /// concrete's).
  void crack_location();

  // ---- state ----------------------------------------------------------------
  const SampleConfig& _cfg;
  Stopwatch _clock;
  nlohmann::json _out;
  // the sample
  bool _cyl = true;
  Region _region;
  double _area = 0.0, _fraction = 0.0, _lambda = 0.0, _rmax = 0.0, _rmin = 0.0;
  Packing _pk;
  Particles _p;
  std::vector<std::uint8_t> _bulk;
  Links _links;
  // time step and loading
  double _dt_crit = 0.0, _dt = 0.0, _c_wave = 0.0, _damping = 0.0, _max_strain = 0.0,
         _v_top = 0.0, _t_ramp = 0.0;
  std::int64_t _nsteps = 0;
  std::unique_ptr<DemSolver> _solver;
  std::unique_ptr<Checkpointer> _ckpt;
  // platens and gauges
  double _layer = 0.0, _half_width = 0.0, _gauge_length = 0.0;
  std::vector<std::int32_t> _bottom, _top, _gauge, _g_lo, _g_hi;
  std::array<std::vector<std::int32_t>, 4> _side; // a triaxial test's side faces: x-, x+, y-, y+
  std::array<double, 4> _side_f{};                // their forces at _side_t [N]
  double _side_t = -1.0;
  double _lateral = 0.0;   // the lateral stress applied over the last step [Pa]
  bool _confined = false;  // the lateral stress has reached the confinement
  std::vector<std::array<double, 3>> _gauge_dir;
  // output
  std::unique_ptr<ParticleWriter> _writer;
  std::ofstream _csv;
  // the curves and what is tracked along them
  std::vector<double> _eps, _sig, _lat, _ax, _conf; // _conf: the side plates' pressure (triaxial)
  double _peak = 0.0, _eps_peak = 0.0;
  double _axial_at_peak = 0.0, _lateral_at_peak = 0.0; // stresses at the peak [Pa]
  double _dissipated_at_peak = 0.0; // by the links (softening + breakage) [J]
  double _demand_at_peak = 0.0;     // the solver's cohesion demand then [Pa]
  bool _after_peak = false, _separated = false;
  double _t_low = -1.0; // since when the force through the crack is below 1 % of the peak
};


} // namespace dembridge::demo::sample_detail
