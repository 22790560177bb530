#pragma once
/// @file coupled.h
/// The explicit bridging-domain coupling of a DE assembly with a shell or a
/// 3D solid FE model (docs/method.md, "The bridging-domain coupling"): energy weights on both sides, the particles
/// of the overlap tied to the shell's motion through fictive elements, and
/// one step = both sides' half kicks, the multiplier correction of the
/// half-step velocities, then both sides' drift, forces and second half kick.
///
/// Weights: eta from the overlap (1 on the FE side, 0 on the DE side).
/// FE: internal forces weighted inside the elements (the UFL weight field),
/// lumped masses max(eta, floor) M. DE: masses and inertias max(1 - eta,
/// floor) m, link forces and energies (1 - eta) at the link mid-point,
/// contacts by the mean weight of their spheres.
/// Shell dofs held by boundary conditions must lie outside the overlap.

#include "dembridge/bridge/fictive.h"
#include "dembridge/bridge/multipliers.h"
#include "dembridge/bridge/weight.h"
#include "dembridge/dem/solver.h"
#include "dembridge/shell/explicit.h"
#include "dembridge/shell/model.h"

#include <memory>

namespace dembridge::bridge
{

struct CouplingOptions
{
  /// the overlap band round the DE-only core (weight.h)
  Overlap overlap = PlanarOverlap{};
  double weight_floor = 1e-3;   ///< in (0, 1)
  double dt = 0.0;              ///< [s]; 0 = safety x the coupled critical step
  /// fraction of the coupled critical step, in (0, 0.95]: the step is a
  /// power-iteration estimate (lambda_max from below), tested stable at 0.97
  /// of it; at 1.0 a run gains energy
  double safety = 0.8;
  /// the energy guard of the coupled system (its total against the initial
  /// energy and the work, as in DemSolver::set_energy_guard); 0 = off
  double energy_guard = 0.5;
  double damping_fe = 0.0;      ///< mass-proportional damping of the shell [1/s]
  double damping_de = 0.0;      ///< velocity-proportional damping of the spheres [1/s]
  double skin = 0.0;            ///< DEM neighbour skin [m]; 0 = Rmin / 2
  /// Rigid bodies will strike the spheres (dem::DemSolver::add_body on
  /// de()): the step is also bounded by the Gershgorin bound of the spheres
  /// the multipliers leave free, each with one body contact on top of its
  /// links (dem::critical_time_step with a material), as a DE run with
  /// bodies is. Always so with bars.
  bool body_contacts = false;
};

/// Energy of the coupled system [J]: the FE and DE budgets of each side
/// (weighted masses and energies). The multipliers do work on each side,
/// `multiplier_work_fe` = dt lambda . G_FE v_FE on the shell and exactly the
/// opposite on the particles (the constraint holds after each correction), so
/// each side's imbalance carries it and their sum closes.
struct CoupledEnergy
{
  shell::EnergyBudget fe;
  dem::DemEnergy de;
  double multiplier_work_fe = 0.0;
  double total() const { return fe.kinetic + fe.strain + de.kinetic + de.elastic; }
  double imbalance() const { return fe.imbalance() + de.imbalance(); }
};

/// Wall time spent in each part of the coupled steps so far [s].
struct CoupledTimings
{
  double fe = 0.0;          ///< the shell's kicks, drift and internal forces
  double de = 0.0;          ///< the spheres' kicks, drift, neighbours and forces
  double multipliers = 0.0; ///< the two multiplier corrections per step
};

class CoupledSolver
{
public:
  /// Sets the weights on both sides, locates the particles of the overlap and
  /// factorises the multiplier matrix.
  ///
  /// Ownership: while it lives, the coupler holds the weighted state of the
  /// caller's model, particles and links: the model's weight field (eta),
  /// the particles' masses and inertias (scaled by max(1 - eta, floor)),
  /// `p.weight` and `l.weight`. It gives them back (the masses and inertias
  /// as they were, the weights cleared, the model's field 1) when it is
  /// destroyed, and when its constructor throws. Particles or links that
  /// already carry weights are refused: a second coupler on the same arrays
  /// would weight them twice.
  /// @throws std::runtime_error: particles or links already weighted, no
  ///   particle in the overlap, an overlap outside the FE mesh, a particle in
  ///   no fictive element, bad weights or a time step above the coupled
  ///   estimate.
  CoupledSolver(shell::FEModel& fe, dem::Particles& p, dem::Links& l, const dem::Material& mat,
                const CouplingOptions& o);
  /// The same with reinforcing bars on the DE side (bonded to p: bars.h),
  /// weighted like the spheres and links: node masses max(1 - eta, floor) m,
  /// element forces and energies (1 - eta) at the element's middle (its
  /// area), bending springs at their middle node, bonds by their sphere's
  /// weight (their surface). Bar nodes in the overlap are tied to the FE
  /// motion as the spheres are. The DE solver takes the weighted bars
  /// (de().bars()). The time step is also bounded by the Gershgorin bound
  /// of the spheres and nodes the multipliers leave free (the bars' own
  /// rows are not in the power iteration).
  /// @throws std::runtime_error as above, for bar nodes beyond the overlap
  ///   on the FE side (named with their count and place), and for a bar
  ///   that ends inside the band (it must run on to the band's FE edge).
  CoupledSolver(shell::FEModel& fe, dem::Particles& p, dem::Links& l, const dem::Material& mat,
                const CouplingOptions& o, dem::Bars bars);
  ~CoupledSolver();
  CoupledSolver(const CoupledSolver&) = delete;
  CoupledSolver& operator=(const CoupledSolver&) = delete;

