#include "support.h"

#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <thread>
#include <cerrno>
#include <cstring>
#include <chrono>
#include <fstream>
#include <iostream>
#include <spawn.h>
#include <stdexcept>
#include <sys/wait.h>

extern char** environ;

namespace dembridge::demo
{

namespace
{
volatile std::sig_atomic_t stop_signal = 0;
std::filesystem::path checkpoint_file; // the last checkpoint written

extern "C" void on_stop_signal(int sig)
{
  stop_signal = sig;
  std::signal(sig, SIG_DFL); // a second one ends the process at once
}

void warn_threads()
{
  const char* env = std::getenv("OMP_NUM_THREADS");
  const unsigned cores = std::thread::hardware_concurrency();
  if (!env || cores == 0)
    return;
  char* end = nullptr;
  const long n = std::strtol(env, &end, 10);
  if (end != env && n > static_cast<long>(cores))
    std::cerr << "warning: OMP_NUM_THREADS = " << n << " asks for more threads than the " << cores
              << " cores of this machine: each step will run slower than on " << cores << " threads"
              << std::endl;
}
} // namespace

bool stop_requested() { return stop_signal != 0; }

void note_checkpoint(const std::filesystem::path& file) { checkpoint_file = file; }

Interrupted::Interrupted(double t, int sig)
    : std::runtime_error("interrupted by " + std::string(sig == SIGTERM ? "SIGTERM" : "SIGINT") + " at t = "
                         + std::to_string(t) + " s"),
      time(t), signal(sig)
{
}

void check_stop(double t_reached)
{
  if (stop_signal != 0)
    throw Interrupted(t_reached, stop_signal);
}

int run_guarded(int argc, char** argv, const std::function<void()>& body, const std::filesystem::path& summary,
                const Runtime& runtime)
{
  if (runtime.start)
    runtime.start(argc, argv);
  // after the runtime (PETSc installs handlers of its own)
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  warn_threads();
  int rc = 0;
  try
  {
    body();
  }
  catch (const Interrupted& e)
  {
    std::cerr << "error: " << e.what() << ": stopped at the end of that step; the output files hold the run up "
                 "to there" << std::endl;
    if (!checkpoint_file.empty())
      std::cerr << "checkpoint: " << checkpoint_file.string() << " (continue with --restart "
                << checkpoint_file.string() << ")" << std::endl;
    rc = 128 + e.signal;
    if (!summary.empty())
      try
      {
        nlohmann::json j{{"completed", false},
                         {"time_reached_s", e.time},
                         {"signal", e.signal == SIGTERM ? "SIGTERM" : "SIGINT"}};
        if (!checkpoint_file.empty())
          j["checkpoint"] = checkpoint_file.string();
        write_json(summary, j);
      }
      catch (const std::exception& w)
      {
        std::cerr << "error: " << w.what() << std::endl;
      }
  }
  catch (const std::exception& e)
  {
    std::cerr << "error: " << e.what() << std::endl;
    rc = 1;
  }
  if (runtime.finish)
    runtime.finish();
  return rc;
}

void write_summary(const std::filesystem::path& file, nlohmann::json j)
{
  j["completed"] = true;
  write_json(file, j);
}

void write_text(const std::filesystem::path& file, const std::string& text)
{
  if (file.has_parent_path())
    std::filesystem::create_directories(file.parent_path());
  std::ofstream out(file);
  if (!out)
    throw std::runtime_error("cannot write '" + file.string() + "': " + std::strerror(errno));
  out << text;
  out.flush();
  if (!out)
    throw std::runtime_error("writing '" + file.string() + "' failed (disk full?)");
}

void write_json(const std::filesystem::path& file, const nlohmann::json& j)
{
  write_text(file, j.dump(2) + "\n");
}

void echo_options(CLI::App& app)
{
  std::cout << "# " << app.get_name() << ": resolved parameters\n";
  for (CLI::Option* opt : app.get_options())
  {
    if (opt->get_name() == "--help" || opt->get_name().empty())
      continue;
    std::string val;
    for (const auto& r : opt->results())
      val += (val.empty() ? "" : " ") + r;
    if (opt->results().empty())
      val = opt->capture_default_str()->get_default_str(); // the value now (a file may have set it)
    std::cout << "#   " << opt->get_name() << " = " << val << "\n";
  }
  std::cout << std::flush;
}

double crossing_frequency(std::span<const double> t, std::span<const double> s)
{
  if (t.size() != s.size() || s.size() < 3)
    throw std::runtime_error("crossing_frequency: need equal-length records of >= 3 samples");
  const auto [mn, mx] = std::minmax_element(s.begin(), s.end());
  const double mid = 0.5 * (*mn + *mx);
  std::vector<double> times;
  for (std::size_t i = 1; i < s.size(); ++i)
  {
    const double a = s[i - 1] - mid, b = s[i] - mid;
    if ((a < 0.0 && b >= 0.0) || (a > 0.0 && b <= 0.0))
      times.push_back(t[i - 1] + (t[i] - t[i - 1]) * a / (a - b));
  }
  if (times.size() < 3)
    throw std::runtime_error("the record holds " + std::to_string(times.size())
                             + " crossings; run longer to measure a frequency");
  const double half_period = (times.back() - times.front()) / (times.size() - 1);
  return 1.0 / (2.0 * half_period);
}

double amplitude(std::span<const double> s)
{
  if (s.empty())
    return 0.0;
  const auto [mn, mx] = std::minmax_element(s.begin(), s.end());
  return 0.5 * (*mx - *mn);
}

static double now()
{
  return std::chrono::duration<double>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

double peak_memory_mb()
{
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0; // Linux: KiB
}

Stopwatch::Stopwatch() : _t0(now()) {}
double Stopwatch::seconds() const { return now() - _t0; }

std::string shipped_file(const std::string& installed, const std::string& source)
{
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec)
  {
    const auto p = exe.parent_path().parent_path() / "share" / "dembridge" / installed;
    if (std::filesystem::exists(p, ec))
      return p.string();
  }
  return source;
}

bool run_plot_script(const std::string& script, const std::string& dir, const std::string& kept,
                     const std::string& python)
{
  const std::string path = shipped_file("scripts/" + script, DEMBRIDGE_SOURCE_DIR "/scripts/" + script);
  if (run_program({python, path, dir}) == 0)
    return true;
  std::cerr << "warning: the plot was not made (" << python << " scripts/" << script << " failed); " << kept
            << " written\n";
  return false;
}

int run_program(const std::vector<std::string>& args)
{
  if (args.empty())
    return -1;
  std::vector<char*> argv;
  for (const auto& a : args)
    argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawnp(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0)
    return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) != pid || !WIFEXITED(status))
    return -1;
  return WEXITSTATUS(status);
}

long peak_rss_bytes()
{
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0)
      return std::stol(line.substr(6)) * 1024;
  return 0;
}

} // namespace dembridge::demo
