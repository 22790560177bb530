#pragma once
// Writes one HDF5 dataset (the output series' helper; internal to dem).
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
} // namespace dembridge::dem::impl
