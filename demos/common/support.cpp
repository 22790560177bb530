#include "support.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <fstream>
#include <iostream>
#include <dolfinx/common/log.h>
#include <petscsys.h>
#include <stdexcept>

namespace dembridge::demo
{

int run_guarded(int argc, char** argv, const std::function<void()>& body)
{
  PetscInitialize(&argc, &argv, nullptr, nullptr);
  loguru::g_stderr_verbosity = loguru::Verbosity_WARNING; // DOLFINx INFO off
  int rc = 0;
  try
  {
    body();
  }
  catch (const std::exception& e)
  {
    std::cerr << "error: " << e.what() << std::endl;
    rc = 1;
  }
  PetscFinalize();
  return rc;
}

void write_json(const std::filesystem::path& file, const nlohmann::json& j)
{
  if (file.has_parent_path())
    std::filesystem::create_directories(file.parent_path());
  std::ofstream out(file);
  if (!out)
    throw std::runtime_error("cannot write '" + file.string() + "'");
  out << j.dump(2) << "\n";
}

void echo_options(const CLI::App& app)
{
  std::cout << "# " << app.get_name() << ": resolved parameters\n";
  for (const CLI::Option* opt : app.get_options())
  {
    if (opt->get_name() == "--help" || opt->get_name().empty())
      continue;
    std::string val;
    for (const auto& r : opt->results())
      val += (val.empty() ? "" : " ") + r;
    if (opt->results().empty())
      val = opt->get_default_str();
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

Stopwatch::Stopwatch() : _t0(now()) {}
double Stopwatch::seconds() const { return now() - _t0; }

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
