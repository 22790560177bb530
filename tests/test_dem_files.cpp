// Material and packing files are checked as files: every bad key or value
// named with the file, no library message, no NaN; writes that fail (a full
// disk: /dev/full) throw naming the file.
#include "dembridge/dem/material_file.h"
#include "dembridge/dem/packing.h"

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

using namespace dembridge::dem;
using Catch::Contains;

namespace
{
std::filesystem::path shipped_material()
{
  return std::filesystem::path(DEMBRIDGE_SOURCE_DIR) / "demos/calibrate/materials/default.json";
}

/// The shipped default material with `edit` applied, written to a file of
/// the test's temporary folder.
std::filesystem::path edited(const std::string& name, const std::function<void(nlohmann::json&)>& edit)
{
  nlohmann::json j;
  std::ifstream(shipped_material()) >> j;
  edit(j);
  const auto dir = std::filesystem::temp_directory_path() / "dembridge_test_files";
  std::filesystem::create_directories(dir);
  const auto file = dir / name;
  std::ofstream(file) << j.dump(2);
  return file;
}

/// The message of read_material(file); "" if it did not throw.
std::string error_of(const std::filesystem::path& file)
{
  try
  {
    read_material(file);
  }
  catch (const std::exception& e)
  {
    return e.what();
  }
  return "";
}
} // namespace

TEST_CASE("material file: bad files and values are named with the file", "[files]")
{
  REQUIRE(error_of(shipped_material()).empty());

  const auto array = edited("array.json", [](nlohmann::json& j) { j = nlohmann::json::array({1, 2}); });
  std::string e = error_of(array);
  CHECK_THAT(e, Contains("array.json") && Contains("one JSON object"));
  CHECK_THAT(e, !Contains("json.exception"));

  e = error_of(edited("negative_e.json", [](nlohmann::json& j) { j["youngs_modulus_pa"] = -3e10; }));
  CHECK_THAT(e, Contains("negative_e.json") && Contains("Young's modulus") && Contains("> 0 Pa"));
  CHECK_THAT(e, !Contains("nan"));

  e = error_of(edited("macro_nu.json", [](nlohmann::json& j) { j["macroscopic"]["poisson_ratio"] = 0.7; }));
  CHECK_THAT(e, Contains("macro_nu.json") && Contains("macroscopic.poisson_ratio") && Contains("(-1, 0.5)"));

  e = error_of(edited("macro_e.json", [](nlohmann::json& j) { j["macroscopic"]["youngs_modulus_pa"] = -1.0; }));
  CHECK_THAT(e, Contains("macroscopic.youngs_modulus_pa") && Contains("> 0 Pa"));

  e = error_of(edited("macro_text.json", [](nlohmann::json& j) { j["macroscopic"]["tensile_strength_pa"] = "3 MPa"; }));
  CHECK_THAT(e, Contains("macroscopic.tensile_strength_pa") && Contains("must be a number"));

  e = error_of(edited("macro_array.json", [](nlohmann::json& j) { j["macroscopic"] = nlohmann::json::array(); }));
  CHECK_THAT(e, Contains("\"macroscopic\" must be an object"));

  e = error_of(edited("unknown.json", [](nlohmann::json& j) { j["youngs_modulus"] = 3e10; }));
  CHECK_THAT(e, Contains("unknown.json") && Contains("unknown key 'youngs_modulus'"));

  e = error_of(edited("lambda.json", [](nlohmann::json& j) { j["lambda"] = "1.4"; }));
  CHECK_THAT(e, Contains("'lambda'") && !Contains("json.exception"));

  e = error_of(edited("format.json", [](nlohmann::json& j) { j["format"] = 2; }));
  CHECK_THAT(e, Contains("\"format\": 2") && !Contains("json.exception"));

  e = error_of(edited("links.json", [](nlohmann::json& j) { j["links_per_sphere"] = -12; }));
  CHECK_THAT(e, Contains("links_per_sphere") && Contains("(0, 100]"));

  const auto dir = std::filesystem::temp_directory_path() / "dembridge_test_files";
  std::ofstream(dir / "broken.json") << "{\"format\": ";
  e = error_of(dir / "broken.json");
  CHECK_THAT(e, Contains("broken.json") && Contains("not valid JSON") && !Contains("json.exception"));
}

TEST_CASE("writes that fail name the file", "[files]")
{
  REQUIRE(std::filesystem::exists("/dev/full")); // Linux's always-full device
  Packing p;
  p.x = {0.0, 0.0, 0.0};
  p.r = {1e-3};
  CHECK_THROWS_WITH(write_packing("/dev/full", p), Contains("/dev/full") && Contains("failed"));
  CHECK_THROWS_WITH(write_material("/dev/full", read_material(shipped_material())),
                    Contains("/dev/full") && Contains("failed"));
}

TEST_CASE("a packing file is checked against its region", "[files]")
{
  const Region box = box_region({0.0, 0.0, 0.0}, {0.05, 0.05, 0.05});
  PackingOptions o;
  o.mean_radius = 2.5e-3;
  const Packing p = generate_packing(box, o);
  // a generated packing keeps its spheres inside, to round-off: far from
  // the half radius the check allows
  const auto [out, worst] = largest_protrusion(box, p);
  CHECK(out < 0.01);
  CHECK_NOTHROW(check_packing_fits(box, p, "file"));

  Packing big = p;
  big.r[7] = 1.0; // a radius out of scale: 1 m in a 5 cm box
  CHECK_THROWS_WITH(check_packing_fits(box, big, "--packing big.txt"),
                    Contains("--packing big.txt") && Contains("sphere 8") && Contains("radius 1 m")
                        && Contains("out of the region"));

  Packing moved = p;
  moved.x[3 * 3] += 1.0; // centred outside
  CHECK_THROWS_WITH(check_packing_fits(box, moved, "file"), Contains("sphere 4") && Contains("centred outside"));
}
