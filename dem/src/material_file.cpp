#include "dembridge/dem/material_file.h"

#include <fstream>
#include <stdexcept>

namespace dembridge::dem
{

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
  if (j.value("format", std::string()) != "dembridge-material-1")
    throw std::runtime_error("material file '" + file.string()
                             + "': expected \"format\": \"dembridge-material-1\"");
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
  // optional: compaction (absent: none)
  if (j.contains("compaction_onset"))
    t.compaction = {get("compaction_onset"), get("compaction_stiffness"), get("compaction_lock")};
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
  j["format"] = "dembridge-material-1";
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
  if (t.compaction.on())
  {
    j["compaction_onset"] = t.compaction.onset;
    j["compaction_stiffness"] = t.compaction.stiffness;
    j["compaction_lock"] = t.compaction.lock;
  }
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
