#pragma once
/// @file impact_run.h
/// The impact run (internal to the impact case): its set-up in
/// impact_setup.cpp (the slab, its bars, the projectile, the solver, or the
/// coupled slab's), its time loop, output, checkpoints and measurements in
/// impact.cpp.

#include "deflection.h"
#include "impact.h"
#include "restart.h"

#include "dembridge/dem/output.h"
#include "dembridge/dem/packing.h"
#include "dembridge/dem/solver.h"

#include <array>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace dembridge::demo::impl
{
using namespace dembridge::dem;
using V3 = std::array<double, 3>;

inline double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double mean(const std::vector<double>& v);
/// The budget's terms as history.csv and the summary group them [J]: the
/// spheres' and bars' kinetic energy; the elastic energy of links, contacts
/// (the projectile's too) and bars; everything dissipated.
double target_kinetic(const DemEnergy& e);
double elastic_all(const DemEnergy& e);
double dissipated(const DemEnergy& e);
/// A number with `precision` significant digits, for messages.
std::string fmt(double v, int precision = 4);

/// Where the outcome stands.
enum class Outcome
{
  running,
  perforated, ///< it touched the slab, its tail is past the rear face and nothing touches it
  missed,     ///< its tail is past the rear face and it never touched the slab
  stopped,    ///< the projectile's speed along its path fell to zero (or reversed)
  time_up     ///< the duration was reached first
};
const char* outcome_name(Outcome o);

/// One impact run: set-up (slab, projectile, supports, domain, time step),
/// the time loop with its history, frames and progress, and the
/// measurements at the end.
class ImpactRun
{
public:
  explicit ImpactRun(const ImpactConfig& cfg) : _cfg(cfg), _s(cfg.scenario) {}

  nlohmann::json run();

private:
  bool bars() const { return _has_bars; }
  /// A prescribed pulse loads the slab in place of the projectile.
  bool pulsed() const { return _s.pulse.any(); }

  // ---- set-up ---------------------------------------------------------------
  void build_target();

  /// The slab's packing, graded along the projectile's path if the
  /// scenario asks for finer spheres there (fine_scale); with bars, packed
  /// round them (pack_around_bars), so that no void is left beside a bar
  /// (removing the spheres on the bars from a plain packing and lining the
  /// bars leaves a loose layer round them: validation.md 7b.2).
  Packing pack(const Region& region) const;

  /// The bars of the scenario (make_bars), their elements at most
  /// element_length_m long (0: the mean sphere diameter).
  void make_the_bars();

  /// Leaves out the spheres (x, r) that overlap a bar by more than the
  /// packing's tolerance (1e-3 of the smallest radius).
  void clear_bars(std::vector<double>& x, std::vector<double>& r);

  /// A packing file's spheres, those centred in the slab (a sphere outside
  /// it is an error: the file is not this slab's).
  Packing read_target_packing(const Region& region) const;
  void build_projectile();
  /// The pulse (PulseSpec) on the spheres under its disc: those centred
  /// within pulse.radius_m of projectile.aim_m in plan whose top lies
  /// within one smallest radius of the struck face, an equal share each.
  void set_up_pulse();
  /// The spheres of each deflection point of an all-DE slab: those centred
  /// within 2 mean radii of it in plan, through the thickness.
  void locate_points();
  /// The deflection at each point [m]: the coupled slab's shells', or the
  /// mass-weighted mean u_z of the point's spheres (u_x under an in-plane
  /// pulse).
  std::vector<double> point_deflections() const;
  void set_up_solver();
  void set_up_supports();
  /// target.supports = "frame": four fixed boxes under the rear face's
  /// strip within support_width_m of the edges (reaching as far beyond
  /// them), touched by the spheres through the body contact law,
  /// frictionless; added after the projectile (body 0).
  void add_frame();
  /// The supports' force on the slab along z [N]: the held spheres'
  /// reaction, the frame's contacts, or the coupled slab's shells'.
  double support_reaction() const;

  /// With finer spheres along the path, the mean radius of those centred
  /// within target.fine_radius_m of it (none: nullopt, as without them).
  std::optional<double> fine_mean_radius() const;
  void describe();

  /// The bars' figures for the summary (before a coupler takes them).
  void describe_bars();

  // ---- output and restart ---------------------------------------------------
  std::filesystem::path dir() const { return _cfg.output_dir; }

  /// The output series, new or (root: a checkpoint's) continued.
  void open_writer(const checkpoint::Group* root);
  void open_output();
  void resume();
  void save(const checkpoint::Group& root);
  void write_frame();

  // ---- the projectile's state -----------------------------------------------
  V3 tip() const { return _solver->body(0).to_world({0.0, 0.0, 0.0}); }
  V3 tail() const { return _solver->body(0).to_world({-_shape.length, 0.0, 0.0}); }
  double path_velocity() const { return dot(_solver->body(0).v, _dir); }
  /// The contacts' force on the projectile against its path [N] (> 0 resists).
  double contact_force() const { return -dot(_solver->body(0).f, _dir); }

  std::size_t broken() const;
  void write_row();
  void write_pulse_row();
  /// A row's coupled columns and deflection points, its end of line.
  void end_row(const ShellsEnergy& f);

  /// The energy budget's imbalance [J]: the spheres' with the shells' (each
  /// carries the multipliers' work, their sum closes).
  double imbalance() const;
  /// The coupled slab's shells' budget (zero without shells).
  ShellsEnergy shells_energy() const;
  void print_header() const;
  void progress() const;

  // ---- the time loop --------------------------------------------------------
  Outcome outcome();

  /// The shared time loop (time_loop.h): the outcome is its end condition;
  /// history rows every _history_every steps, frames every crossing /
  /// frames, progress every 2 s, each also at the last step.
  void loop();

  // ---- measurements ---------------------------------------------------------
  void report();
  void report_bars();
  void measure_damage();
  void report_energy();
  /// The projectile's outcome, speeds, depth, craters and energy partition.
  void report_projectile();
  /// Under a pulse: the outcome and the load's energy budget.
  void report_pulse();
  /// The mean damage (broken / initial links) of the overlap's spheres, in
  /// the summary: how far the damage reached into the band.
  void report_band_damage(const std::vector<int>& lost);
  const ImpactConfig& _cfg;
  const Scenario& _s;
  nlohmann::json _out;
  V3 _lo{}, _hi{}, _dir{};
  Packing _pk;
  Particles _p;
  Links _links;
  std::vector<int> _initial_links;
  double _fraction = 0.0, _lambda = 0.0, _rmax = 0.0, _rmin = 0.0;
  Shape _shape;
  RigidBody _body;
  double _ke0 = 0.0;
  double _dt = 0.0, _dt_crit = 0.0, _duration = 0.0, _crossing = 0.0;
  std::int64_t _nsteps = 0, _crossing_steps = 1, _history_every = 1;
  std::size_t _supported = 0;
  std::vector<std::size_t> _frame; // the frame's bodies
  Bars _bars;
  bool _has_bars = false;
  std::size_t _bonds = 0, _spheres_on_bars = 0;
  std::vector<double> _masses; // the spheres' masses as built (a coupler weights _p.m)
  // the coupled slab (after the spheres, links and bars it holds), the
  // solver of the spheres (its own, or the coupler's)
  std::unique_ptr<SlabCoupling> _coupling;
  std::unique_ptr<DemSolver> _own_solver;
  DemSolver* _solver = nullptr;
  std::unique_ptr<Checkpointer> _ckpt;
  std::unique_ptr<ParticleWriter> _writer;
  std::unique_ptr<BarWriter> _bar_writer;
  double _residual = 0.0; // the coupled step's constraint residual [m/s]
  std::ofstream _csv;
  double _max_depth = -1e300, _peak_force = 0.0;
  bool _touched = false;
  Outcome _outcome = Outcome::running;
  std::vector<std::int32_t> _loaded;                  // the pulse's spheres
  std::vector<std::vector<std::int32_t>> _point_spheres; // an all-DE slab's deflection points
  std::unique_ptr<DeflectionTrack> _track;
};

} // namespace dembridge::demo::impl
