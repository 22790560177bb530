#pragma once
/// @file sample.h
/// Quasi-static uniaxial tension or compression, or triaxial compression, of a DE sample (cylinder or
/// square prism), as a function the dem_sample demo, the tests and the
/// calibration share. The bottom layer of spheres is held axially, the top
/// layer moves axially at a constant strain rate (ramped in over 20 wave
/// transits); both are free laterally (frictionless platens). E and nu are
/// measured as a laboratory does, on gauges over the middle: the axial
/// strain of the middle half (spheres centred within Rmax of H/4 and 3H/4),
/// the lateral strain of the surface spheres of the middle third, and the
/// stress averaged over the gauge from the two platen reactions. The platen
/// strain (displacement over the height) is also written. A triaxial test
/// (prism) adds a lateral pressure through four rigid, frictionless side
/// plates, one per side face (SampleConfig::confinement).

#include "dembridge/dem/assembly.h"
#include "dembridge/dem/packing.h"

#include "restart.h"

#include <nlohmann/json.hpp>
#include <string>

namespace dembridge::demo
{

struct SampleConfig
{
  std::string shape = "cylinder";   ///< cylinder | prism
  double diameter = 0.05;           ///< cylinder diameter or prism side [m]
  double height = 0.1;              ///< [m]
  double mean_radius = 2.5e-3;      ///< [m]
  double radius_ratio = 2.0;        ///< Rmax / Rmin
  unsigned seed = 1;
  std::string packing_file;         ///< x y z r file instead of generating
  double lambda = 0.0;              ///< interaction range; 0 = from links_per_sphere
  double links_per_sphere = 12.0;
  dem::Material material;
  std::string test = "tension";     ///< tension | compression | triaxial
  /// Triaxial test (prism only): the lateral pressure [Pa] four rigid side
  /// plates apply. They follow the axial stress up to it (the hydrostatic
  /// phase), then hold it while the top platen goes on (the deviatoric
  /// phase). 0 for the other tests.
  double confinement = 0.0;
  /// Circumferential notch at mid-height (cylinder; prism: on all four
  /// faces): the links crossing z = H/2 outside the ligament are removed.
  /// The ligament's share of the cross-section, in (0, 1]; 1 = no notch.
  /// Stresses, fracture energy are then per ligament area.
  double ligament = 1.0;
  double strain_rate = 0.1;         ///< [1/s], > 0
  double max_strain = 0.0;          ///< stop at this strain; 0 = 5e-4 tension, 5e-3 compression, 3e-2 triaxial
  double stop_ratio = 0.5;          ///< stop when |stress| (triaxial: the deviator) falls below this x peak after the peak
  /// Tension until the sample is separated (the force through the crack,
  /// on the bottom platen, stays below 1 % of the peak for two periods of
  /// the first axial mode), for the fracture energy; stop_ratio is then not
  /// used and max_strain = 0 means 5e-3.
  bool to_separation = false;
  double damping = -1.0;            ///< [1/s]; < 0 = first axial circular frequency of the sample (0 with uniform_start)
  /// Dynamic tests: every sphere starts at the affine axial velocity
  /// strain_rate z (the platens' own from the first step, no ramp), so the
  /// strain is uniform from the start and no wave runs from the platens.
  bool uniform_start = false;
  double dt = 0.0;                  ///< [s]; 0 = safety x critical
  double safety = 0.9;
  std::string output_dir;           ///< "" = no files
  int frames = 100;                 ///< XDMF frames if the run goes to max_strain
  bool quiet = false;
  /// Checkpoints and restart (restart.h); null: neither.
  const RestartOptions* restart = nullptr;
};

/// The sample's region: a cylinder of axis z (diameter, height) or a square
/// prism, from the origin. @throws for another shape.
dem::Region sample_region(const SampleConfig& cfg);

/// The sample's packing: read from cfg.packing_file, else generated in
/// sample_region(cfg) with the mean radius, radius ratio and seed.
dem::Packing sample_packing(const SampleConfig& cfg);

/// Runs the test; returns the summary (particles, links,
/// mean_links_per_particle, packing_fraction, youngs_modulus_pa,
/// poisson_ratio, peak_stress_pa, strain_at_peak, links_broken_tension,
/// links_broken_shear, cohesion_demand_pa, wall_s, ...). cohesion_demand_pa
/// is the smallest C0 at which no link would have failed in shear during the
/// run (dem::ForceCounters::cohesion_demand): the same test with any C0
/// above it, all else equal, gives the same result bit for bit;
/// cohesion_demand_at_peak_pa the same up to the peak (the same run up to
/// it). A tension test run to separation
/// (to_separation, and max_strain large enough: `separated` is true)
/// measures the fracture energy `fracture_energy_j_m2`: the energy the links
/// dissipate (softening, and what is left in a link when it breaks) over the
/// cross-section; `dissipated_before_peak_j` is its part before the peak. Writes DIR/stress_strain.csv and
/// DIR/particles.xdmf with an output folder.
nlohmann::json run_sample(const SampleConfig& cfg);

} // namespace dembridge::demo
