// The coupled slab of the impact program (coupled_slab.h): the parts from
// the scenario (bridge/slab.h), the mats cut to the DE region, the shells'
// steel layers, and the coupler (bridge::CoupledSolver) behind the run's
// SlabCoupling interface.
#include "coupled_slab.h"

#include "support.h"

#include "dembridge/bridge/coupled.h"
#include "dembridge/shell/output.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <set>
#include <numbers>
#include <stdexcept>

namespace dembridge::demo
{
namespace
{
using V3 = std::array<double, 3>;

V3 lerp(const V3& a, const V3& b, double u)
{
  return {a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1]), a[2] + u * (b[2] - a[2])};
}

double length(const V3& a, const V3& b)
{
  return std::sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) + (b[2] - a[2]) * (b[2] - a[2]));
}

/// The part of segment [a, b] where dist <= limit, as parameters [u0, u1]
/// (u0 > u1: none). The distance to a convex core is convex along a line,
/// so that part is one interval: found by sampling, its ends by bisection.
std::pair<double, double> inside_part(const V3& a, const V3& b, const std::function<double(const V3&)>& dist,
                                      double limit)
{
  constexpr int samples = 512;
  int first = -1, last = -1;
  for (int k = 0; k <= samples; ++k)
    if (dist(lerp(a, b, double(k) / samples)) <= limit)
    {
      if (first < 0)
        first = k;
      last = k;
    }
  if (first < 0)
    return {1.0, 0.0};
  auto edge = [&](double in, double out)
  {
    for (int it = 0; it < 60; ++it)
    {
      const double mid = 0.5 * (in + out);
      (dist(lerp(a, b, mid)) <= limit ? in : out) = mid;
    }
    return in;
  };
  const double u0 = first == 0 ? 0.0 : edge(double(first) / samples, double(first - 1) / samples);
  const double u1 = last == samples ? 1.0 : edge(double(last) / samples, double(last + 1) / samples);
  return {u0, u1};
}

/// The coupled slab: its parts at construction (before any packing), the
/// shells and the coupler in couple().
class CoupledSlab final : public SlabCoupling
{
public:
  explicit CoupledSlab(const Scenario& s)
    : _s(s), _spec(slab_spec(s)), _overlap(bridge::slab_overlap(_spec)), _region(bridge::slab_de_region(_spec))
  {
    warn_path();
    check_points();
    check_pulse();
  }

  const dem::Region& de_region() const override { return _region; }

  /// The mats' bars cut where they leave the band (at its outer edge less a
  /// millionth of it, so that no node lies beyond); a piece shorter than one
  /// bar element is left to the shells. Polylines must lie in the core.
  std::vector<dem::BarLine> cut_bars(const std::vector<dem::BarLine>& lines) const override
  {
    const std::size_t mats = mat_lines(_s).size(); // bar_lines: the mats', then the polylines
    const double h = _s.reinforcement.element_length > 0.0 ? _s.reinforcement.element_length
                                                           : 2.0 * _s.target.mean_radius;
    const auto dist = [this](const V3& x) { return _overlap.distance(x); };
    std::vector<dem::BarLine> out;
    for (std::size_t q = 0; q < lines.size(); ++q)
    {
      const auto& pts = lines[q].points;
      if (q >= mats)
      {
        for (const auto& x : pts)
          if (dist(x) > 0.0)
            throw std::runtime_error("reinforcement.bars_m: bar " + std::to_string(q - mats) + " reaches ("
                                     + number_text(x[0]) + ", " + number_text(x[1]) + ", " + number_text(x[2])
                                     + ") m, outside the DE core (" + _overlap.what() + "): with shells.model = "
                                     "\"coupled\" a polyline must lie in the core (it would end in the overlap or "
                                     "in the shells, which carry the mats only)");
        out.push_back(lines[q]);
        continue;
      }
      const auto [u0, u1] = inside_part(pts[0], pts[1], dist, _spec.band * (1.0 - 1e-6));
      const V3 a = lerp(pts[0], pts[1], u0), b = lerp(pts[0], pts[1], u1);
      if (u1 <= u0 || length(a, b) < h)
        continue;
      dem::BarLine cut = lines[q];
      cut.points = {a, b};
      out.push_back(cut);
    }
    return out;
  }

