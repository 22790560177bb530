// The XDMF + HDF5 output is read back with the HDF5 C API: datasets, shapes,
// number of time steps, finite values, and the CSV history.
#include "cantilever.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <hdf5.h>
#include <string>

using namespace dembridge;

namespace
{
/// Number of links (datasets) in group `path`, -1 if it does not exist.
long count_children(hid_t file, const std::string& path)
{
  if (H5Lexists(file, path.c_str(), H5P_DEFAULT) <= 0)
    return -1;
  hid_t g = H5Gopen2(file, path.c_str(), H5P_DEFAULT);
  H5G_info_t info;
  H5Gget_info(g, &info);
  H5Gclose(g);
  return static_cast<long>(info.nlinks);
}

/// Shape of a 2D dataset, and whether all values are finite.
std::pair<std::array<hsize_t, 2>, bool> inspect(hid_t file, const std::string& path)
{
  hid_t d = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  hid_t s = H5Dget_space(d);
  std::array<hsize_t, 2> dims{0, 0};
  const int rank = H5Sget_simple_extent_ndims(s);
  H5Sget_simple_extent_dims(s, dims.data(), nullptr);
  std::vector<double> v(dims[0] * (rank > 1 ? dims[1] : 1));
  H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  H5Sclose(s);
  H5Dclose(d);
  bool finite = true;
  for (double x : v)
    finite = finite && std::isfinite(x);
  return {dims, finite};
}

} // namespace

TEST_CASE("cantilever output: XDMF/HDF5 fields and time steps, CSV history", "[io]")
{
  const auto dir = std::filesystem::temp_directory_path() / "dembridge_test_output";
  std::filesystem::remove_all(dir);
  demo::CantileverConfig c;
  c.quiet = true;
  c.nx = 17;
  c.ny = 5;
  c.periods = 2.0;
  c.frames = 5;
  c.output_dir = dir.string();
  const auto r = demo::run_cantilever(c);
  const long frames = r["frames_written"].get<long>();
  REQUIRE(frames >= 6);
  const std::size_t nodes = r["nodes"].get<std::size_t>();

  REQUIRE(std::filesystem::exists(dir / "cantilever.xdmf"));
  REQUIRE(std::filesystem::exists(dir / "cantilever.h5"));
  hid_t f = H5Fopen((dir / "cantilever.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(f >= 0);
  const std::vector<std::string> fields
      = {"displacement", "velocity", "rotation", "angular_velocity", "normal"};
  CHECK(count_children(f, "/") == frames + 1); // /mesh and /frame_k
  for (long k = 0; k < frames; ++k)
    for (const auto& field : fields)
    {
      INFO(field << " at frame " << k);
      const auto [dims, finite] = inspect(f, field == "normal" ? "/mesh/normal" : "/frame_" + std::to_string(k) + "/" + field);
      CHECK(dims[0] == nodes);
      CHECK(dims[1] == 3);
      CHECK(finite);
    }
  // the section's tensors per cell (FEModel::section_stresses)
  const std::vector<std::string> sections = {"stress_top", "stress_bottom", "membrane_force", "bending_moment"};
  for (long k = 0; k < frames; ++k)
    for (const auto& field : sections)
    {
      INFO(field << " at frame " << k);
      const auto [dims, finite] = inspect(f, "/frame_" + std::to_string(k) + "/" + field);
      CHECK(dims[0] > 0);
      CHECK(dims[1] == 9);
      CHECK(finite);
    }
  const auto [gdims, gfinite] = inspect(f, "/mesh/geometry");
  CHECK(gdims[0] == nodes);
  CHECK(gdims[1] == 3);
  H5Fclose(f);

  // The XDMF has one grid per time step, carrying every field, and declares
  // every float 64-bit.
  std::ifstream xdmf(dir / "cantilever.xdmf");
  std::string text((std::istreambuf_iterator<char>(xdmf)), std::istreambuf_iterator<char>());
  std::size_t times = 0;
  for (std::size_t p = text.find("<Time Value="); p != std::string::npos;
       p = text.find("<Time Value=", p + 1))
    ++times;
  CHECK(times == static_cast<std::size_t>(frames));
  std::size_t floats = 0, doubles = 0;
  for (std::size_t p = text.find("NumberType=\"Float\""); p != std::string::npos;
       p = text.find("NumberType=\"Float\"", p + 1))
  {
    ++floats;
    const std::string tag = "NumberType=\"Float\" Precision=\"8\"";
    doubles += text.compare(p, tag.size(), tag) == 0;
  }
  CHECK(floats == static_cast<std::size_t>(frames) * (1 + fields.size() + sections.size()));
  CHECK(text.find("AttributeType=\"Tensor\" Center=\"Cell\"") != std::string::npos);
  CHECK(doubles == floats);

  // CSV: header + one row per frame
  std::ifstream csv(dir / "history.csv");
  std::string line;
  std::getline(csv, line);
  CHECK(line.rfind("t_s,tip_m,kinetic_J", 0) == 0);
  long rows = 0;
  while (std::getline(csv, line))
    ++rows;
  CHECK(rows == frames);
}
