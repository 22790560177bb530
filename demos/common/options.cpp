#include "options.h"

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <unistd.h>

namespace dembridge::demo
{
namespace fs = std::filesystem;

Allowed Allowed::positive(double hi) { return {0.0, hi, true, false, {}, {}}; }
Allowed Allowed::non_negative(double hi) { return {0.0, hi, false, false, {}, {}}; }
Allowed Allowed::closed(double lo, double hi) { return {lo, hi, false, false, {}, {}}; }
Allowed Allowed::above(double lo, double hi) { return {lo, hi, true, false, {}, {}}; }
Allowed Allowed::open(double lo, double hi) { return {lo, hi, true, true, {}, {}}; }

Allowed Allowed::or_value(double value, std::string what) const
{
  Allowed a = *this;
  a.special = value;
  a.meaning = std::move(what);
  return a;
}

bool Allowed::contains(double v) const
{
  if (special && v == *special)
    return true;
  const bool above_lo = lo_open ? v > lo : v >= lo;
  const bool below_hi = hi_open ? v < hi : v <= hi;
  return above_lo && below_hi;
}

namespace
{
std::string number_text(double v)
{
  if (std::isinf(v))
    return v > 0 ? "inf" : "-inf";
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

/// Strict reading of a whole string as a finite number; the problem, or "".
std::string read_number(const std::string& s, double& v)
{
  if (s.empty())
    return "no value given";
  const char* begin = s.c_str();
  char* end = nullptr;
  errno = 0;
  v = std::strtod(begin, &end);
  if (end == begin || *end != '\0')
    return "'" + s + "' is not a number";
  if (!std::isfinite(v) || errno == ERANGE)
    return "'" + s + "' is not a finite number";
  return "";
}

CLI::Validator number_check(const Allowed& a, bool integer)
{
  return CLI::Validator(
      [a, integer](std::string& s) -> std::string
      {
        double v = 0.0;
        std::string why = read_number(s, v);
        if (why.empty() && integer && v != std::floor(v))
          why = "'" + s + "' is not a whole number";
        if (why.empty() && !a.contains(v))
          why = s + " is out of range";
        if (!why.empty())
          return why + "; allowed: " + a.text();
        if (integer)
          s = std::to_string(static_cast<long long>(v)); // "1e3" -> "1000" for CLI11's conversion
        return "";
      },
      "", "allowed");
}

std::string with_allowed(std::string help, const Allowed& a)
{
  return help + " [allowed: " + a.text() + "]";
}

} // namespace

std::string Allowed::text() const
{
  std::string t;
  if (std::isinf(lo) && std::isinf(hi))
    t = "any finite number";
  else
    t = std::string(lo_open || std::isinf(lo) ? "(" : "[") + number_text(lo) + ", " + number_text(hi)
        + (hi_open || std::isinf(hi) ? ")" : "]");
  if (special)
    t += "; " + number_text(*special) + " = " + meaning;
  return t;
}

namespace
{
/// Any numeric option (a scalar or a list of them): the allowed set in its
/// help, each value checked (and, for integers, written in a form CLI11
/// converts: "1e3" -> "1000") when the command line is parsed.
template <typename T>
CLI::Option* add_checked(CLI::App& app, const std::string& name, T& value, std::string help,
                         const Allowed& allowed, bool integer)
{
  return app.add_option(name, value, with_allowed(std::move(help), allowed))
      ->transform(number_check(allowed, integer))
      ->capture_default_str();
}
} // namespace

CLI::Option* add_number(CLI::App& app, const std::string& name, double& value, std::string help,
                        const Allowed& allowed)
{
  return add_checked(app, name, value, std::move(help), allowed, false);
}

CLI::Option* add_integer(CLI::App& app, const std::string& name, int& value, std::string help,
                         const Allowed& allowed)
{
  return add_checked(app, name, value, std::move(help), allowed, true);
}

CLI::Option* add_integer(CLI::App& app, const std::string& name, unsigned& value, std::string help,
                         const Allowed& allowed)
{
  return add_checked(app, name, value, std::move(help), allowed, true);
}

CLI::Option* add_integers(CLI::App& app, const std::string& name, std::vector<int>& value, std::string help,
                          const Allowed& allowed)
{
  return add_checked(app, name, value, std::move(help) + ", one or more", allowed, true);
}

CLI::Option* add_integers(CLI::App& app, const std::string& name, std::vector<long>& value, std::string help,
                          const Allowed& allowed)
{
  return add_checked(app, name, value, std::move(help) + ", one or more", allowed, true);
}

CLI::Option* add_vector(CLI::App& app, const std::string& name, std::array<double, 3>& value, std::string help,
                        const Allowed& allowed)
{
  return add_checked(app, name, value, std::move(help) + ", three numbers", allowed, false);
}

CLI::Option* add_choice(CLI::App& app, const std::string& name, std::string& value, std::string help,
                        const std::string& choices)
{
  std::vector<std::string> list;
  std::istringstream in(choices);
  for (std::string w; in >> w;)
    if (w != "|")
      list.push_back(w);
  auto check = [list, choices](std::string& s) -> std::string
  {
    for (const auto& c : list)
      if (s == c)
        return "";
    return "'" + s + "' is not one of the choices; allowed: " + choices;
  };
  return app.add_option(name, value, help + " [allowed: " + choices + "]")
      ->check(CLI::Validator(check, "", "choice"))
      ->capture_default_str();
}

CLI::Option* add_input_file(CLI::App& app, const std::string& name, std::string& value, std::string help)
{
  auto check = [](std::string& s) -> std::string
  {
    if (s.empty())
      return "no file given";
    std::error_code ec;
    const fs::path p(s);
    if (!fs::exists(p, ec))
      return "file '" + s + "' does not exist";
    if (fs::is_directory(p, ec))
      return "'" + s + "' is a folder, not a file";
    if (!fs::is_regular_file(p, ec))
      return "'" + s + "' is not a regular file";
    if (fs::file_size(p, ec) == 0)
      return "file '" + s + "' is empty";
    if (!std::ifstream(p))
      return "file '" + s + "' cannot be read";
    return "";
  };
  return app.add_option(name, value, help + " [input file]")->check(CLI::Validator(check, "", "input file"));
}

CLI::Option* add_program(CLI::App& app, const std::string& name, std::string& value, std::string help)
{
  auto check = [](std::string& s) -> std::string
  {
    if (s.empty())
      return "no program given";
    if (s.find('/') != std::string::npos)
      return ::access(s.c_str(), X_OK) == 0 && !fs::is_directory(s) ? "" : "'" + s + "' is not an executable file";
    const char* path = std::getenv("PATH");
    std::istringstream dirs(path ? path : "");
    for (std::string d; std::getline(dirs, d, ':');)
      if (!d.empty() && ::access((fs::path(d) / s).c_str(), X_OK) == 0)
        return "";
    return "no program '" + s + "' on PATH";
  };
  return app.add_option(name, value, help + " [program]")->check(CLI::Validator(check, "", "program"))
      ->capture_default_str();
}

CLI::Option* add_output_dir(CLI::App& app, const std::string& name, std::string& value, std::string help)
{
  auto check = [](std::string& s) -> std::string
  {
    if (s.empty())
      return ""; // no output
    std::error_code ec;
    const fs::path p(s);
    if (fs::exists(p, ec) && !fs::is_directory(p, ec))
      return "'" + s + "' exists and is not a folder";
    fs::create_directories(p, ec);
    if (ec)
      return "cannot create the folder '" + s + "': " + ec.message();
    const fs::path probe = p / (".dembridge_write_check_" + std::to_string(::getpid()));
    {
      std::ofstream f(probe);
      if (!f || !(f << "x") || !f.flush())
        return "the folder '" + s + "' is not writable";
    }
    fs::remove(probe, ec);
    return "";
  };
  return app.add_option(name, value, help + " [output folder]")->check(CLI::Validator(check, "", "output folder"));
}

CLI::Option* add_output_file(CLI::App& app, const std::string& name, std::string& value, std::string help)
{
  auto check = [](std::string& s) -> std::string
  {
    if (s.empty())
      return "";
    std::error_code ec;
    const fs::path p(s);
    if (fs::is_directory(p, ec))
      return "'" + s + "' is a folder, not a file";
    if (p.has_parent_path())
    {
      fs::create_directories(p.parent_path(), ec);
      if (ec)
        return "cannot create the folder of '" + s + "': " + ec.message();
    }
    const bool existed = fs::exists(p, ec);
    {
      std::ofstream f(p, std::ios::app); // not truncated: the run writes it at the end
      if (!f)
        return "cannot write the file '" + s + "': " + std::strerror(errno);
    }
    if (!existed)
      fs::remove(p, ec);
    return "";
  };
  return app.add_option(name, value, help + " [output file]")->check(CLI::Validator(check, "", "output file"));
}

int parse_options(CLI::App& app, int argc, char** argv)
{
  try
  {
    app.parse(argc, argv);
  }
  catch (const CLI::ParseError& e)
  {
    if (e.get_exit_code() == 0) // --help
      return app.exit(e);
    std::cerr << "error: " << e.what() << std::endl;
    return 2;
  }
  return -1;
}

} // namespace dembridge::demo
