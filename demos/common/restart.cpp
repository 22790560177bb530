#include "restart.h"

#include "options.h"
#include "support.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <iostream>
#include <stdexcept>

namespace dembridge::demo
{

void add_restart_options(CLI::App& app, RestartOptions& o)
{
  add_integer(app, "--checkpoint-every", o.every,
              "write a checkpoint every N steps (and whenever the run is interrupted); 0 = only when interrupted",
              Allowed::closed(0, 1e9));
  add_output_file(app, "--checkpoint", o.file,
                  "checkpoint file (HDF5) to write; default OUTPUT/checkpoint.h5, none without --output");
  // the file is checked to be a checkpoint of this program before any work
  add_input_file(app, "--restart", o.restart,
                 "continue the run from this checkpoint (same options; its output folder is continued)")
      ->each([&app](const std::string& file)
             {
               try
               {
                 checkpoint::File::open(file, app.get_name());
               }
               catch (const std::exception& e)
               {
                 throw CLI::ValidationError(e.what());
               }
             });
}

void add_run_options(CLI::App& app, std::string& output_dir, const std::string& output_help, std::string& summary,
                     RestartOptions& restart)
{
  add_output_dir(app, "--output", output_dir, output_help);
  add_output_file(app, "--summary", summary, "write the results as JSON to this file");
  add_restart_options(app, restart);
}

int parse_run_options(CLI::App& app, int argc, char** argv, RestartOptions& restart)
{
  if (const int rc = parse_options(app, argc, argv); rc >= 0)
    return rc;
  return record_setup(app, restart);
}

int record_setup(CLI::App& app, RestartOptions& o, const std::vector<std::string>& ignore)
{
  static const std::vector<std::string> where{"--help", "--output", "--summary", "--checkpoint",
                                              "--checkpoint-every", "--restart"};
  o.setup = nlohmann::json::object();
  for (CLI::Option* opt : app.get_options())
  {
    const std::string name = opt->get_name();
    if (name.empty() || std::count(where.begin(), where.end(), name) || std::count(ignore.begin(), ignore.end(), name))
      continue;
    std::string val;
    for (const auto& r : opt->results())
      val += (val.empty() ? "" : " ") + r;
    if (opt->results().empty())
      val = opt->capture_default_str()->get_default_str();
    o.setup[name] = val;
  }
  o.program = app.get_name();
  const CLI::Option* out = app.get_option_no_throw("--output");
  if (o.every > 0 && o.file.empty() && (!out || out->results().empty() || out->results()[0].empty()))
  {
    std::cerr << "error: --checkpoint-every: " << o.every
              << " steps, but nowhere to write the checkpoints: give --output DIR (they go to "
                 "DIR/checkpoint.h5) or --checkpoint FILE" << std::endl;
    return 2;
  }
  return -1;
}

Checkpointer::Checkpointer(const RestartOptions& o, const std::string& output_dir) : _o(o)
{
  if (!o.file.empty())
    _file = o.file;
  else if (!output_dir.empty())
    _file = std::filesystem::path(output_dir) / "checkpoint.h5";
  // a checkpoint of another set-up is refused now, before the run's set-up
  // (packing, meshing) is spent on it
  if (restarting())
    open_restart();
}

checkpoint::File Checkpointer::open_restart() const
{
  auto f = checkpoint::File::open(_o.restart, _o.program);
  const auto root = f.root();
  const auto stored = nlohmann::json::parse(root.read_string("setup"), nullptr, false);
  if (!stored.is_object())
    root.fail("setup", "not the JSON of a run's options (file damaged?)");
  for (const auto& [name, value] : _o.setup.items())
  {
    const std::string was = stored.contains(name) ? stored[name].get<std::string>() : "(not an option then)";
    if (was != value.get<std::string>())
      throw std::runtime_error(name + ": '" + value.get<std::string>() + "' differs from the checkpointed run's '"
                               + was + "' (" + _o.restart + "): a restart continues the same run; "
                               + (name.starts_with("--") ? "give " + name + " " + was
                                                         : "set " + name + " = " + was + " (scenario file or --set)"));
  }
  return f;
}

void Checkpointer::write(const std::function<void(const checkpoint::Group&)>& save)
{
  if (!enabled())
    return;
  auto f = checkpoint::File::create(_file, _o.program);
  {
    const auto root = f.root(); // closed before the file is
    root.write("setup", _o.setup.dump());
    save(root);
  }
  f.commit();
  ++_written;
  note_checkpoint(_file);
}

void Checkpointer::end_of_step(std::int64_t step, double t, const std::function<void(const checkpoint::Group&)>& save)
{
  if (stop_requested() || (_o.every > 0 && step % _o.every == 0))
    write(save);
  check_stop(t);
}

std::int64_t flushed_size(std::ofstream& out, const std::filesystem::path& file)
{
  out.flush();
  if (!out)
    throw std::runtime_error("writing '" + file.string() + "' failed (disk full?)");
  return static_cast<std::int64_t>(out.tellp());
}

void reopen_text(std::ofstream& out, const std::filesystem::path& file, std::int64_t bytes)
{
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  if (ec || static_cast<std::int64_t>(size) < bytes)
    throw std::runtime_error("cannot continue '" + file.string() + "': " + (ec ? "missing" : "shorter than the checkpoint recorded")
                             + " (restart into the output folder of the run that wrote the checkpoint)");
  std::filesystem::resize_file(file, static_cast<std::uintmax_t>(bytes));
  out.open(file, std::ios::app);
  if (!out)
    throw std::runtime_error("cannot open '" + file.string() + "' to continue it");
}

} // namespace dembridge::demo
