#include "dembridge/dem/material_file.h"

#include <cmath>
#include <fstream>
#include <set>
#include <string>
#include <stdexcept>

namespace dembridge::dem
{
namespace
{
/// The optional tables of format 2: "steel" and "bond" objects, each key
/// optional (absent: the default of Steel or BondLaw).
void read_reinforcement_laws(const nlohmann::json& j, const std::filesystem::path& file, MaterialFile& m)
{
  auto table = [&](const char* name, std::initializer_list<std::pair<const char*, double*>> keys)
  {
    const nlohmann::json& t = j[name];
    if (!t.is_object())
      throw std::runtime_error("material file '" + file.string() + "': \"" + name + "\" must be an object");
    for (const auto& [key, _] : t.items())
    {
      bool known = false;
      for (const auto& [k, v] : keys)
        known = known || key == k;
      if (!known)
        throw std::runtime_error("material file '" + file.string() + "': unknown key '" + name + "." + key + "'");
    }
    for (const auto& [key, v] : keys)
      if (t.contains(key))
      {
        if (!t[key].is_number())
          throw std::runtime_error("material file '" + file.string() + "': '" + name + "." + key + "' is not a number");
        *v = t[key].get<double>();
      }
  };
  if (j.contains("steel"))
  {
    Steel s;
    table("steel", {{"youngs_modulus_pa", &s.youngs_modulus}, {"density_kg_m3", &s.density},
                    {"yield_pa", &s.yield}, {"hardening_pa", &s.hardening}, {"rupture_strain", &s.rupture_strain}});
    m.steel = s;
  }
  if (j.contains("bond"))
  {
    BondLaw b;
    table("bond", {{"tau_max_pa", &b.tau_max}, {"s0_m", &b.s0}, {"s1_m", &b.s1}, {"s2_m", &b.s2}, {"s3_m", &b.s3},
                   {"alpha", &b.alpha}, {"tau_f_ratio", &b.tau_f_ratio}, {"radial_stiffness_pa_m", &b.radial_stiffness},
                   {"opening_pa", &b.opening}, {"opening_gap_m", &b.opening_gap}});
    m.bond = b;
  }
  try
  {
    if (m.steel)
      m.steel->validate();
    if (m.bond)
      m.bond->validate();
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("material file '" + file.string() + "': " + e.what());
  }
}
} // namespace

namespace
{
/// The top-level keys of a material file (format 2; format 1 lacks steel and bond).
const std::set<std::string> known_keys{
    "format", "youngs_modulus_pa", "poisson_ratio", "density_kg_m3", "alpha", "beta", "gamma",
    "tensile_strength_pa", "cohesion_pa", "softening", "phi_i_deg", "phi_c_deg", "links_per_sphere",
    "rate_fc_pa", "rate_max_1_s", "rate_cohesion", "rate_mean_tension", "rate_filter_s", "rate_current",
    "contact_shear_limit_pa", "rolling_friction", "crack_closure", "compaction_onset", "compaction_stiffness",
    "compaction_lock", "compaction_pressure_pa", "steel", "bond", "lambda", "macroscopic", "calibration"};

/// The "macroscopic" block: what the parameters reproduce. Free-form, but the
/// values other programs read from it (the FE side's E and nu in bar and
/// coupled_cantilever, rc_beam's section theory's E, nu and sigma_t) must
/// be physical: checked when a file is read and before one is written.
void check_macroscopic(const nlohmann::json& m, const std::filesystem::path& file)
{
  const std::string at = "material file '" + file.string() + "': ";
  if (!m.is_object())
    throw std::runtime_error(at + "\"macroscopic\" must be an object of measured values");
  struct Range
  {
    const char* key;
    double lo, hi; ///< allowed: (lo, hi)
    const char* allowed;
  };
  static const Range ranges[] = {{"youngs_modulus_pa", 0.0, 1e13, "> 0 Pa"},
                                 {"poisson_ratio", -1.0, 0.5, "in (-1, 0.5)"},
                                 {"tensile_strength_pa", 0.0, 1e12, "> 0 Pa"}};
  for (const Range& r : ranges)
  {
    if (!m.contains(r.key))
      continue;
    const nlohmann::json& v = m[r.key];
    if (!v.is_number())
      throw std::runtime_error(at + "'macroscopic." + r.key + "' must be a number, not " + v.dump());
    const double x = v.get<double>();
    if (!(std::isfinite(x) && x > r.lo && x < r.hi))
      throw std::runtime_error(at + "'macroscopic." + r.key + "' = " + v.dump() + ": must be " + r.allowed);
  }
}
} // namespace

MaterialFile read_material(const std::filesystem::path& file)
{
  std::ifstream in(file);
  if (!in)
    throw std::runtime_error("cannot open material file '" + file.string() + "'");
  const std::string at = "material file '" + file.string() + "': ";
  nlohmann::json j;
  try
  {
    in >> j;
  }
  catch (const std::exception&)
  {
    throw std::runtime_error("material file '" + file.string() + "' is not valid JSON (a file that calibrate "
                             "writes: one object of named values)");
  }
  if (!j.is_object())
    throw std::runtime_error(at + "must hold one JSON object of named values ({\"format\": ..., "
                             "\"youngs_modulus_pa\": ...}), not " + std::string(j.type_name()));
  for (const auto& [key, _] : j.items())
    if (!known_keys.count(key))
      throw std::runtime_error(at + "unknown key '" + key + "' (the keys are listed in docs/demos.md, "
                               "\"Material files\")");
  auto get = [&](const char* key) -> double
  {
    if (!j.contains(key) || !j[key].is_number())
      throw std::runtime_error(at + "missing or non-numeric key '" + key + "'");
    const double v = j[key].get<double>();
    if (!std::isfinite(v))
      throw std::runtime_error(at + "'" + key + "' is not a finite number");
    return v;
  };
  auto get_bool = [&](const char* key) -> bool
  {
    if (!j[key].is_boolean())
      throw std::runtime_error(at + "key '" + key + "' must be true or false");
    return j[key].get<bool>();
  };
  const std::string format = j.contains("format") && j["format"].is_string() ? j["format"].get<std::string>() : "";
  if (format != "dembridge-material-1" && format != "dembridge-material-2")
    throw std::runtime_error(at + "\"format\": " + (j.contains("format") ? j["format"].dump() : "missing")
                             + ": expected \"dembridge-material-2\" (or -1, without steel and bond)");
  MaterialFile m;
  Material& t = m.material;
  t.youngs_modulus = get("youngs_modulus_pa");
  t.poisson_ratio = get("poisson_ratio");
  t.density = get("density_kg_m3");
  t.micro = {get("alpha"), get("beta"), get("gamma")};
  t.tensile = get("tensile_strength_pa");
  t.cohesion = get("cohesion_pa");
  t.zeta = get("softening");
  t.phi_i_deg = get("phi_i_deg");
  t.phi_c_deg = get("phi_c_deg");
  m.links_per_sphere = get("links_per_sphere");
  if (!(m.links_per_sphere > 0.0 && m.links_per_sphere <= 100.0))
    throw std::runtime_error(at + "'links_per_sphere' = " + j["links_per_sphere"].dump() + ": must be in (0, 100]");
  // optional: the strain-rate effect (absent: none)
  if (j.contains("rate_fc_pa"))
    t.rate_fc = get("rate_fc_pa");
  if (j.contains("rate_max_1_s"))
    t.rate_max = get("rate_max_1_s");
  if (j.contains("rate_cohesion"))
    t.rate_cohesion = get_bool("rate_cohesion");
  if (j.contains("rate_mean_tension"))
    t.rate_mean_tension = get_bool("rate_mean_tension");
  if (j.contains("rate_filter_s"))
    t.rate_filter = get("rate_filter_s");
  if (j.contains("rate_current"))
    t.rate_current = get_bool("rate_current");
  // optional: the contacts' Tresca limit (absent: none)
  if (j.contains("contact_shear_limit_pa"))
    t.contact_shear_limit = get("contact_shear_limit_pa");
  // optional: the contacts' rolling resistance (absent: none)
  if (j.contains("rolling_friction"))
    t.rolling_friction = get("rolling_friction");
  // optional: where broken links' spheres meet again (absent: at R_a + R_b)
  if (j.contains("crack_closure"))
    t.crack_closure = get("crack_closure");
  // optional: compaction (absent: none)
  if (j.contains("compaction_onset"))
  {
    t.compaction = {get("compaction_onset"), get("compaction_stiffness"), get("compaction_lock")};
    if (j.contains("compaction_pressure_pa"))
      t.compaction.pressure = get("compaction_pressure_pa");
  }
  if (format == "dembridge-material-2")
    read_reinforcement_laws(j, file, m);
  else if (j.contains("steel") || j.contains("bond"))
    throw std::runtime_error(at + "\"steel\" and \"bond\" need \"format\": \"dembridge-material-2\"");
  if (j.contains("lambda"))
  {
    m.lambda = get("lambda");
    if (m.lambda < 0.0)
      throw std::runtime_error(at + "'lambda' = " + j["lambda"].dump() + ": must be >= 0");
  }
  // (null: none, as files of a MaterialFile without them were written)
  m.macroscopic = j.contains("macroscopic") && !j["macroscopic"].is_null() ? j["macroscopic"] : nlohmann::json::object();
  check_macroscopic(m.macroscopic, file);
  m.calibration = j.contains("calibration") && !j["calibration"].is_null() ? j["calibration"] : nlohmann::json::object();
  try
  {
    t.validate();
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(at + e.what());
  }
  return m;
}

void write_material(const std::filesystem::path& file, const MaterialFile& m)
{
  const Material& t = m.material;
  nlohmann::ordered_json j;
  j["format"] = "dembridge-material-2";
  j["youngs_modulus_pa"] = t.youngs_modulus;
  j["poisson_ratio"] = t.poisson_ratio;
  j["density_kg_m3"] = t.density;
  j["alpha"] = t.micro.alpha;
  j["beta"] = t.micro.beta;
  j["gamma"] = t.micro.gamma;
  j["tensile_strength_pa"] = t.tensile;
  j["cohesion_pa"] = t.cohesion;
  j["softening"] = t.zeta;
  j["phi_i_deg"] = t.phi_i_deg;
  j["phi_c_deg"] = t.phi_c_deg;
  j["links_per_sphere"] = m.links_per_sphere;
  if (t.rate_fc > 0.0)
    j["rate_fc_pa"] = t.rate_fc;
  if (t.rate_max > 0.0)
    j["rate_max_1_s"] = t.rate_max;
  if (t.rate_filter > 0.0)
    j["rate_filter_s"] = t.rate_filter;
  if (t.rate_mean_tension)
    j["rate_mean_tension"] = true;
  if (t.rate_current)
    j["rate_current"] = true;
  if (!t.rate_cohesion)
    j["rate_cohesion"] = false;
  if (t.contact_shear_limit > 0.0)
    j["contact_shear_limit_pa"] = t.contact_shear_limit;
  if (t.rolling_friction > 0.0)
    j["rolling_friction"] = t.rolling_friction;
  if (t.crack_closure > 0.0)
    j["crack_closure"] = t.crack_closure;
  if (t.compaction.on())
  {
    j["compaction_onset"] = t.compaction.onset;
    j["compaction_stiffness"] = t.compaction.stiffness;
    j["compaction_lock"] = t.compaction.lock;
    if (t.compaction.pressure > 0.0)
      j["compaction_pressure_pa"] = t.compaction.pressure;
  }
  if (m.steel)
    j["steel"] = {{"youngs_modulus_pa", m.steel->youngs_modulus}, {"density_kg_m3", m.steel->density},
                  {"yield_pa", m.steel->yield}, {"hardening_pa", m.steel->hardening},
                  {"rupture_strain", m.steel->rupture_strain}};
  if (m.bond)
    j["bond"] = {{"tau_max_pa", m.bond->tau_max}, {"s0_m", m.bond->s0}, {"s1_m", m.bond->s1}, {"s2_m", m.bond->s2},
                 {"s3_m", m.bond->s3}, {"alpha", m.bond->alpha}, {"tau_f_ratio", m.bond->tau_f_ratio},
                 {"radial_stiffness_pa_m", m.bond->radial_stiffness}, {"opening_pa", m.bond->opening},
                 {"opening_gap_m", m.bond->opening_gap}};
  j["lambda"] = m.lambda;
  j["macroscopic"] = m.macroscopic.is_null() ? nlohmann::json::object() : m.macroscopic;
  check_macroscopic(j["macroscopic"], file); // a file the programs would refuse is not written
  j["calibration"] = m.calibration.is_null() ? nlohmann::json::object() : m.calibration;
  if (file.has_parent_path())
    std::filesystem::create_directories(file.parent_path());
  std::ofstream out(file);
  if (!out)
    throw std::runtime_error("cannot write material file '" + file.string() + "'");
  out << j.dump(2) << "\n";
  out.flush();
  if (!out)
    throw std::runtime_error("writing material file '" + file.string() + "' failed (disk full?)");
}

} // namespace dembridge::dem