  dem::DemSolver& couple(dem::Particles& p, dem::Links& l, const dem::Material& mat, dem::Bars bars,
                         const CouplingStep& step) override
  {
    Stopwatch clock;
    _fe = std::make_unique<shell::FEModel>(bridge::slab_shells(MPI_COMM_WORLD, _spec), shell_material(_s));
    bridge::check_slab_shells(*_fe, _spec); // Gmsh's mesh fits the core (a guard: it does by construction)
    if (_s.reinforcement.layers > 0)
      _fe->set_reinforcement(shell_steel(_s, _fe->nodal_normals()[2] >= 0.0 ? 1.0 : -1.0));
    // before the coupler, whose step counts them
    _frame_nodes = bridge::slab_frame_springs(*_fe, _spec, _fe->material().youngs_modulus);
    bridge::CouplingOptions o;
    o.overlap = _overlap;
    o.weight_floor = _s.shells.weight_floor;
    o.dt = step.dt;
    o.safety = step.safety; // checked by slab_spec: at most 0.95
    o.damping_de = step.damping;
    o.damping_fe = step.damping; // the shells as the spheres (and as the all-shell slab's)
    o.skin = step.skin;
    o.body_contacts = true;
    try
    {
      _cs = bars.nodes() > 0 ? std::make_unique<bridge::CoupledSolver>(*_fe, p, l, mat, o, std::move(bars))
                             : std::make_unique<bridge::CoupledSolver>(*_fe, p, l, mat, o);
    }
    catch (const std::exception& e)
    {
      throw std::runtime_error(std::string("the coupled slab (shells.*, run.dt_s, run.safety_factor): ") + e.what());
    }
    _points = std::make_unique<ShellPoints>(*_fe, _s);
    _supports = bridge::slab_support_dofs(*_fe, _spec);
    if (!_supports.empty())
      _cs->fe().add_motion({"supports", _supports, shell::MotionKind::fixed, {}});
    _setup_s = clock.seconds();
    return _cs->de();
  }

  double dt() const override { return _cs->dt(); }
  double dt_critical() const override { return _cs->dt_coupled(); }

  void start() override
  {
    const std::vector<double> zero(_fe->num_dofs(), 0.0);
    _cs->start(zero, zero);
  }

  void observe() override { _cs->observe(); }

  double step(bool observed) override
  {
    const double r = _cs->step(observed);
    _worst = std::max(_worst, r);
    return r;
  }

  ShellsEnergy energy() const override
  {
    const auto e = _cs->fe().energy(); // the shells' side only: the spheres' budget is the run's
    return {e.kinetic, e.strain, e.imbalance(), _cs->multiplier_work()};
  }

  double max_deflection() const override { return demo::max_deflection(*_fe, _cs->fe().u()); }
  double support_reaction() const override
  {
    return demo::support_reaction(*_fe, _cs->fe().reactions(), _cs->fe().u());
  }

  std::vector<double> point_deflections() const override { return _points->deflections(_cs->fe().u()); }

  void open_output(const std::filesystem::path& dir, const checkpoint::Group* root) override
  {
    const auto file = dir / "shell.xdmf";
    _writer = root ? std::make_unique<shell::XdmfWriter>(*_fe, file, root->group("shell_xdmf"))
                   : std::make_unique<shell::XdmfWriter>(*_fe, file);
  }

  void write_frame() override { _writer->write(_cs->fe().time(), _cs->fe().u(), _cs->fe().v()); }
  void close_output() override
  {
    if (_writer)
      _writer->close();
  }

  void save(const checkpoint::Group& g) const override
  {
    _cs->save(g.group("coupled"));
    g.write("worst_residual", _worst);
    if (_writer)
      _writer->save(g.group("shell_xdmf"));
  }

  void load(const checkpoint::Group& g) override
  {
    _cs->load(g.group("coupled"));
    _worst = g.read_double("worst_residual");
  }

  nlohmann::json describe() const override
  {
    const char* edges[] = {"free", "simply-supported", "clamped", "frame"};
    return {{"core", _overlap.what()},
            {"band_m", _spec.band},
            {"element_size_m", _spec.element_size},
            {"outer_element_size_m", _spec.outer_element_size > 0.0 ? _spec.outer_element_size : _spec.element_size},
            {"edges", edges[static_cast<int>(_spec.edges)]},
            {"shell_nodes", _fe->num_nodes()},
            {"shell_cells", _fe->num_cells()},
            {"supported_shell_dofs", _supports.size()},
            {"frame_nodes", _frame_nodes},
            {"constrained_particles", _cs->constrained()},
            {"constrained_bar_nodes", _cs->constrained_bar_nodes()},
            {"dt_coupled_s", _cs->dt_coupled()},
            {"dt_fe_s", _cs->dt_fe()},
            {"dt_de_s", _cs->dt_de()},
            {"shell_setup_s", _setup_s}};
  }

