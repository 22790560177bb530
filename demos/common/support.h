#pragma once
/// @file support.h
/// Small helpers shared by the demos and benchmarks: guarded main with
/// PETSc/MPI start-up, JSON summaries, echo of resolved options, signal
/// analysis of time histories.

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace CLI
{
class App;
}

namespace dembridge::demo
{


/// What a program starts before its body and stops after it: PETSc (and
/// MPI) for the programs with finite elements (fe_runtime.h), nothing for
/// those of discrete elements alone, which neither link DOLFINx nor start
/// MPI.
struct Runtime
{
  std::function<void(int&, char**&)> start; ///< empty: nothing
  std::function<void()> finish;             ///< empty: nothing
};

/// Starts `runtime`, installs the SIGINT and SIGTERM handlers
/// (stop_requested), runs `body`, prints any exception as "error: ..." on
/// stderr and returns a non-zero exit code for it: 1 for an error, 128 +
/// the signal's number (130, 143) for an interrupted run, whose summary, if
/// `summary` names one, is written with "completed": false and the time
/// reached. Warns when OMP_NUM_THREADS asks for more threads than cores.
int run_guarded(int argc, char** argv, const std::function<void()>& body,
                const std::filesystem::path& summary = {}, const Runtime& runtime = {});

/// True once SIGINT or SIGTERM arrived: a run stops at the end of the step
/// it is in (a second signal ends the process at once).
bool stop_requested();

/// Thrown by check_stop: the run stopped at its end of step at `time`.
struct Interrupted : std::runtime_error
{
  Interrupted(double t, int sig);
  double time; ///< physical time reached [s]
  int signal;  ///< SIGINT or SIGTERM
};

/// Runs `f`; a std::runtime_error it throws (but Interrupted) is thrown
/// again as a std::runtime_error "context: what" (a library's message given the
/// user's option or key that caused it).
template <class F>
auto with_context(const std::string& context, F&& f) -> decltype(f())
{
  try
  {
    return f();
  }
  catch (const Interrupted&)
  {
    throw; // a stop, not an error of the input
  }
  catch (const std::runtime_error& e)
  {
    throw std::runtime_error(context + ": " + e.what());
  }
}

/// Called at the end of every step of a time loop, with the time reached
/// [s]: @throws Interrupted if a stop was requested. Files close on the way
/// out (their writers' destructors), so what was written stays readable.
void check_stop(double t_reached);

/// Records that a checkpoint was written to `file`: an interrupted run's
/// summary and message then name it.
void note_checkpoint(const std::filesystem::path& file);

/// Writes a run's summary with "completed": true.
void write_summary(const std::filesystem::path& file, nlohmann::json j);

/// Writes `text` to `file` (its folder made). @throws naming the file if a
/// write fails (a full disk).
void write_text(const std::filesystem::path& file, const std::string& text);
/// Writes `j` as indented JSON to `file` (write_text).
void write_json(const std::filesystem::path& file, const nlohmann::json& j);

/// Prints every option of `app` with its resolved value (the run's header):
/// the value given, else the value the option's variable holds now.
void echo_options(CLI::App& app);

/// First frequency [Hz] of a near-harmonic signal s(t) from its crossings of
/// the mid-level (max + min) / 2, linearly interpolated, averaged over all
/// complete half periods. @throws std::runtime_error with fewer than three
/// crossings (record too short).
double crossing_frequency(std::span<const double> t, std::span<const double> s);

/// Half the peak-to-peak of s [same unit as s].
double amplitude(std::span<const double> s);

/// Wall-clock seconds since construction.
/// The process's peak resident memory so far [MiB] (getrusage's ru_maxrss).
double peak_memory_mb();

class Stopwatch
{
public:
  Stopwatch();
  double seconds() const;

private:
  double _t0;
};

/// A file shipped with dembridge: share/dembridge/`installed` under the
/// prefix this executable runs from, when it is there (an installed
/// program), else `source`, the source tree's copy (a program of the build).
std::string shipped_file(const std::string& installed, const std::string& source);

/// Runs a program with these arguments (args[0] is looked up on PATH), no
/// shell involved, and waits for it. Returns its exit code, or -1 if it could
/// not be started or did not exit normally.
int run_program(const std::vector<std::string>& args);

/// Runs the shipped plot script scripts/`script` (shipped_file) on the
/// folder `dir` with `python`, and waits for it. On failure it warns on
/// stderr that the plot was not made and that `kept` (the data) are written;
/// a plot is never worth failing the run for. Returns true if it succeeded.
bool run_plot_script(const std::string& script, const std::string& dir, const std::string& kept,
                     const std::string& python = "/usr/bin/python3");

/// Resident memory high-water mark of this process [bytes] (Linux).
long peak_rss_bytes();

} // namespace dembridge::demo
