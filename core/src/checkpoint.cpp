// Checkpoint files on the HDF5 C API (checkpoint.h).
#include "dembridge/core/checkpoint.h"

#include <hdf5.h>
#include <stdexcept>
#include <system_error>
#include <utility>

namespace dembridge::checkpoint
{
namespace
{
constexpr const char* format_name = "dembridge checkpoint";

template <typename T> hid_t native();
template <> hid_t native<double>() { return H5T_NATIVE_DOUBLE; }
template <> hid_t native<std::int32_t>() { return H5T_NATIVE_INT32; }
template <> hid_t native<std::int64_t>() { return H5T_NATIVE_INT64; }
template <> hid_t native<std::uint8_t>() { return H5T_NATIVE_UINT8; }

/// HDF5 prints its own error stack on failures; the messages thrown here say
/// what failed, so the stack is silenced while a checkpoint is handled.
struct QuietHdf5
{
  H5E_auto2_t func = nullptr;
  void* data = nullptr;
  QuietHdf5()
  {
    H5Eget_auto2(H5E_DEFAULT, &func, &data);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, func, data); }
};
} // namespace

Group::Group(std::int64_t id, std::string path, std::string file, bool writing)
    : _id(id), _path(std::move(path)), _file(std::move(file)), _writing(writing)
{
}

Group::Group(Group&& o) noexcept
    : _id(std::exchange(o._id, -1)), _path(std::move(o._path)), _file(std::move(o._file)),
      _writing(o._writing)
{
}

Group::~Group()
{
  if (_id >= 0)
    H5Gclose(_id);
}

void Group::fail(const std::string& name, const std::string& what) const
{
  throw std::runtime_error("checkpoint " + _file + ": " + (_path == "/" ? "/" : _path + "/") + name
                           + ": " + what);
}

Group Group::group(const std::string& name) const
{
  QuietHdf5 quiet;
  hid_t g = _writing ? H5Gcreate2(_id, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT)
                     : H5Gopen2(_id, name.c_str(), H5P_DEFAULT);
  if (g < 0)
    fail(name, _writing ? "cannot create the group" : "not in the file (written by another set-up?)");
  return Group(g, (_path == "/" ? "/" : _path + "/") + name, _file, _writing);
}

bool Group::has(const std::string& name) const
{
  QuietHdf5 quiet;
  return H5Lexists(_id, name.c_str(), H5P_DEFAULT) > 0;
}

