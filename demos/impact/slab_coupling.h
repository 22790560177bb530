#pragma once
/// @file slab_coupling.h
/// What the impact run asks of a coupled slab (scenario key shells.model =
/// "coupled"; docs/impact.md, "Coupled slabs"): the DE region to pack, the
/// bars that belong to it, then the shells and the coupler round the
/// spheres, their step, energy, output and checkpoint. The run itself
/// knows no DOLFINx: the implementation (coupled_slab.cpp, library
/// impact_coupled_case) is handed to it through ImpactConfig::coupling.

#include "scenario.h"

#include "dembridge/core/checkpoint.h"
#include "dembridge/dem/bars.h"
#include "dembridge/dem/packing.h"
#include "dembridge/dem/solver.h"

#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

namespace dembridge::demo
{

/// The shells' side of the budget and the coupling's terms [J].
struct ShellsEnergy
{
  double kinetic = 0.0, strain = 0.0;
  double imbalance = 0.0;       ///< the shells' own (it carries the multipliers' work)
  double multiplier_work = 0.0; ///< the multipliers' work on the shells (the opposite on the spheres)
};

/// The time step's settings, as for the DE slab (RunSpec).
struct CouplingStep
{
  double dt = 0.0;     ///< [s]; 0 = safety x the coupled critical step
  double safety = 0.8; ///< [-]
  double damping = 0.0; ///< of the spheres and the shells alike [1/s]
  double skin = 0.0;   ///< neighbour skin [m]
};

class SlabCoupling
{
public:
  virtual ~SlabCoupling() = default;
  /// The spheres' region: the core and its band through the thickness.
  virtual const dem::Region& de_region() const = 0;
  /// The scenario's bars cut to what the spheres hold: the mats' bars end
  /// inside the band (the shells' steel layers carry them beyond).
  /// @throws std::runtime_error for a polyline that leaves the core.
  virtual std::vector<dem::BarLine> cut_bars(const std::vector<dem::BarLine>& lines) const = 0;
  /// Builds the shells and the coupler of p, l (and bars); returns the DE
  /// solver it steps (bodies and the domain are added to it before start).
  virtual dem::DemSolver& couple(dem::Particles& p, dem::Links& l, const dem::Material& mat, dem::Bars bars,
                                 const CouplingStep& step) = 0;
  virtual double dt() const = 0;
  virtual double dt_critical() const = 0; ///< the coupled step's bound [s]
  /// Starts both sides (the shells at rest).
  virtual void start() = 0;
  /// One coupled step; returns the constraint's residual [m/s]. Unless
  /// `observed` (a step whose state is read: a row, a frame), v(n+1) is
  /// not projected onto the constraint (bridge::CoupledSolver::step) and
  /// the residual is the last observed step's.
  virtual double step(bool observed) = 0;
  /// Projects v(n+1) after a step that was not observed (the last one).
  virtual void observe() = 0;
  virtual ShellsEnergy energy() const = 0;
  virtual double max_deflection() const = 0;   ///< largest |u_z| of the shells [m]
  virtual double support_reaction() const = 0; ///< the supports' force along z on the shells [N]
  /// u_z at shells.deflection_points_m, interpolated in their shell elements (u_x under an in-plane pulse) [m]
  virtual std::vector<double> point_deflections() const = 0;
  /// The shells' output (shell.xdmf), new or continued from a checkpoint.
  virtual void open_output(const std::filesystem::path& dir, const checkpoint::Group* root) = 0;
  virtual void write_frame() = 0;
  virtual void close_output() = 0;
  virtual void save(const checkpoint::Group& g) const = 0;
  virtual void load(const checkpoint::Group& g) = 0;
  /// Set-up figures for the summary (shell nodes, tied points, steps).
  virtual nlohmann::json describe() const = 0;
  /// End-of-run figures (time spent, residuals).
  virtual nlohmann::json report() const = 0;
};

using SlabCouplingFactory = std::function<std::unique_ptr<SlabCoupling>(const Scenario&)>;

} // namespace dembridge::demo