  nlohmann::json report() const override
  {
    const auto& t = _cs->timings();
    const auto e = _cs->energy();
    const double all = t.de + t.fe + t.multipliers;
    return {{"max_constraint_residual_m_s", _worst},
            {"multiplier_work_j", e.multiplier_work_fe},
            {"shell_kinetic_j", e.fe.kinetic},
            {"shell_strain_j", e.fe.strain},
            {"shell_max_deflection_m", max_deflection()},
            {"step_time_s", {{"de", t.de}, {"shells", t.fe}, {"multipliers", t.multipliers}}},
            {"shells_and_bridge_share", all > 0.0 ? (t.fe + t.multipliers) / all : 0.0}};
  }

private:
  /// shells.deflection_points_m on the shells: not in the core (no shell
  /// there; points outside the plan were refused with the scenario).
  void check_points() const
  {
    const auto& pts = _s.shells.deflection_points;
    for (std::size_t q = 0; q < pts.size(); ++q)
    {
      const auto& x = pts[q];
      const std::string at = "shells.deflection_points_m: point " + std::to_string(q) + " (" + number_text(x[0])
                             + ", " + number_text(x[1]) + ") m ";
      if (_overlap.distance({x[0], x[1], -0.5 * _spec.thickness}) < 0.0)
        throw std::runtime_error(at + "lies in the DE core (" + _overlap.what() + "): no shell there");
    }
  }

  /// A pulse's disc must lie in the core (the shells and the band's
  /// spheres carry no load of their own).
  void check_pulse() const
  {
    if (!_s.pulse.any())
      return;
    const double r = _s.pulse.radius > 0.0 ? _s.pulse.radius : 0.5 * _s.projectile.diameter;
    const double reach = _spec.core == bridge::SlabSpec::Core::box ? std::min(_spec.core_half[0], _spec.core_half[1])
                                                                   : _spec.core_radius;
    if (r > reach)
      throw std::runtime_error(pulse_radius_text(_s) + ": the loaded disc reaches beyond the DE core ("
                               + _overlap.what() + "): load the core only (a smaller disc, or a larger core)");
  }

  /// The projectile's path should stay in the core through the thickness
  /// (with obliquity it drifts along x): else the shells meet it.
  void warn_path() const
  {
    const ProjectileSpec& q = _s.projectile;
    const double drift = _s.target.thickness * std::tan(q.obliquity_deg * std::numbers::pi / 180.0);
    const double reach = _spec.core == bridge::SlabSpec::Core::box ? _spec.core_half[0] : _spec.core_radius;
    const double across = _spec.core == bridge::SlabSpec::Core::box ? _spec.core_half[1] : _spec.core_radius;
    if (0.5 * q.diameter + drift > reach || 0.5 * q.diameter > across)
      std::cerr << "warning: the projectile's path (radius " << number_text(0.5 * q.diameter) << " m, drifting "
                << number_text(drift) << " m along x through the thickness) leaves the DE core ("
                << _overlap.what() << "): it will strike the overlap or the shells, which do not fracture"
                << std::endl;
  }

  const Scenario& _s;
  bridge::SlabSpec _spec;
  bridge::Overlap _overlap;
  dem::Region _region;
  std::unique_ptr<shell::FEModel> _fe;
  std::unique_ptr<bridge::CoupledSolver> _cs;
  std::vector<std::int32_t> _supports;
  std::size_t _frame_nodes = 0; // shell nodes on the frame (Edges::frame)
  std::unique_ptr<ShellPoints> _points; // shells.deflection_points_m
  std::unique_ptr<shell::XdmfWriter> _writer;
  double _setup_s = 0.0, _worst = 0.0;
};

} // namespace

bridge::SlabSpec slab_plan(const Scenario& s)
{
  const ShellSpec& sh = s.shells;
  const TargetSpec& t = s.target;
  bridge::SlabSpec sp;
  sp.size = t.size;
  sp.thickness = t.thickness;
  sp.centre = s.projectile.aim;
  sp.band = sh.band > 0.0 ? sh.band : 8.0 * t.mean_radius;
  sp.element_size = sh.element_size > 0.0 ? sh.element_size : 0.5 * sp.band;
  sp.outer_element_size = sh.outer_element_size;
  sp.cell = sh.cell == "triangle" ? shell::Cell::triangle : shell::Cell::quadrilateral;
  const std::string edges = !sh.edges.empty()             ? sh.edges
                            : t.supports == "sides"       ? "clamped"
                            : t.supports == "rear-edges" ? "simply-supported"
                            : t.supports == "frame"      ? "frame"
                                                          : "free";
  sp.edges = edges == "clamped"            ? bridge::SlabSpec::Edges::clamped
             : edges == "simply-supported" ? bridge::SlabSpec::Edges::simply_supported
             : edges == "frame"            ? bridge::SlabSpec::Edges::frame
                                           : bridge::SlabSpec::Edges::free;
  sp.frame_width = t.support_width;
  return sp;
}