template <typename T> void Group::write_array(const std::string& name, std::span<const T> v) const
{
  if (!_writing)
    fail(name, "the file is open for reading");
  QuietHdf5 quiet;
  const hsize_t n = v.size();
  hid_t space = H5Screate_simple(1, &n, nullptr);
  hid_t set = H5Dcreate2(_id, name.c_str(), native<T>(), space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  const bool ok = set >= 0 && (n == 0 || H5Dwrite(set, native<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0);
  if (set >= 0)
    H5Dclose(set);
  H5Sclose(space);
  if (!ok)
    fail(name, "cannot write (disk full?)");
}

template <typename T> void Group::read_array(const std::string& name, std::vector<T>& v) const
{
  QuietHdf5 quiet;
  hid_t set = H5Dopen2(_id, name.c_str(), H5P_DEFAULT);
  if (set < 0)
    fail(name, "not in the file (written by another set-up?)");
  hid_t space = H5Dget_space(set);
  const int rank = H5Sget_simple_extent_ndims(space);
  hsize_t n = 0;
  if (rank == 1)
    H5Sget_simple_extent_dims(space, &n, nullptr);
  H5Sclose(space);
  hid_t type = H5Dget_type(set);
  const bool same = H5Tequal(type, native<T>()) > 0;
  H5Tclose(type);
  if (rank != 1 || !same)
  {
    H5Dclose(set);
    fail(name, "not an array of the expected type");
  }
  v.resize(n);
  const bool ok = n == 0 || H5Dread(set, native<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0;
  H5Dclose(set);
  if (!ok)
    fail(name, "cannot be read (file damaged?)");
}

void Group::write(const std::string& name, std::span<const double> v) const { write_array(name, v); }
void Group::write(const std::string& name, std::span<const std::int32_t> v) const { write_array(name, v); }
void Group::write(const std::string& name, std::span<const std::int64_t> v) const { write_array(name, v); }
void Group::write(const std::string& name, std::span<const std::uint8_t> v) const { write_array(name, v); }
void Group::write(const std::string& name, const std::string& s) const
{
  write(name, std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()));
}

void Group::read(const std::string& name, std::vector<double>& v) const { read_array(name, v); }
void Group::read(const std::string& name, std::vector<std::int32_t>& v) const { read_array(name, v); }
void Group::read(const std::string& name, std::vector<std::int64_t>& v) const { read_array(name, v); }
void Group::read(const std::string& name, std::vector<std::uint8_t>& v) const { read_array(name, v); }

void Group::read_exact(const std::string& name, std::span<double> v) const
{
  std::vector<double> r;
  read(name, r);
  if (r.size() != v.size())
    fail(name, "holds " + std::to_string(r.size()) + " values, this run has " + std::to_string(v.size())
                   + " (the checkpoint is of another set-up)");
  std::copy(r.begin(), r.end(), v.begin());
}

double Group::read_double(const std::string& name) const
{
  std::vector<double> r;
  read(name, r);
  if (r.size() != 1)
    fail(name, "not a single value");
  return r[0];
}

std::int64_t Group::read_int(const std::string& name) const
{
  std::vector<std::int64_t> r;
  read(name, r);
  if (r.size() != 1)
    fail(name, "not a single value");
  return r[0];
}

std::string Group::read_string(const std::string& name) const
{
  std::vector<std::uint8_t> r;
  read(name, r);
  return std::string(r.begin(), r.end());
}

// ---- File ---------------------------------------------------------------------

File::File(std::int64_t id, std::filesystem::path file, bool writing)
    : _id(id), _file(std::move(file)), _writing(writing)
{
}

File::File(File&& o) noexcept
    : _id(std::exchange(o._id, -1)), _file(std::move(o._file)), _writing(o._writing)
{
}

File::~File()
{
  close();
  if (_writing && !_file.empty())
  {
    std::error_code ec;
    std::filesystem::remove(_file.string() + ".tmp", ec); // an uncommitted write
  }
}

void File::close() noexcept
{
  if (_id >= 0)
    H5Fclose(_id);
  _id = -1;
}

File File::create(const std::filesystem::path& file, const std::string& program)
{
  QuietHdf5 quiet;
  if (file.has_parent_path())
    std::filesystem::create_directories(file.parent_path());
  const std::string tmp = file.string() + ".tmp";
  hid_t id = H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (id < 0)
    throw std::runtime_error("checkpoint " + file.string() + ": cannot create '" + tmp + "'");
  File f(id, file, true);
  {
    const Group r = f.root();
    r.write("format", std::string(format_name));
    r.write_int("version", format_version);
    r.write("program", program);
  }
  return f;
}

File File::open(const std::filesystem::path& file, const std::string& program)
{
  const std::string name = file.string();
  if (!std::filesystem::is_regular_file(file))
    throw std::runtime_error("checkpoint " + name + ": no such file");
  QuietHdf5 quiet;
  hid_t id = H5Fis_hdf5(name.c_str()) > 0 ? H5Fopen(name.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT) : -1;
  if (id < 0)
    throw std::runtime_error("checkpoint " + name + ": not an HDF5 file");
  File f(id, file, false);
  const Group r = f.root();
  if (!r.has("format") || r.read_string("format") != format_name)
    throw std::runtime_error("checkpoint " + name + ": not a dembridge checkpoint");
  const std::int64_t v = r.read_int("version");
  if (v != format_version)
    throw std::runtime_error("checkpoint " + name + ": format version " + std::to_string(v)
                             + ", this build reads version " + std::to_string(format_version));
  const std::string by = r.read_string("program");
  if (by != program)
    throw std::runtime_error("checkpoint " + name + ": written by " + by + ", not by " + program);
  return f;
}

Group File::root() const
{
  hid_t g = H5Gopen2(_id, "/", H5P_DEFAULT);
  return Group(g, "/", _file.string(), _writing);
}

void File::commit()
{
  if (!_writing || _id < 0)
    throw std::runtime_error("checkpoint " + _file.string() + ": not being written");
  const bool flushed = H5Fflush(_id, H5F_SCOPE_GLOBAL) >= 0;
  const bool closed = H5Fclose(_id) >= 0;
  _id = -1;
  const std::string tmp = _file.string() + ".tmp";
  if (!flushed || !closed)
    throw std::runtime_error("checkpoint " + _file.string() + ": cannot write '" + tmp + "' (disk full?)");
  std::filesystem::rename(tmp, _file);
}

std::int64_t reopen_frames(const std::filesystem::path& h5, std::size_t frames)
{
  const std::string name = h5.string();
  QuietHdf5 quiet;
  hid_t id = std::filesystem::is_regular_file(h5) && H5Fis_hdf5(name.c_str()) > 0
                 ? H5Fopen(name.c_str(), H5F_ACC_RDWR, H5P_DEFAULT)
                 : -1;
  if (id < 0)
    throw std::runtime_error("cannot continue the output '" + name
                             + "': missing or not HDF5 (restart into the output folder of the run "
                               "that wrote the checkpoint)");
  auto frame = [](std::size_t k) { return "/frame_" + std::to_string(k); };
  if (frames > 0 && H5Lexists(id, frame(frames - 1).c_str(), H5P_DEFAULT) <= 0)
  {
    H5Fclose(id);
    throw std::runtime_error("cannot continue the output '" + name + "': it holds fewer than the "
                             + std::to_string(frames) + " frames the checkpoint recorded");
  }
  for (std::size_t k = frames; H5Lexists(id, frame(k).c_str(), H5P_DEFAULT) > 0; ++k)
    H5Ldelete(id, frame(k).c_str(), H5P_DEFAULT);
  return id;
}

} // namespace dembridge::checkpoint
