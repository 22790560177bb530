// impact: a rigid projectile striking a slab of DE concrete (docs/impact.md).
// The case is a scenario file (TOML): the concrete, the slab and its
// supports, the projectile, the run; --set overrides any key.
//
// Sample runs:
//   build/bin/impact small --output out/impact --summary out/impact/summary.json
//   build/bin/impact hanchak-48 --set projectile.velocity_m_s=606 --output out/h606
//   build/bin/impact my_case.toml --set target.mean_radius_m=0.004
//   build/bin/impact --keys            (every scenario key, its unit and default)
// Output: DIR/particles.xdmf (+ .h5: the spheres with damage and velocity,
// the broken links as cracks, the projectile's surface), DIR/history.csv,
// DIR/history.png, DIR/scenario.json (every key as used), DIR/packing.txt.
#include "coupled_slab.h"
#include "fe_runtime.h"
#include "impact.h"
#include "options.h"
#include "support.h"

#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>

namespace
{
/// A shipped scenario's name ("small"), or a file.
std::string scenario_path(const std::string& arg)
{
  namespace fs = std::filesystem;
  if (fs::exists(arg) || arg.find('/') != std::string::npos || arg.ends_with(".toml"))
    return arg;
  return dembridge::demo::shipped_file("scenarios/" + arg + ".toml",
                                       DEMBRIDGE_SOURCE_DIR "/demos/impact/scenarios/" + arg + ".toml");
}
} // namespace

int main(int argc, char** argv)
{
  using namespace dembridge;
  demo::ImpactConfig c;
  std::string scenario, summary, model;
  std::vector<std::string> sets;
  bool keys = false;
  int plot = 1;
  CLI::App app{"A rigid projectile striking a slab of DE concrete", "impact"};
  app.add_option("scenario", scenario,
                 "scenario file (TOML), or the name of a shipped one: small, small-rc, small-slab, elastic-slab, hanchak-48, semi-infinite");
  app.add_option("--set", sets, "override a scenario key: section.key=value (TOML value), e.g. "
                                "projectile.velocity_m_s=600; repeatable");
  demo::add_choice(app, "--model", model, "the slab's model, as the scenario key shells.model: de = all spheres, "
                   "coupled = a DE core tied to reinforced-concrete shells, fe = all shells under the scenario's [pulse]; \"\" = the "
                   "scenario's", "de | coupled | fe");
  app.add_flag("--keys", keys, "print every scenario key with its unit, default and allowed values, and exit");
  demo::add_integer(app, "--plot", plot, "1: write DIR/history.png with matplotlib, 0: no", demo::Allowed::closed(0, 1));
  demo::RestartOptions restart;
  demo::add_run_options(app, c.output_dir, "output folder (XDMF, CSV, PNG); empty = none", summary, restart);
  if (const int rc = demo::parse_options(app, argc, argv); rc >= 0)
    return rc;
  if (keys)
  {
    std::cout << "Scenario keys (TOML sections and keys; SI units in the names):\n" << demo::scenario_keys();
    return 0;
  }
  if (scenario.empty())
  {
    std::cerr << "error: scenario: give a scenario file or a shipped scenario's name (small, small-rc, small-slab, hanchak-48, "
                 "semi-infinite); --keys lists the keys" << std::endl;
    return 2;
  }
  try
  {
    if (!model.empty())
      sets.push_back("shells.model=\"" + model + "\"");
    c.scenario = demo::read_scenario(scenario_path(scenario), sets);
  }
  catch (const std::exception& e)
  {
    std::cerr << "error: " << e.what() << std::endl;
    return 2;
  }
  // the run is defined by the scenario's values, not by the file's name
  if (const int rc = demo::record_setup(app, restart, {"scenario", "--set", "--model", "--keys", "--plot"}); rc >= 0)
    return rc;
  for (const auto& [key, value] : c.scenario.resolved.items())
    restart.setup[key] = value.dump();
  c.restart = &restart;
  c.plot = plot == 1;
  c.coupling = demo::make_slab_coupling;
  c.shells_only = demo::run_shell_slab;

  return demo::run_guarded(argc, argv, [&]
  {
    demo::echo_options(app);
    std::cout << "# scenario " << c.scenario.file.string() << ":\n";
    for (const auto& [key, value] : c.scenario.resolved.items())
      std::cout << "#   " << key << " = " << value.dump() << "\n";
    const auto r = demo::run_impact(c);
    std::cout << r.dump(2) << std::endl;
    if (!summary.empty())
      demo::write_summary(summary, r);
    if (c.plot && !c.output_dir.empty())
    {
      if (demo::run_plot_script("plot_impact.py", c.output_dir, "history.csv is"))
        std::cout << "plot: " << (std::filesystem::path(c.output_dir) / "history.png").string() << "\n";
    }
  }, summary, c.scenario.shells.model != "de" ? demo::petsc_runtime() : demo::Runtime{});
}
