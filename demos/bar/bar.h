#pragma once
/// @file bar.h
/// The paper's validation case (section 4; docs/demos.md, "bar"): a concrete
/// bar 0.85 x 0.25 x 0.25 m, fixed at x = 0, loaded at x = length, modelled
/// all with shells (fe), coupled (shells from x = 0, spheres to the loaded
/// end, tied in an overlap of whole FE layers) or all with spheres (de).
///
/// Loading, documented for users:
/// - static: a force at the loaded end (`static_force`, axial for tension,
///   along z for bending, spread evenly over the end face), applied at t = 0
///   and held, with velocity-proportional damping (default: critical for the
///   first mode of beam theory) until `end_time` (default 3 first periods);
///   the end displacement is compared with beam theory (F L / E A; Timoshenko
///   P L^3 / 3 E I + P L / k G A).
/// - dynamic: the loaded end's displacement (x for tension, z for bending;
///   the other components free) follows d0 (1 - cos(pi t / ramp)) / 2 up to
///   `ramp_time`, then the end is released; undamped free vibration follows.
///   First frequency and amplitude (half peak-to-peak) of the probe
///   histories after the release.
/// The bar is linear elastic (the paper validates the coupling in
/// elasticity): the DE links' strengths are raised out of reach.

#include "restart.h"

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace dembridge::demo
{

struct BarConfig
{
  std::string model = "coupled";  ///< fe | coupled | de
  std::string load = "tension";   ///< tension | bending
  std::string regime = "dynamic"; ///< static | dynamic
  double length = 0.85;           ///< [m]
  double width = 0.25;            ///< section side = shell thickness [m]
  double fe_size = 0.05;          ///< FE element size along x and across [m]
  double mean_radius = 0.01;      ///< DE mean radius [m]
  double radius_ratio = 2.0;      ///< Rmax / Rmin [-]
  unsigned seed = 1;              ///< packing seed
  double overlap_start = 0.40;    ///< coupled: DE region from here [m]
  int overlap_layers = 3;         ///< coupled: FE element layers in the overlap
  double probe_de = 0.75;         ///< probe in the DE zone [m]
  double probe_overlap = 0.4351;  ///< probe in the overlap (de, coupled) [m]
  double probe_overlap_fe = 0.45; ///< the same probe in the FE model [m]
  std::string material;           ///< DE parameter file (from calibrate)
  double fe_youngs_modulus = 0.0; ///< E of the FE side and of beam theory [Pa]; 0 = the file's macroscopic E (the bar demo passes the E the DE bar shows, bar_modulus)
  bool skin_compensation = true;  ///< stiffen the links of the spheres near the faces (dem/skin.h)
  std::string cell = "quadrilateral";
  double static_force = 0.0;      ///< [N]; 0 = 100 kN tension, 20 kN bending
  double damping = -1.0;          ///< static damping [1/s]; < 0 = 2 omega_1 (beam theory)
  double end_displacement = 0.0;  ///< dynamic d0 [m]; 0 = 5e-5 tension, 2e-4 bending
  double ramp_time = 0.0;         ///< dynamic ramp [s]; 0 = one first period (beam theory)
  double end_time = 0.0;          ///< [s]; 0 = 3 periods (static), ramp + 4 periods (dynamic)
  double safety = 0.8;            ///< fraction of the critical time step
  int frames = 20;                ///< output frames
  std::string output;             ///< folder for history.csv, shape.csv, XDMF; empty = none
  bool quiet = false;             ///< no progress lines
  /// Checkpoints and restart of a single case (restart.h); null: neither.
  const RestartOptions* restart = nullptr;
};

/// Checks the options that need no run (names, sizes, positions).
/// @throws std::runtime_error naming the value and what is allowed.
void check_config(const BarConfig& c);

/// Throws std::runtime_error "what value: allowed is allowed" (a value of
/// the configuration out of its range).
[[noreturn]] void refuse_value(const std::string& what, double value, const std::string& allowed);

/// Runs one case; returns the summary (keys: model,
/// load, regime, particles, shell_nodes, probe_0_75 and probe_0_4351 with
/// first_frequency_hz and amplitude_m (dynamic), static_end_displacement_m
/// and reference_end_displacement_m (static), wall_s, steps, and more).
/// @throws std::runtime_error on bad input, naming the value and what is allowed.
nlohmann::json run_bar(const BarConfig& c);

/// Young's modulus the DE bar shows in static tension [Pa]: end force over
/// area over the strain fitted (least squares) on the DE displacement along
/// the middle half of the bar, away from both ends. `run` is the summary of a
/// de / tension / static run, which holds it as measured_youngs_modulus_pa.
double measured_modulus(const nlohmann::json& run);

/// The E the DE bar of c's sizes, seed and skin compensation shows in
/// static tension [Pa]: a de / tension / static run of c (quiet, no output)
/// and its measured_modulus. The default E of the FE side and of beam theory.
double bar_modulus(BarConfig c);

/// Beam-theory first frequency of the bar for the load [Hz].
double bar_first_frequency(const BarConfig& c, double E, double nu, double rho);

/// The paper's table from the twelve runs (keys "<model>_<load>_<regime>"):
/// frequency and amplitude differences coupled vs DE and vs FE at both
/// probes, static errors against beam theory, wall times. Returns the table
/// as JSON; `markdown` receives it as a Markdown table.
nlohmann::json compare_table(const nlohmann::json& runs, std::string& markdown);

/// The twelve cases with c's sizes, seed and E (c.model, load, regime and
/// output are not read), each written to root/<model>_<load>_<regime>
/// (history, shapes, XDMF, summary.json), then root/comparison.md and
/// root/comparison.json. Returns {"table": compare_table, "runs": summaries}.
nlohmann::json compare_cases(const BarConfig& c, const std::filesystem::path& root);

/// Several packings (`--seeds`): for each quantity of the paper's table,
/// each model's mean and sample standard deviation over the seeds, coupled
/// vs DE and vs FE for each seed, and in how many seeds the coupled value
/// lies between the FE and DE ones; for the statics, each model's error
/// against beam theory per seed. `tables[k]` is compare_table's JSON for
/// `seeds[k]`. Returns it as JSON; `markdown` receives the Markdown tables.
/// @throws std::runtime_error with fewer than two seeds.
nlohmann::json seeds_table(const std::vector<unsigned>& seeds, const std::vector<nlohmann::json>& tables,
                           std::string& markdown);

} // namespace dembridge::demo
