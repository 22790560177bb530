#include "dembridge/dem/material_file.h"

#include <fstream>
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

MaterialFile read_material(const std::filesystem::path& file)
{
  std::ifstream in(file);
  if (!in)
    throw std::runtime_error("cannot open material file '" + file.string() + "'");
  nlohmann::json j;
  try
  {
    in >> j;
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("material file '" + file.string() + "' is not valid JSON: " + e.what());
  }
  auto get = [&](const char* key) -> double
  {
    if (!j.contains(key) || !j[key].is_number())
      throw std::runtime_error("material file '" + file.string() + "': missing or non-numeric key '"
                               + key + "'");
    return j[key].get<double>();
  };
  auto get_bool = [&](const char* key) -> bool
  {
    if (!j[key].is_boolean())
      throw std::runtime_error("material file '" + file.string() + "': key '" + key + "' must be true or false");
    return j[key].get<bool>();
  };
  const std::string format = j.value("format", std::string());
  if (format != "dembridge-material-1" && format != "dembridge-material-2")
    throw std::runtime_error("material file '" + file.string() + "': \"format\": \"" + format
                             + "\": expected \"dembridge-material-2\" (or -1, without steel and bond)");
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
  m.lambda = j.value("lambda", 0.0);
  m.macroscopic = j.value("macroscopic", nlohmann::json::object());
  m.calibration = j.value("calibration", nlohmann::json::object());
  try
  {
    t.validate();
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("material file '" + file.string() + "': " + e.what());
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
  j["macroscopic"] = m.macroscopic;
  j["calibration"] = m.calibration;
  if (file.has_parent_path())
    std::filesystem::create_directories(file.parent_path());
  std::ofstream out(file);
  if (!out)
    throw std::runtime_error("cannot write material file '" + file.string() + "'");
  out << j.dump(2) << "\n";
}

} // namespace dembridge::dem