  shell::ExplicitSolver& fe() { return *_fe_solver; }
  dem::DemSolver& de() { return *_de_solver; }

  /// Initial state of the shell (u, v over its dofs; particles keep theirs),
  /// made compatible by one correction, then both sides start.
  void start(std::span<const double> u_fe, std::span<const double> v_fe);
  /// One coupled step; returns the constraint residual after the correction [m/s].
  /// `observed`: the caller reads this step's state (an output frame, the
  /// energy, the residual). When false, what only an observer needs is
  /// skipped:
  ///  - the projection of v(n+1) onto the constraint (a second multiplier
  ///    solve). Without damping the positions do not depend on it -- the
  ///    next half-step velocities are projected anyway, and the projection
  ///    is linear -- so it is then skipped (tested: the same motion to
  ///    1e-12). With damping on either side it is always made: it changes
  ///    the path there (the shell damps with v(n+1/2), the spheres with v(n+1)).
  ///  - the residual's pass over the points: the return value is then the
  ///    residual of the last observed step (0 before any).
  double step(bool observed = true);
  /// After a step(false): projects v(n+1) onto the constraint as an observed
  /// step would have (a run that learns only after its step that it is
  /// over, and reads its state). Positions are not touched; nothing to do
  /// after an observed step.
  void observe();

  double dt() const { return _dt; }
  /// Critical step of the coupled, weighted system [s]: 2 / sqrt(lambda_max)
  /// of its stiffness over its masses on the motions that satisfy the
  /// constraint, by power iteration with the multiplier correction as the
  /// projection (boundary conditions left out, which is on the safe side).
  double dt_coupled() const { return _dt_coupled; }
  double dt_fe() const { return _dt_fe; }  ///< critical step of the FE model alone, unweighted
  double dt_de() const { return _dt_de; }  ///< critical step of the DE assembly alone, unweighted
  std::size_t constrained() const { return _ids.size(); }
  /// The bar nodes tied to the FE motion (those in the overlap).
  std::size_t constrained_bar_nodes() const { return _bar_ids.size(); }
  /// The multipliers of the last correction, 3 per tied point: the
  /// constrained particles, then the tied bar nodes [N].
  std::span<const double> multipliers() const { return _mult->multipliers(); }
  const CouplingOperator& coupling() const { return _op; }
  CoupledEnergy energy() const;
  /// The multipliers' work on the FE side so far [J] (CoupledEnergy::multiplier_work_fe).
  double multiplier_work() const { return _multiplier_energy; }
  const CoupledTimings& timings() const { return _time; }

  /// Writes the coupled state after a step: both sides (groups "shell" and
  /// "dem", as their solvers' save()) and the multipliers' work.
  void save(const checkpoint::Group& g) const;
  /// Reads a state written by save() into a coupler set up as the one that
  /// wrote it (after start()): the run continues bit for bit.
  /// @throws std::runtime_error naming what differs.
  void load(const checkpoint::Group& g);

private:
  // set-up phases of the constructor, in order
  static void validate(const CouplingOptions& o);
  void own_critical_steps();                        // each side's, unweighted
  void weigh_fe(const CouplingOptions& o);          // weight field, FE masses
  void weigh_de(const CouplingOptions& o);          // masses, sphere and link weights
  // no point of x (3 per point) past the band's FE edge: refused naming `what`
  static void refuse_beyond(const Overlap& overlap, std::span<const double> x, const char* what, const char* advice);
  void weigh_bars(const CouplingOptions& o);        // the bars' masses, areas, springs, bonds
  void refuse_ends_in_band(const Overlap& overlap) const; // no bar ends strictly inside the band
  void locate_overlap();                            // G_FE of the overlap's particles and bar nodes
  CouplingOperator locate_points(const std::vector<double>& pts) const;
  void coupled_time_step(const CouplingOptions& o, const dem::Material& mat); // and the step to use
  void give_back() noexcept;                        // the caller's masses and weights
  void correct(bool half_step, bool residual = true);
  shell::FEModel& _model;
  dem::Particles& _p;
  dem::Links& _l;
  std::vector<double> _m_given, _inertia_given; // the caller's masses and inertias
  std::vector<std::int32_t> _ids;  // constrained particles
  dem::Bars _bars;                 // the weighted bars, until the DE solver takes them
  std::vector<std::int32_t> _bar_ids; // constrained bar nodes (their points follow the particles')
  CouplingOperator _op;
  std::vector<double> _m_fe, _m_de, _v_de;
  std::unique_ptr<MultiplierSolver> _mult;
  std::unique_ptr<shell::ExplicitSolver> _fe_solver;
  std::unique_ptr<dem::DemSolver> _de_solver;
  CoupledTimings _time;
  core::EnergyGuard _guard;
  void check_energy() const; // the energy guard
  double _dt = 0.0, _dt_coupled = 0.0, _dt_fe = 0.0, _dt_de = 0.0, _multiplier_energy = 0.0,
         _residual = 0.0;
  bool _projected = true; // v(n+1) projected at the last step
};

} // namespace dembridge::bridge
