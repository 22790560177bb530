#pragma once
/// @file scenario.h
/// The impact scenario file (TOML): a target slab of DE concrete, a rigid
/// projectile, the supports and the run's settings, each a section of the
/// file; keys carry their SI unit in their name (docs/impact.md gives the
/// schema). Every key is checked when the file is read: an unknown key, a
/// value of the wrong type or out of its range is an error naming the file,
/// the key and what is allowed. `--set key=value` overrides a key (dotted:
/// `projectile.velocity_m_s=600`) as if the file said so.

#include "dembridge/dem/assembly.h"
#include "dembridge/dem/bars.h"
#include "dembridge/dem/body.h"
#include "dembridge/dem/packing.h"

#include <array>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace dembridge::demo
{

/// The concrete: a calibrated material file, then any of its keys overridden.
struct MaterialSpec
{
  std::string file;              ///< resolved path of the material file
  dem::Material material;        ///< its values, with the overrides
  double links_per_sphere = 12.0;
  std::optional<dem::Steel> steel;   ///< the file's steel, if it has one
  std::optional<dem::BondLaw> bond;  ///< the file's bond law, if it has one
};

/// A rectangular slab: x, y in [-size/2, size/2], z in [-thickness, 0] (the
/// struck face at z = 0, its outward normal +z).
struct TargetSpec
{
  std::array<double, 2> size{0.1, 0.1}; ///< lateral sizes [m]
  double thickness = 0.03;              ///< [m]
  double mean_radius = 2.5e-3;          ///< [m]
  double radius_ratio = 2.0;            ///< Rmax / Rmin [-]
  unsigned seed = 1;
  std::string packing_file;             ///< "" = generate
  std::string supports = "sides";       ///< sides (lateral faces held) | rear-edges | none
  double support_width = 0.0;           ///< band held [m]; 0 = 2 Rmax
  /// finer spheres within this distance of the projectile's path [m]; 0 = none
  double fine_radius = 0.0;
  double fine_mean_radius = 0.0;        ///< their mean radius [m]; 0 = mean_radius / 2
  double fine_transition = 0.0;         ///< width over which the radii grow to mean_radius [m]; 0 = 4 mean_radius
  /// stiffen the links of the spheres near the slab's faces (dem/skin.h),
  /// which are soft in bending without it
  bool skin_compensation = false;
  bool fine() const { return fine_radius > 0.0; }
  double fine_mean() const { return fine_mean_radius > 0.0 ? fine_mean_radius : 0.5 * mean_radius; }
  double transition() const { return fine_transition > 0.0 ? fine_transition : 4.0 * mean_radius; }
};

/// Reinforcement: mats of bars along x and y through the thickness, and/or
/// bars given as polylines; their steel and bond (docs/impact.md).
struct ReinforcementSpec
{
  int layers = 0;                          ///< mats; 0 = none
  double bar_diameter = 0.0;               ///< [m]
  std::array<double, 2> spacing{0.1, 0.1}; ///< between the bars along x (in y), along y (in x) [m]
  double cover = 0.0;                      ///< face to the axis of the outermost bars [m]; 0 = 2 bar diameters
  std::vector<std::vector<std::array<double, 3>>> polylines; ///< explicit bars [m]
  dem::Steel steel;
  dem::BondLaw bond;
  double element_length = 0.0; ///< [m]; 0 = the mean sphere diameter
  double bond_reach = 0.0;     ///< [m]; 0 = half the mean sphere radius
  /// true: the slab is packed as without bars and the bars lie inside it,
  /// bonded to the spheres they cross (no room left, no sphere-bar contact);
  /// the default, as the room left for the bars weakens the slab (docs/impact.md)
  bool embedded = true;
  bool any() const { return layers > 0 || !polylines.empty(); }
};

struct ProjectileSpec
{
  double mass = 0.0;           ///< [kg]; 0 = from density and shape
  double density = 7850.0;     ///< [kg/m^3] (used when mass = 0)
  double diameter = 0.0254;    ///< [m]
  double length = 0.1;         ///< tip to tail [m]
  std::string nose = "ogive";  ///< flat | hemispherical | conical | ogive
  double crh = 3.0;            ///< ogive caliber-radius-head [-]
  double cone_angle_deg = 30.0;
  double velocity = 300.0;     ///< striking speed [m/s]
  double obliquity_deg = 0.0;  ///< angle between the path and the face's normal, in the x-z plane
  std::array<double, 2> aim{0.0, 0.0}; ///< where the path meets the face (x, y) [m]
  double standoff = 1e-3;      ///< tip to face at the start, along the path [m]
  double friction = 0.1;       ///< Coulomb coefficient projectile-concrete [-]
};

struct RunSpec
{
  double duration = 0.0;       ///< at most [s]; 0 = 4 x the crossing time (slab and its own length)
  double dt = 0.0;             ///< [s]; 0 = safety x critical
  double safety = 0.8;         ///< fraction of the critical step [-] (validation.md 7b.1)
  double damping = 0.0;        ///< velocity-proportional damping [1/s]
  int frames = 40;             ///< XDMF frames over the crossing time
  int history_every = 0;       ///< steps between history rows; 0 = 250 over the crossing time
  double domain_margin = 0.0;  ///< the domain: the slab grown by this [m]; 0 = its thickness
  double skin = 0.0;           ///< neighbour-list skin [m]; 0 = half the smallest radius
};

/// The slab's model (docs/impact.md, "Coupled slabs"): all DE, or a DE core
/// where the projectile strikes tied to reinforced-concrete shells over the
/// rest of the slab (bridge/slab.h).
struct ShellSpec
{
  std::string model = "de";        ///< de | coupled
  std::string core = "cylinder";   ///< cylinder | box, through the thickness, centred on projectile.aim_m
  double core_radius = 0.0;        ///< cylinder [m]
  std::array<double, 2> core_size{0.0, 0.0}; ///< box, along x and y [m]
  double band = 0.0;               ///< the overlap's width round the core [m]; 0 = 8 mean radii
  double element_size = 0.0;       ///< the shells' at the core [m]; 0 = band / 2
  double outer_element_size = 0.0; ///< at the slab's corners, graded [m]; 0 = element_size
  std::string cell = "quadrilateral"; ///< quadrilateral | triangle
  std::string edges;               ///< free | simply-supported | clamped; "" = from target.supports
  double weight_floor = 1e-3;      ///< of the weighted masses (bridge::CouplingOptions) [-]
  /// points (x, y) whose deflection history.csv follows: on shells interpolated in the
  /// element at the mid-surface, on spheres the mean of those within 2 mean radii [m]
  std::vector<std::array<double, 2>> deflection_points;
  bool coupled() const { return model == "coupled"; }
  bool shells_only() const { return model == "fe"; }
};

/// A prescribed load in place of the projectile (docs/impact.md, "Elastic
/// checks"): a half-sine pulse F(t) = peak sin(pi t / duration) for t in
/// [0, duration], zero after, spread evenly over a disc centred on
/// projectile.aim_m: along -z on the struck face (bending), or along +x
/// through the whole thickness (membrane). The same pulse loads the three
/// models (the spheres under or in the disc; the shells' nodes in it).
struct PulseSpec
{
  double peak_force = 0.0; ///< [N]; 0 = none (the projectile strikes)
  double duration = 0.0;   ///< [s]
  double radius = 0.0;     ///< the loaded disc's [m]; 0 = projectile.diameter_m / 2
  std::string direction = "-z"; ///< -z (on the struck face) | x (in plane, through the thickness)
  bool any() const { return peak_force > 0.0; }
  bool in_plane() const { return direction == "x"; }
  /// F(t) [N]
  double force(double t) const;
};

struct Scenario
{
  std::filesystem::path file;
  std::string name;
  MaterialSpec material;
  TargetSpec target;
  ReinforcementSpec reinforcement;
  ProjectileSpec projectile;
  RunSpec run;
  ShellSpec shells;
  PulseSpec pulse;
  /// Every key with the value used (defaults included), "section.key" ->
  /// value: echoed at the start, written to the summary, compared on restart.
  nlohmann::json resolved;
};

/// Reads and checks a scenario file, with the --set overrides ("key=value",
/// value in TOML syntax; a bare word is a string). Relative file names in
/// it are relative to the scenario's folder.
/// @throws std::runtime_error naming the file, the key and what is allowed.
Scenario read_scenario(const std::filesystem::path& file, const std::vector<std::string>& sets = {});

/// The bars of the scenario's reinforcement: the mats' bars (along x above
/// along y in each mat, the mats spread evenly from the struck face's cover
/// to the rear face's; one mat lies at the rear face's), then the polylines.
/// @throws std::runtime_error naming the key: a cover below the bar radius,
///   mats that do not fit in the thickness, a spacing not above the
///   diameter, a polyline with no part inside the slab.
std::vector<dem::BarLine> bar_lines(const Scenario& s);
/// The mats' bars alone (the first of bar_lines), with their checks.
std::vector<dem::BarLine> mat_lines(const Scenario& s);

/// The projectile's shape (its nose, diameter, length).
/// @throws std::runtime_error naming the keys: a shape that cannot be made
///   (a body shorter than its nose).
dem::Shape projectile_shape(const ProjectileSpec& q);

/// The unit vector of the projectile's path: along -z tilted by the
/// obliquity towards +x.
std::array<double, 3> path_direction(const ProjectileSpec& q);

/// The radius scale of the slab's packing at a point (PackingOptions::
/// size_scale) with target.fine_radius_m: fine_mean_radius_m / mean_radius_m
/// within fine_radius_m of the projectile's path (the line through aim_m at
/// the obliquity), growing linearly to 1 over fine_transition_m beyond.
std::function<double(const dem::Point&)> fine_scale(const Scenario& s);

/// The scenario keys with their meaning, unit and default, one per line
/// (`impact --keys`; docs/impact.md lists the same).
std::string scenario_keys();

/// "pulse.radius_m = R m", or for the default the projectile's half diameter
/// it stands for, as the messages name the pulse's disc.
std::string pulse_radius_text(const Scenario& s);

/// A number as the scenario's messages print it (12 significant digits).
std::string number_text(double v);

} // namespace dembridge::demo
