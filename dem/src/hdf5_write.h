#pragma once
// Helpers of the output series (internal to dem): one HDF5 dataset, and a
// text file replaced whole.
#include <filesystem>
#include <fstream>
#include <hdf5.h>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <vector>

namespace dembridge::dem::impl
{
/// Creates dataset `name` (groups on the way created) of the given shape
/// and writes `data` into it. @throws std::runtime_error if it cannot.
inline void write_dataset(hid_t file, const std::string& name, const void* data, hid_t type,
                          std::initializer_list<hsize_t> dims)
{
  std::vector<hsize_t> d(dims);
  hid_t space = H5Screate_simple(static_cast<int>(d.size()), d.data(), nullptr);
  hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(lcpl, 1);
  hid_t set = H5Dcreate2(file, name.c_str(), type, space, lcpl, H5P_DEFAULT, H5P_DEFAULT);
  if (set < 0)
    throw std::runtime_error("HDF5: cannot create dataset " + name);
  if (d[0] > 0)
    H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
  H5Dclose(set);
  H5Pclose(lcpl);
  H5Sclose(space);
}
/// Writes `text` to `file` through FILE.tmp and a rename, so that a reader
/// never sees a half-written file (an XDMF rewritten at every frame).
inline void replace_text_file(const std::filesystem::path& file, const std::string& text)
{
  const auto tmp = file.string() + ".tmp";
  {
    std::ofstream out(tmp);
    out << text;
    if (!out.flush())
      throw std::runtime_error("cannot write '" + tmp + "' (disk full?)");
  }
  std::filesystem::rename(tmp, file);
}
} // namespace dembridge::dem::impl
