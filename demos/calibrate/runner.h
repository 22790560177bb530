#pragma once
// Internal to the calibrate demo: the runner of the identification's
// simulated tests (a cache of deterministic runs, their means over
// packings) and the steps the identification (identify.cpp) is built of.
#include "identify.h"

#include <iostream>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace dembridge::demo::calib
{
/// One simulated test: material, test (tension | compression | fracture:
/// notched tension to separation), elastic (no breakage, a short run), an
/// output folder ("" = none), peak_only (only the peak stress, E and nu
/// are used) and which of the runner's packings.
struct Request
{
  dem::Material m;
  std::string test;
  bool elastic = false;
  std::string out;
  bool peak_only = false;
  std::size_t packing = 0;
};

struct Runner
{
  /// packings: the sample's files, one per seed (cfg.sample.packing_file
  /// is the first)
  Runner(const IdentifyConfig& c, std::vector<std::string> packings) : cfg(c), files(std::move(packings)) {}
  IdentifyConfig cfg;
  std::vector<std::string> files;
  nlohmann::json history = nlohmann::json::array();
  /// results of runs without output, by test, material and packing: the
  /// runs are deterministic, so a repeated one is not simulated again
  std::map<std::string, nlohmann::json> done;
  /// the same by test, packing and material but C0, with their C0: a run
  /// whose links never reached the shear cap (SampleConfig:
  /// cohesion_demand_pa) is the same bit for bit with any C0 above its demand
  std::map<std::string, std::vector<std::pair<double, nlohmann::json>>> by_rest;
  /// peak-only reuses already made, by test, packing and material
  std::map<std::string, nlohmann::json> peak_done;

  std::size_t packings() const { return files.size(); }

  nlohmann::json run(const dem::Material& m, const std::string& test, bool elastic,
                     const std::string& out = "", bool peak_only = false)
  {
    return run(Request{m, test, elastic, out, peak_only, 0});
  }

  /// A run with another C0 serves when it did not reach the shear cap with
  /// either C0 (cohesion_demand_pa): it is the same bit for bit. With
  /// peak_only it serves when it did not reach the cap before its peak
  /// (cohesion_demand_at_peak_pa): the same run up to the peak; the
  /// post-peak part may differ, so such a reuse is kept apart (peak_done)
  /// and the final tests are always run.
  nlohmann::json run(const Request& r)
  {
    const dem::Material& m = r.m;
    SampleConfig s = cfg.sample;
    s.packing_file = files.at(r.packing);
    s.material = m;
    s.test = r.test;
    s.quiet = true;
    s.output_dir = r.out;
    if (r.elastic)
    {
      s.material.tensile = s.material.cohesion = 1e12; // no breakage
      s.max_strain = 5e-5;
    }
    if (r.test == "fracture")
    {
      s.test = "tension";
      s.ligament = cfg.ligament;
      s.to_separation = true;
      s.max_strain = 0.0; // 5e-3
    }
    std::ostringstream rest;
    rest.precision(17);
    rest << r.test << ' ' << r.elastic << ' ' << r.packing << ' ' << m.youngs_modulus << ' ' << m.poisson_ratio
         << ' ' << m.density << ' ' << m.micro.alpha << ' ' << m.micro.beta << ' ' << m.micro.gamma << ' '
         << m.tensile << ' ' << m.zeta << ' ' << m.phi_i_deg << ' ' << m.phi_c_deg;
    std::ostringstream key;
    key.precision(17);
    key << rest.str() << ' ' << m.cohesion;
    if (r.out.empty())
    {
      if (auto it = done.find(key.str()); it != done.end())
        return it->second;
      if (auto it = peak_done.find(key.str()); r.peak_only && it != peak_done.end())
        return it->second;
      // the shear cap never reached, up to the peak or in the whole run
      const char* demand = r.peak_only ? "cohesion_demand_at_peak_pa" : "cohesion_demand_pa";
      if (!r.elastic)
        for (const auto& [c0, x] : by_rest[rest.str()])
        {
          const double d = x[demand].get<double>() * (1.0 + 1e-9);
          if (d < c0 && d < m.cohesion)
          {
            record(r, x, c0);
            (r.peak_only ? peak_done : done)[key.str()] = x;
            return x;
          }
        }
    }
    auto x = run_sample(s);
    if (r.out.empty())
    {
      done[key.str()] = x;
      by_rest[rest.str()].emplace_back(m.cohesion, x);
    }
    if (r.test == "fracture" && !x["separated"].get<bool>())
      throw std::runtime_error("the notched sample did not separate by a strain of "
                               + std::to_string(x["final_strain"].get<double>())
                               + " (zeta = " + std::to_string(m.zeta) + "): no fracture energy");
    record(r, x, 0.0);
    return x;
  }

  void record(const Request& q, const nlohmann::json& r, double reused_from)
  {
    const dem::Material& m = q.m;
    nlohmann::json h = {{"test", q.elastic ? "elastic " + q.test : q.test},
                        {"seed", cfg.sample.seed + q.packing},
                        {"alpha", m.micro.alpha},
                        {"beta", m.micro.beta},
                        {"gamma", m.micro.gamma},
                        {"tensile_strength_pa", m.tensile},
                        {"cohesion_pa", m.cohesion},
                        {"softening", m.zeta},
                        {"youngs_modulus_pa", r["youngs_modulus_pa"]},
                        {"poisson_ratio", r["poisson_ratio"]},
                        {"peak_stress_pa", r["peak_stress_pa"]},
                        {"particles", r["particles"]},
                        {"wall_s", reused_from > 0.0 ? 0.0 : r["wall_s"].get<double>()}};
    if (reused_from > 0.0)
      h["reused_from_cohesion_pa"] = reused_from;
    if (q.test == "fracture")
      h["fracture_energy_j_m2"] = r["fracture_energy_j_m2"];
    history.push_back(h);
    if (!cfg.quiet)
      std::cout << "  " << h.dump() << std::endl;
  }

  /// Means over the packings, at material m, of the tension peak (always),
  /// the compression peak and the notched test's G_f (when asked); the
  /// peaks from peak-only runs.
  struct Means
  {
    double st = 0.0, sc = 0.0, gf = 0.0;
  };
  Means means(const dem::Material& m, bool compression, bool fracture)
  {
    const double w = 1.0 / packings();
    Means a;
    for (std::size_t p = 0; p < packings(); ++p)
    {
      a.st += w * run({m, "tension", false, "", true, p})["peak_stress_pa"].get<double>();
      if (compression)
        a.sc += w * run({m, "compression", false, "", true, p})["peak_stress_pa"].get<double>();
      if (fracture)
        a.gf += w * run({m, "fracture", false, "", false, p})["fracture_energy_j_m2"].get<double>();
    }
    return a;
  }
};

/// Generates the sample's packing (sample_packing of its generator
/// settings, whatever packing file it names) into a temporary file and
/// returns its path.
std::string temporary_packing(SampleConfig s, const std::string& tag);

/// E and nu (initial tangent of an elastic compression test, on the first
/// packing) and, unless elastic_only, the peaks of full tension and
/// compression tests: their means over the runner's packings, each
/// packing's in "packings" when there are several. The first packing's
/// tests write the output folders and give *tension, *compression.
nlohmann::json measure(Runner& R, const dem::Material& m, bool elastic_only, nlohmann::json* tension = nullptr,
                       nlohmann::json* compression = nullptr, const std::string& out_t = "",
                       const std::string& out_c = "");

/// Differences of `a` from `ref` (relative; nu absolute) and whether each is
/// within its tolerance.
nlohmann::json compare(const nlohmann::json& a, const nlohmann::json& ref, double tol_e, double tol_nu,
                       double tol_s);

/// Throws the error of a target out of reach: its value, the reachable
/// range [lo, hi] on this packing and why.
[[noreturn]] void unreachable(const std::string& what, double v, double lo, double hi, const std::string& why);

/// m with softening zeta, T = t's sigma_t and C0 = rho T: the strengths'
/// scale is irrelevant for sigma_c/sigma_t and G_f/sigma_t^2.
dem::Material at_ratio(const dem::Material& m, const Targets& t, double zeta, double rho);

/// Width in log(C0/T) below which a bracket of the ratio is not split
/// further (solve_ratio): 1.5 % noise in sigma_c/sigma_t over the ratio's
/// slope near the solution, d log ratio / d log(C0/T) ~ 0.75 (default
/// sample, zeta 10), is 2 % in C0/T, either side.
inline constexpr double noise_width = 0.04;
/// The band of sigma_c/sigma_t (relative) within which a test counts as
/// hitting the target up to the compression peak's noise (1-2 %).
inline constexpr double q_noise_band = 0.025;

/// C0/T for the targets' sigma_c/sigma_t at m's zeta (regula falsi on
/// log(C0/T)); returns C0/T and sigma_t measured at T = target sigma_t.
/// rho_guess > 0 (a first guess, or a solution at a nearby zeta) with *slope
/// (d ratio / d log(C0/T) there): secant steps from it first (at most a factor 2 each),
/// the whole range [0.3, 30] if three do not bracket the target. *slope is
/// set to the slope of the last bracket.
///
/// The ratio is noisy near the solution (the compression peak is the onset
/// of a cascade of link failures: 1-2 % between nearby C0/T on both the
/// 400-sphere and the default sample), so once the bracket is narrower than
/// `noise_width` in log(C0/T) (what that noise allows to resolve) without
/// a test within tol, the test nearest the target is taken and reported.
/// Each test is appended to *tested as (C0/T, log(ratio / target)).
std::pair<double, double> solve_ratio(Runner& R, const dem::Material& m, const Targets& t, double tol,
                                      double rho_guess, double* slope,
                                      std::vector<std::array<double, 2>>* tested = nullptr);

} // namespace dembridge::demo::calib
