#pragma once
/// @file support.h
/// Small helpers shared by the demos and benchmarks: guarded main with
/// PETSc/MPI start-up, JSON summaries, echo of resolved options, signal
/// analysis of time histories.

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <span>
#include <string>

namespace CLI
{
class App;
}

namespace dembridge::demo
{

/// Initialises PETSc (and MPI), runs `body`, prints any exception as
/// "error: ..." on stderr and returns a non-zero exit code for it.
int run_guarded(int argc, char** argv, const std::function<void()>& body);

/// Writes `j` as indented JSON to `file` (creating its folder).
void write_json(const std::filesystem::path& file, const nlohmann::json& j);

/// Prints every option of `app` with its resolved value (the run's header).
void echo_options(const CLI::App& app);

/// First frequency [Hz] of a near-harmonic signal s(t) from its crossings of
/// the mid-level (max + min) / 2, linearly interpolated, averaged over all
/// complete half periods. @throws std::runtime_error with fewer than three
/// crossings (record too short).
double crossing_frequency(std::span<const double> t, std::span<const double> s);

/// Half the peak-to-peak of s [same unit as s].
double amplitude(std::span<const double> s);

/// Wall-clock seconds since construction.
class Stopwatch
{
public:
  Stopwatch();
  double seconds() const;

private:
  double _t0;
};

/// Resident memory high-water mark of this process [bytes] (Linux).
long peak_rss_bytes();

} // namespace dembridge::demo