bridge::SlabSpec slab_spec(const Scenario& s)
{
  const ShellSpec& sh = s.shells;
  bridge::SlabSpec sp = slab_plan(s);
  if (sh.core == "box")
  {
    sp.core = bridge::SlabSpec::Core::box;
    if (!(sh.core_size[0] > 0.0 && sh.core_size[1] > 0.0))
      throw std::runtime_error("shells.core_size_m = [" + number_text(sh.core_size[0]) + ", "
                               + number_text(sh.core_size[1]) + "]: give the box core's sizes (> 0 m) with "
                               "shells.model = \"coupled\"");
    sp.core_half = {0.5 * sh.core_size[0], 0.5 * sh.core_size[1]};
  }
  else
  {
    sp.core = bridge::SlabSpec::Core::cylinder;
    if (!(sh.core_radius > 0.0))
      throw std::runtime_error("shells.core_radius_m = 0: give the cylinder core's radius (> 0 m) with "
                               "shells.model = \"coupled\"");
    sp.core_radius = sh.core_radius;
  }
  // the coupled step is a power-iteration estimate from below, stable at
  // 0.97 of it (bridge::CouplingOptions::safety): the coupler allows 0.95
  if (s.run.safety > 0.95)
    throw std::runtime_error("run.safety_factor = " + number_text(s.run.safety) + ": with shells.model = "
                             "\"coupled\" allowed (0, 0.95] (the coupled critical step is an estimate from below)");
  try
  {
    sp.validate();
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(std::string("shells: ") + e.what() + " (target.size_m, projectile.aim_m: the core's "
                             "centre, shells.core_radius_m or core_size_m, band_m, element_size_m)");
  }
  return sp;
}

shell::Material shell_material(const Scenario& s)
{
  const dem::Material& m = s.material.material;
  shell::Material sm;
  sm.youngs_modulus = m.youngs_modulus;
  sm.poisson_ratio = m.poisson_ratio;
  sm.density = m.density;
  sm.thickness = s.target.thickness;
  return sm;
}

shell::Reinforcement shell_steel(const Scenario& s, double normal_z)
{
  const ReinforcementSpec& b = s.reinforcement;
  shell::Reinforcement r;
  r.youngs_modulus = b.steel.youngs_modulus;
  r.density = b.steel.density;
  r.direction = {1.0, 0.0, 0.0};
  std::set<std::pair<int, double>> seen; // (direction, z) of each layer
  for (const auto& line : mat_lines(s))
  {
    const auto& a = line.points[0];
    const auto& c = line.points[1];
    const int dir = std::abs(c[0] - a[0]) > std::abs(c[1] - a[1]) ? 0 : 1;
    if (seen.insert({dir, a[2]}).second)
      r.layers.push_back({dir, b.bar_diameter, b.spacing[dir], normal_z * (a[2] + 0.5 * s.target.thickness)});
  }
  return r;
}

std::unique_ptr<SlabCoupling> make_slab_coupling(const Scenario& s) { return std::make_unique<CoupledSlab>(s); }

double max_deflection(const shell::FEModel& fe, std::span<const double> u)
{
  double w = 0.0;
  for (std::size_t k = 0; k < fe.num_nodes(); ++k)
    w = std::max(w, std::abs(u[fe.block_size() * k + 2]));
  return w;
}

double support_reaction(const shell::FEModel& fe, std::span<const double> r, std::span<const double> u)
{
  double f = fe.support_spring_force(u);
  for (std::size_t k = 0; k < fe.num_nodes(); ++k)
    f += r[fe.block_size() * k + 2];
  return f;
}

ShellPoints::ShellPoints(const shell::FEModel& fe, const Scenario& s)
  : _n(s.shells.deflection_points.size()), _dofs(fe.num_dofs()), _component(s.pulse.in_plane() ? 0 : 2)
{
  if (_n == 0)
    return;
  // (points outside the slab's plan were refused when the scenario was read)
  const double h = s.target.thickness;
  std::vector<double> pts;
  for (const auto& p : s.shells.deflection_points)
    pts.insert(pts.end(), {p[0], p[1], -0.5 * h});
  const bridge::ShellGeometry g{fe.node_coordinates(), fe.nodal_normals(), fe.cell_nodes(), fe.nodes_per_cell(), h};
  _op = std::make_unique<bridge::CouplingOperator>(bridge::locate(g, pts));
}

std::vector<double> ShellPoints::deflections(std::span<const double> u) const
{
  std::vector<double> v(3 * _n), w(_n);
  if (_n == 0)
    return w;
  if (u.size() != _dofs)
    throw std::runtime_error("ShellPoints: " + std::to_string(u.size()) + " dof values for shells of "
                             + std::to_string(_dofs));
  _op->interpolate(u, v);
  for (std::size_t q = 0; q < _n; ++q)
    w[q] = v[3 * q + _component];
  return w;
}

} // namespace dembridge::demo
