// The identification's runner and its steps (runner.h).
#include "runner.h"

#include "dembridge/dem/packing.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

namespace dembridge::demo::calib
{

/// Generates the sample's packing (sample_packing of its generator
/// settings, whatever packing file it names) into a temporary file and
/// returns its path.
std::string temporary_packing(SampleConfig s, const std::string& tag)
{
  s.packing_file.clear();
  const auto file = std::filesystem::temp_directory_path()
                    / ("dembridge_calibration_" + std::to_string(::getpid()) + "_" + tag + ".txt");
  dem::write_packing(file, sample_packing(s));
  return file.string();
}

/// E and nu (initial tangent of an elastic compression test, on the first
/// packing) and, unless elastic_only, the peaks of full tension and
/// compression tests: their means over the runner's packings, each
/// packing's in "packings" when there are several. The first packing's
/// tests write the output folders and give *tension, *compression.
nlohmann::json measure(Runner& R, const dem::Material& m, bool elastic_only, nlohmann::json* tension,
                       nlohmann::json* compression, const std::string& out_t,
                       const std::string& out_c)
{
  const auto elastic = R.run(m, "compression", true);
  nlohmann::json a = {{"youngs_modulus_pa", elastic["youngs_modulus_pa"]},
                      {"poisson_ratio", elastic["poisson_ratio"]}};
  if (elastic_only)
  {
    const auto c = R.run(m, "compression", true, out_c);
    if (compression)
      *compression = c;
    return a;
  }
  double st = 0.0, sc = 0.0;
  nlohmann::json each = nlohmann::json::array();
  for (std::size_t p = 0; p < R.packings(); ++p)
  {
    const auto rt = R.run({m, "tension", false, p == 0 ? out_t : "", false, p});
    const auto rc = R.run({m, "compression", false, p == 0 ? out_c : "", false, p});
    const double t = rt["peak_stress_pa"].get<double>(), c = rc["peak_stress_pa"].get<double>();
    st += t / R.packings(), sc += c / R.packings();
    each.push_back({{"seed", R.cfg.sample.seed + p}, {"tensile_strength_pa", t}, {"compressive_strength_pa", c}});
    if (p > 0)
      continue;
    // for information: the secant-like slope of the full compression test
    // (5-30 % of the peak) already includes early link failures
    a["compression_test_modulus_pa"] = rc["youngs_modulus_pa"];
    if (tension)
      *tension = rt;
    if (compression)
      *compression = rc;
  }
  a["tensile_strength_pa"] = st;
  a["compressive_strength_pa"] = sc;
  if (R.packings() > 1)
    a["packings"] = each;
  return a;
}

/// Differences of `a` from `ref` (relative; nu absolute) and whether each is
/// within its tolerance.
nlohmann::json compare(const nlohmann::json& a, const nlohmann::json& ref, double tol_e, double tol_nu,
                       double tol_s)
{
  nlohmann::json d, ok;
  bool all = true;
  for (const char* k : {"youngs_modulus_pa", "poisson_ratio", "tensile_strength_pa", "compressive_strength_pa"})
  {
    if (!a.contains(k) || !ref.contains(k))
      continue;
    const double x = a[k].get<double>(), y = ref[k].get<double>();
    const bool nu = std::string(k) == "poisson_ratio";
    const double diff = nu ? x - y : x / y - 1.0;
    const double tol = nu ? tol_nu : (std::string(k) == "youngs_modulus_pa" ? tol_e : tol_s);
    d[k] = diff;
    ok[k] = std::abs(diff) < tol;
    all = all && std::abs(diff) < tol;
  }
  return {{"achieved", a}, {"difference", d}, {"within_tolerance", ok}, {"within", all}};
}

[[noreturn]] void unreachable(const std::string& what, double v, double lo, double hi,
                              const std::string& why)
{
  std::ostringstream s;
  s << "target " << what << " = " << v << " cannot be reached on this packing: the reachable range is ["
    << lo << ", " << hi << "] (" << why << ")";
  throw std::runtime_error(s.str());
}

/// m with softening zeta, T = t's sigma_t and C0 = rho T: the strengths'
/// scale is irrelevant for sigma_c/sigma_t and G_f/sigma_t^2.
dem::Material at_ratio(const dem::Material& m, const Targets& t, double zeta, double rho)
{
  dem::Material q = m;
  q.zeta = zeta;
  q.tensile = t.tensile_strength;
  q.cohesion = rho * q.tensile;
  return q;
}

std::pair<double, double> solve_ratio(Runner& R, const dem::Material& m, const Targets& t, double tol,
                                      double rho_guess, double* slope,
                                      std::vector<std::array<double, 2>>* tested)
{
  const double ratio_target = t.compressive_strength / t.tensile_strength;
  // best test so far: (|miss|, rho, st)
  std::array<double, 3> best{1e300, 0.0, 0.0};
  auto strengths = [&](double rho)
  {
    const auto [st, sc, gf] = R.means(at_ratio(m, t, m.zeta, rho), true, false);
    const double miss = std::log(sc / st / ratio_target);
    if (tested)
      tested->push_back({rho, miss});
    if (std::abs(miss) < best[0])
      best = {std::abs(miss), rho, st};
    return std::pair{st, sc};
  };
  double r_lo = 0.3, r_hi = 30.0;
  double st_lo = 0.0, sc_lo = 0.0, st_hi = 0.0, sc_hi = 0.0;
  bool bracketed = false;
  if (rho_guess > 0.0 && *slope > 0.0)
  {
    double x = std::log(rho_guess), sl = *slope;
    auto [st, sc] = strengths(rho_guess);
    if (std::abs(sc / st / ratio_target - 1.0) < tol)
      return {rho_guess, st};
    for (int it = 0; it < 3 && !bracketed; ++it)
    {
      const double q = sc / st;
      const double step = std::clamp((ratio_target - q) / sl, -std::log(2.0), std::log(2.0));
      const double xn = std::clamp(x + step, std::log(0.3), std::log(30.0));
      if (std::abs(xn - x) < 1e-9)
        break;
      auto [stn, scn] = strengths(std::exp(xn));
      const double qn = scn / stn;
      if (std::abs(qn / ratio_target - 1.0) < tol)
        return {std::exp(xn), stn};
      if ((q - ratio_target) * (qn - ratio_target) < 0.0)
      {
        bracketed = true;
        const bool up = xn > x;
        r_lo = std::exp(up ? x : xn), r_hi = std::exp(up ? xn : x);
        st_lo = up ? st : stn, sc_lo = up ? sc : scn;
        st_hi = up ? stn : st, sc_hi = up ? scn : sc;
      }
      if ((qn - q) / (xn - x) > 0.0)
        sl = (qn - q) / (xn - x);
      x = xn, st = stn, sc = scn;
    }
  }
  if (!bracketed)
  {
    r_lo = 0.3, r_hi = 30.0;
    std::tie(st_lo, sc_lo) = strengths(r_lo);
    std::tie(st_hi, sc_hi) = strengths(r_hi);
  }
  double q_lo = sc_lo / st_lo, q_hi = sc_hi / st_hi;
  if (ratio_target < q_lo || ratio_target > q_hi)
    unreachable("sigma_c/sigma_t", ratio_target, q_lo, q_hi,
                "C0/T from 0.3 to 30 at zeta = " + std::to_string(m.zeta));
  // regula falsi on log(C0/T) with the Illinois modification (the end
  // kept twice in a row has its residual halved), bisection when the
  // secant leaves the inner 90 % of the bracket (the ratio is nearly
  // linear in log(C0/T): one pair of tests on the default sample where
  // bisection took 6)
  double rho = r_lo, st = st_lo;
  double f_lo = q_lo - ratio_target, f_hi = q_hi - ratio_target;
  double q_lo_raw = q_lo, q_hi_raw = q_hi; // without the Illinois halving
  int kept = 0; // +1: the low end was kept last time, -1: the high end
  for (int it = 0; it < 20; ++it)
  {
    const double x_lo = std::log(r_lo), x_hi = std::log(r_hi);
    if (x_hi - x_lo < noise_width)
    {
      rho = best[1], st = best[2];
      if (!R.cfg.quiet)
        std::cout << "  C0/T bracket [" << r_lo << ", " << r_hi << "] narrower than the noise of "
                  << "sigma_c/sigma_t allows to resolve: the nearest test, C0/T = " << rho << " ("
                  << 100.0 * std::expm1(best[0]) << " % from the target ratio), is taken" << std::endl;
      break;
    }
    double x = x_lo - f_lo * (x_hi - x_lo) / (f_hi - f_lo);
    if (!(x > x_lo + 0.05 * (x_hi - x_lo) && x < x_hi - 0.05 * (x_hi - x_lo)))
      x = 0.5 * (x_lo + x_hi);
    const double r = std::exp(x);
    auto [a, b] = strengths(r);
    rho = r;
    st = a;
    const double q = b / a;
    if (std::abs(q / ratio_target - 1.0) < tol)
      break;
    if (q < ratio_target)
    {
      r_lo = r, f_lo = q - ratio_target, q_lo_raw = q;
      if (kept == -1)
        f_hi *= 0.5;
      kept = -1;
    }
    else
    {
      r_hi = r, f_hi = q - ratio_target, q_hi_raw = q;
      if (kept == 1)
        f_lo *= 0.5;
      kept = 1;
    }
  }
  *slope = (q_hi_raw - q_lo_raw) / (std::log(r_hi) - std::log(r_lo));
  return {rho, st};
}

} // namespace dembridge::demo::calib
