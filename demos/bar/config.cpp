// The bar's configuration checked, and the moduli and frequency its
// references use (bar.h).
#include "bar.h"

#include "dembridge/shell/analytic.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace dembridge::demo
{
void refuse_value(const std::string& what, double value, const std::string& allowed)
{
  std::ostringstream s;
  s << what << " " << value << ": allowed is " << allowed;
  throw std::runtime_error(s.str());
}

void check_config(const BarConfig& c)
{
  if (c.model != "fe" && c.model != "coupled" && c.model != "de")
    throw std::runtime_error("model '" + c.model + "': allowed are fe, coupled, de");
  if (c.load != "tension" && c.load != "bending")
    throw std::runtime_error("load '" + c.load + "': allowed are tension, bending");
  if (c.regime != "static" && c.regime != "dynamic")
    throw std::runtime_error("regime '" + c.regime + "': allowed are static, dynamic");
  if (!(c.length > 0.0))
    refuse_value("length [m]", c.length, "> 0");
  if (!(c.width > 0.0 && c.width < c.length))
    refuse_value("width [m]", c.width, "in (0, length)");
  if (!(c.fe_size > 0.0 && c.fe_size <= c.width))
    refuse_value("fe-size [m]", c.fe_size, "in (0, width]");
  if (!(c.mean_radius > 0.0 && c.mean_radius < 0.1 * c.width))
    refuse_value("mean-radius [m]", c.mean_radius, "in (0, width / 10)");
  if (c.overlap_layers < 1)
    refuse_value("overlap-layers", c.overlap_layers, ">= 1");
  if (!(c.safety > 0.0 && c.safety <= 0.95))
    refuse_value("safety-factor", c.safety, "in (0, 0.95] (the critical step is a power-iteration estimate, from below)");
  if (c.damping >= 0.0 && !std::isfinite(c.damping))
    refuse_value("damping [1/s]", c.damping, "finite, >= 0 (or < 0 for the default)");
  for (double p : {c.probe_de, c.probe_overlap, c.probe_overlap_fe})
    if (!(p > 0.0 && p < c.length))
      refuse_value("probe position [m]", p, "in (0, length)");
  if (c.frames < 1)
    refuse_value("frames", c.frames, ">= 1");
}

double measured_modulus(const nlohmann::json& run)
{
  if (!run.contains("measured_youngs_modulus_pa"))
    throw std::runtime_error("measured_modulus: not a static tension run with spheres");
  return run.at("measured_youngs_modulus_pa").get<double>();
}

double bar_modulus(BarConfig c)
{
  c.model = "de";
  c.load = "tension";
  c.regime = "static";
  c.output.clear();
  c.quiet = true;
  c.restart = nullptr; // a pre-run: the checkpoints are the case's
  return measured_modulus(run_bar(c));
}

double bar_first_frequency(const BarConfig& c, double E, double nu, double rho)
{
  if (c.load == "tension")
    return shell::analytic::axial_clamped_free_frequency(E, rho, c.length);
  return shell::analytic::timoshenko_cantilever_frequency(E, nu, rho, {c.width, c.width}, c.length,
                                                          5.0 / 6.0);
}

} // namespace dembridge::demo
