#pragma once
/// @file options.h
/// Checked command-line options for every demo and benchmark. A numeric
/// option states what it allows (a range, and optionally one value with a
/// meaning of its own, such as "0 = automatic"); the check runs when the
/// command line is parsed, before any work, and refuses anything else with
/// one line that names the option, the value given and what is allowed. The
/// allowed set is appended to the option's help as "[allowed: ...]", which
/// the test suite reads back to try values outside it (tests/bad_input.py).
/// File options are checked the same way: inputs must be readable, non-empty
/// regular files; output folders and files must be creatable and writable.

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace CLI
{
class App;
class Option;
} // namespace CLI

namespace dembridge::demo
{

/// What a numeric option allows: the interval from lo to hi (each end open
/// or closed; infinite ends are open), and optionally one value outside it
/// that means something (`special`, explained by `meaning`).
struct Allowed
{
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = true, hi_open = true;
  std::optional<double> special;
  std::string meaning;

  /// (0, hi]
  static Allowed positive(double hi);
  /// [0, hi]
  static Allowed non_negative(double hi);
  /// [lo, hi]
  static Allowed closed(double lo, double hi);
  /// (lo, hi]
  static Allowed above(double lo, double hi);
  /// (lo, hi)
  static Allowed open(double lo, double hi);
  /// The same interval, and also exactly `value` with its meaning.
  Allowed or_value(double value, std::string what) const;

  bool contains(double v) const;
  /// "(0, 1]; 0 = automatic": the text of the help and the messages.
  std::string text() const;
};

/// A floating-point option [unit in its help] checked against `allowed`.
CLI::Option* add_number(CLI::App& app, const std::string& name, double& value, std::string help,
                        const Allowed& allowed);
/// An integer option checked against `allowed` (which must hold integers
/// only; "1e3" is read as 1000, "1.5" refused).
CLI::Option* add_integer(CLI::App& app, const std::string& name, int& value, std::string help,
                         const Allowed& allowed);
CLI::Option* add_integer(CLI::App& app, const std::string& name, unsigned& value, std::string help,
                         const Allowed& allowed);
/// A list of integers (one or more), each checked against `allowed`.
CLI::Option* add_integers(CLI::App& app, const std::string& name, std::vector<int>& value, std::string help,
                          const Allowed& allowed);
CLI::Option* add_integers(CLI::App& app, const std::string& name, std::vector<long>& value, std::string help,
                          const Allowed& allowed);
/// Three numbers (a vector), each checked against `allowed`.
CLI::Option* add_vector(CLI::App& app, const std::string& name, std::array<double, 3>& value, std::string help,
                        const Allowed& allowed);
/// A text option that must be one of `choices` ("a | b | c").
CLI::Option* add_choice(CLI::App& app, const std::string& name, std::string& value, std::string help,
                        const std::string& choices);
/// An input file: it must exist, be a regular file, readable and not empty.
CLI::Option* add_input_file(CLI::App& app, const std::string& name, std::string& value, std::string help);
/// A program to run: an executable file, or a name found on PATH.
CLI::Option* add_program(CLI::App& app, const std::string& name, std::string& value, std::string help);
/// An output folder: created if missing, and it must be writable.
CLI::Option* add_output_dir(CLI::App& app, const std::string& name, std::string& value, std::string help);
/// An output file: its folder is created if missing, and the file must be
/// writable (it is not truncated until the run writes it).
CLI::Option* add_output_file(CLI::App& app, const std::string& name, std::string& value, std::string help);

/// Parses the command line. Returns -1 to go on, or the exit code to return
/// from main: 0 after --help, 2 after an error (printed as one line,
/// "error: --option ...", on stderr).
int parse_options(CLI::App& app, int argc, char** argv);

} // namespace dembridge::demo
