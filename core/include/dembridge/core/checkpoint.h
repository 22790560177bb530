#pragma once
/// @file checkpoint.h
/// Checkpoint files: one HDF5 file holding the whole state of a run, as a
/// tree of groups that each part of the program fills with its own arrays
/// (the DEM solver "dem", the shell solver "shell", the coupling, the
/// demo's measurements "run"). Values are stored in their native binary
/// form, so a run restarted from a checkpoint continues bit for bit. A new
/// part of the state is a new group: readers ignore the groups they do not
/// ask for, and a group or array that is asked for and missing is an error
/// naming it. The file carries a format name, its version and the program
/// that wrote it. Writing goes to FILE.tmp, renamed to FILE once complete:
/// an interrupted write leaves the previous checkpoint intact.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace dembridge::checkpoint
{

/// The version of the file layout this build writes and reads.
constexpr std::int64_t format_version = 5;

/// A group of a checkpoint being written (arrays are created) or read
/// (arrays are read back). Errors name the file and the array's path.
class Group
{
public:
  Group(Group&& o) noexcept;
  Group& operator=(Group&&) = delete;
  Group(const Group&) = delete;
  ~Group();

  /// The sub-group `name`: created when writing; when reading,
  /// @throws std::runtime_error if it is not in the file.
  Group group(const std::string& name) const;
  /// True if the group holds an array or group `name`.
  bool has(const std::string& name) const;
  /// Path of this group in the file, e.g. "/dem/particles".
  const std::string& path() const { return _path; }
  bool writing() const { return _writing; }

  void write(const std::string& name, std::span<const double> v) const;
  void write(const std::string& name, std::span<const std::int32_t> v) const;
  void write(const std::string& name, std::span<const std::int64_t> v) const;
  void write(const std::string& name, std::span<const std::uint8_t> v) const;
  void write(const std::string& name, double v) const { write(name, std::span<const double>(&v, 1)); }
  void write_int(const std::string& name, std::int64_t v) const
  {
    write(name, std::span<const std::int64_t>(&v, 1));
  }
  void write(const std::string& name, const std::string& s) const;

  /// Reads an array whole (resized to the stored length).
  void read(const std::string& name, std::vector<double>& v) const;
  void read(const std::string& name, std::vector<std::int32_t>& v) const;
  void read(const std::string& name, std::vector<std::int64_t>& v) const;
  void read(const std::string& name, std::vector<std::uint8_t>& v) const;
  /// Reads an array of exactly v.size() values. @throws naming the array,
  /// the length stored and the length expected otherwise.
  void read_exact(const std::string& name, std::span<double> v) const;
  double read_double(const std::string& name) const;
  std::int64_t read_int(const std::string& name) const;
  std::string read_string(const std::string& name) const;

  /// @throws std::runtime_error "checkpoint FILE: PATH/name: what".
  [[noreturn]] void fail(const std::string& name, const std::string& what) const;

private:
  friend class File;
  Group(std::int64_t id, std::string path, std::string file, bool writing);
  template <typename T> void write_array(const std::string& name, std::span<const T> v) const;
  template <typename T> void read_array(const std::string& name, std::vector<T>& v) const;
  std::int64_t _id;
  std::string _path;
  std::string _file;
  bool _writing;
};

/// A checkpoint file, open for writing (create) or reading (open).
class File
{
public:
  /// Starts writing `file` (as FILE.tmp; commit() makes it FILE) for
  /// `program`. @throws if the folder cannot take it.
  static File create(const std::filesystem::path& file, const std::string& program);
  /// Opens `file` written by `program`. @throws naming the file if it is
  /// missing, not a checkpoint, of another format version or of another
  /// program.
  static File open(const std::filesystem::path& file, const std::string& program);
  File(File&& o) noexcept;
  File& operator=(File&&) = delete;
  File(const File&) = delete;
  /// Closes; a file being written and not committed is removed.
  ~File();

  Group root() const;
  /// Flushes and closes the file, then renames FILE.tmp to FILE.
  void commit();
  const std::filesystem::path& path() const { return _file; }

private:
  File(std::int64_t id, std::filesystem::path file, bool writing);
  void close() noexcept;
  std::int64_t _id;
  std::filesystem::path _file;
  bool _writing;
};

/// Reopens the HDF5 file of a time series written as groups /frame_0,
/// /frame_1, ... to continue it after its first `frames` frames, those a
/// checkpoint recorded (frames written after the checkpoint are deleted).
/// Returns the HDF5 file id (hid_t). @throws std::runtime_error naming the
/// file if it is missing, not HDF5 or holds fewer frames.
std::int64_t reopen_frames(const std::filesystem::path& h5, std::size_t frames);

} // namespace dembridge::checkpoint
