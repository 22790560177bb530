#pragma once
/// @file restart.h
/// Checkpoint and restart for the demos' time loops. A run given
/// --checkpoint-every N writes its whole state to one HDF5 file every N
/// steps and whenever it is interrupted (SIGINT, SIGTERM); --restart FILE
/// continues a run from such a file, bit for bit, appending to the output
/// files of the run that wrote it. The checkpoint records the options that
/// define the run (all but where and how often it writes); a restart with
/// another value of any of them is refused, naming the option.

#include "dembridge/core/checkpoint.h"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace CLI
{
class App;
}

namespace dembridge::demo
{

struct RestartOptions
{
  int every = 0;           ///< steps between checkpoints; 0 = only when interrupted
  std::string file;        ///< checkpoint file; "" = OUTPUT/checkpoint.h5 (none without --output)
  std::string restart;     ///< checkpoint to continue from; "" = a new run
  std::string program;     ///< the program's name (a checkpoint is read by the program that wrote it)
  nlohmann::json setup;    ///< option -> value of the options that define the run
};

/// Adds --checkpoint-every, --checkpoint and --restart to `app`.
void add_restart_options(CLI::App& app, RestartOptions& o);

/// After parsing: records in o.setup every option of `app` with its value,
/// except those that say where or how often to write (--output, --summary,
/// --checkpoint, --checkpoint-every, --restart, --help) and `ignore`.
/// Returns -1 to go on, or 2 after printing an error: checkpoints asked for
/// (--checkpoint-every) with nowhere to write them (no --output, no
/// --checkpoint).
int record_setup(CLI::App& app, RestartOptions& o, const std::vector<std::string>& ignore = {});

/// Adds what every program with a time loop writes and how it restarts:
/// --output DIR (`output_help` says what goes in it), --summary FILE and the
/// checkpoint options (add_restart_options).
void add_run_options(CLI::App& app, std::string& output_dir, const std::string& output_help, std::string& summary,
                     RestartOptions& restart);
/// parse_options, then record_setup: -1 to go on, or the exit code.
int parse_run_options(CLI::App& app, int argc, char** argv, RestartOptions& restart);

class Checkpointer
{
public:
  /// @param output_dir the run's output folder ("" = none), where the
  /// checkpoint goes unless --checkpoint names a file
  /// @throws std::runtime_error when restarting from a checkpoint of another
  ///   set-up (open_restart): construct it before the run's set-up.
  Checkpointer(const RestartOptions& o, const std::string& output_dir);
  /// True if this run writes checkpoints.
  bool enabled() const { return !_file.empty(); }
  bool restarting() const { return !_o.restart.empty(); }
  /// The checkpoint to continue from, its set-up checked against this run's.
  /// @throws std::runtime_error naming the first option that differs.
  checkpoint::File open_restart() const;
  /// Called at the end of every step: writes a checkpoint (calling `save`
  /// with its root group) every N steps and when a stop was requested, then
  /// check_stop(t) (which throws Interrupted on a stop).
  void end_of_step(std::int64_t step, double t, const std::function<void(const checkpoint::Group&)>& save);
  /// Writes a checkpoint now.
  void write(const std::function<void(const checkpoint::Group&)>& save);
  const std::filesystem::path& file() const { return _file; }
  std::size_t written() const { return _written; }

private:
  RestartOptions _o;
  std::filesystem::path _file;
  std::size_t _written = 0;
};

/// A CSV (or any text file) written as the run goes: its flushed length,
/// for a checkpoint. @throws naming the file if a write failed.
std::int64_t flushed_size(std::ofstream& out, const std::filesystem::path& file);
/// Reopens `file` to continue it after its first `bytes` bytes (those the
/// checkpoint recorded; later rows are dropped). @throws naming the file if
/// it is missing or shorter.
void reopen_text(std::ofstream& out, const std::filesystem::path& file, std::int64_t bytes);

} // namespace dembridge::demo
