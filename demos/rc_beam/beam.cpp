#include "beam.h"
#include "support.h"
#include "time_loop.h"

#include "dembridge/dem/output.h"
#include "dembridge/dem/packing.h"
#include "dembridge/dem/skin.h"
#include "dembridge/dem/solver.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <numbers>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace dembridge::demo
{
using namespace dembridge::dem;
constexpr double pi = std::numbers::pi;

namespace
{
class BeamRun
{
public:
  explicit BeamRun(const BeamConfig& c) : _c(c), _t(beam_theory(c)) {}

  nlohmann::json run()
  {
    build();
    set_up();
    loop();
    report();
    if (!_c.output_dir.empty())
      write_theory_curve(std::filesystem::path(_c.output_dir) / "theory_curve.csv");
    return _out;
  }

private:
  void build()
  {
    const double L = _c.span / 2.0 + _c.overhang;
    const Region region = box_region({-L, -_c.width / 2.0, 0.0}, {L, _c.width / 2.0, _c.height});
    // the bars along the beam, evenly across its width, 10 mm short of its ends
    std::vector<BarLine> lines;
    for (int k = 0; k < _c.bars; ++k)
    {
      const double y = -_c.width / 2.0 + _c.width * (k + 0.5) / _c.bars;
      lines.push_back({{{-L + 0.01, y, _c.cover}, {L - 0.01, y, _c.cover}}, _c.bar_diameter, 0, 0});
    }
    _bars = make_bars(lines, {_c.steel}, {_c.bond}, 2.0 * _c.mean_radius);
    PackingOptions po;
    po.mean_radius = _c.mean_radius;
    po.radius_ratio = _c.radius_ratio;
    po.seed = _c.seed;
    // the dem module's errors name the region; the user's options are these
    std::ostringstream mean_radius;
    mean_radius << _c.mean_radius;
    const std::string opts = "--mean-radius " + mean_radius.str() + " m in the beam (--height, --width, "
                             "--span, --overhang)";
    const ConcretePacking c = with_context(opts, [&] { return pack_around_bars(region, _bars, po); }); // method.md 1.15
    _rmax = *std::max_element(c.packing.r.begin(), c.packing.r.end());
    _p = make_particles(c.packing.x, c.packing.r, _c.material.density, c.solid_fraction);
    _links = create_links(
        _p, with_context(opts, [&] { return lambda_for_bulk_links(region, _p.x, _p.r, _c.links_per_sphere); }),
        _c.material);
    if (_c.skin_compensation)
      // the faces' skin, two Rmax deep, stiffened to the bulk's links per
      // sphere: bending weighs the soft skin by z^2 (docs/method.md 1.13)
      _skin = compensate_skin(_p, _links, region, 2.0 * _rmax);
    _bonds = create_bonds(_bars, _p, 0.5 * _c.mean_radius);
  }

  void set_up()
  {
    const double E = _c.concrete_modulus, rho = _c.material.density;
    const double I = _c.width * std::pow(_c.height, 3) / 12.0, A = _c.width * _c.height;
    const double w1 = std::pow(pi / _c.span, 2) * std::sqrt(E * I / (rho * A));
    _damping = _c.damping > 0.0 ? _c.damping : 0.1 * w1;
    _period = 2.0 * pi / w1;
    _ramp = _c.ramp_time > 0.0 ? _c.ramp_time : 4.0 * 2.0 * pi / w1;
    _target = _c.deflection > 0.0 ? _c.deflection : 2.0 * _t.deflection(_c, _t.p_yield);
    _dt = _c.safety * critical_time_step(_p, _links, _c.material, _bars);
    _solver = std::make_unique<DemSolver>(_p, _links, _c.material, _dt, _damping, 0.5 * _c.mean_radius / 2.0);
    const double band = 1.5 * _rmax, half = _c.span / 2.0, top = _c.height;
    auto at_support = [&](double xs) { return [=](const Point& x) { return x[2] < band && std::abs(x[0] - xs) < band; }; };
    _left = DemSolver::select(_p, at_support(-half), "the left support's spheres");
    _right = DemSolver::select(_p, at_support(half), "the right support's spheres");
    _plate = DemSolver::select(_p, [&](const Point& x) { return x[2] > top - band && std::abs(x[0]) < band; },
                               "the loading plate's spheres");
    _gauge = DemSolver::select(_p, [&](const Point& x) { return x[2] < band && std::abs(x[0]) < band; },
                               "the midspan gauge's spheres");
    auto zero = [](double) { return 0.0; };
    // each support a band of spheres held at rest; hinged, the band turns
    // about its line (y) through its centroid, as a roller bearing lets a
    // beam turn; held, it also clamps the beam's rotation over its width.
    // The left one holds x, the right one lets the beam lengthen.
    ParticleMotion left{"left", _left, MotionKind::velocity, {true, true, true}, zero, _c.hinged_supports};
    ParticleMotion right{"right", _right, MotionKind::velocity, {false, true, true}, zero, _c.hinged_supports};
    if (_c.hinged_supports)
      left.axis = right.axis = {0.0, 1.0, 0.0};
    _solver->add_motion(left);
    _solver->add_motion(right);
    const double v = _c.speed, ramp = _ramp;
    _solver->add_motion({"plate", _plate, MotionKind::velocity, {false, false, true},
                         [=](double t) { return -v * std::min(1.0, t / ramp); }});
    _solver->add_bars(_bars);
    _solver->start();
    cover_strip();
    describe();
  }

  /// The cover's strip: the spheres whose centres lie below the bars' axis
  /// between the supports, the links between them, and its two ends (the
  /// spheres within 2 Rmax of either support line).
  void cover_strip()
  {
    const double half = _c.span / 2.0;
    std::vector<std::int32_t> local(_p.size(), -1);
    std::int32_t n = 0;
    for (std::size_t i = 0; i < _p.size(); ++i)
      if (_p.x0[3 * i + 2] < _c.cover && std::abs(_p.x0[3 * i]) <= half)
      {
        local[i] = n++;
        _strip_x.push_back(_p.x0[3 * i]);
      }
    for (std::size_t k = 0; k < _links.size(); ++k)
      if (local[_links.a[k]] >= 0 && local[_links.b[k]] >= 0)
        _strip_links.push_back(static_cast<std::int32_t>(k));
    _strip_local = std::move(local);
    _strip_joined = !cover_cut().first; // a strip that is not one piece at the start cannot be cut
    if (!_strip_joined)
      std::cerr << "rc_beam: warning: the cover's strip (" << _strip_x.size() << " spheres below the bars' axis, "
                << _strip_links.size()
                << " links) is not one piece before loading: no cracking point can be read (spheres too "
                   "large for the cover?)\n";
  }

  /// A link past its tensile peak (softening, K_n delta_max > S_int T) or
  /// broken: a crack runs through it.
  bool cracked(std::size_t k) const
  {
    if (_links.state[k] != LinkState::intact)
      return true;
    const double strength = _links.strength.empty() ? 1.0 : _links.strength[k];
    return _links.kn[k] * _links.delta_max[k] > link_surface(_p, _links, k) * _c.material.tensile * strength;
  }

  /// Whether a crack has cut the cover's strip: its uncracked links no
  /// longer join the spheres at its left end to those at its right end
  /// (union-find over the strip). Second: where, the furthest x reached
  /// from the left end [m].
  std::pair<bool, double> cover_cut() const
  {
    std::vector<std::int32_t> root(_strip_x.size());
    std::iota(root.begin(), root.end(), 0);
    auto find = [&](std::int32_t i)
    {
      while (root[i] != i)
        i = root[i] = root[root[i]];
      return i;
    };
    for (const std::int32_t k : _strip_links)
      if (!cracked(k))
        root[find(_strip_local[_links.a[k]])] = find(_strip_local[_links.b[k]]);
    const double half = _c.span / 2.0, end = 2.0 * _rmax;
    std::vector<char> left(_strip_x.size(), 0);
    for (std::size_t i = 0; i < _strip_x.size(); ++i)
      if (_strip_x[i] < -half + end)
        left[find(static_cast<std::int32_t>(i))] = 1;
    double reach = -half;
    bool joined = false;
    for (std::size_t i = 0; i < _strip_x.size(); ++i)
      if (left[find(static_cast<std::int32_t>(i))])
      {
        reach = std::max(reach, _strip_x[i]);
        joined = joined || _strip_x[i] > half - end;
      }
    return {!joined, reach};
  }

  void describe()
  {
    _out["particles"] = _p.size();
    _out["links"] = _links.size();
    _out["bar_elements"] = _bars.elements();
    _out["bonds"] = _bonds;
    _out["cover_strip"] = {{"spheres", _strip_x.size()}, {"links", _strip_links.size()}, {"joined", _strip_joined}};
    _out["skin_compensation"] = {{"on", _c.skin_compensation}, {"spheres", _skin.spheres}, {"links", _skin.links},
                                 {"mean_link_factor", _skin.mean_link_factor}};
    _out["dt_s"] = _dt;
    _out["damping_1_s"] = _damping;
    _out["ramp_time_s"] = _ramp;
    _out["target_deflection_m"] = _target;
    _out["theory"] = {{"modular_ratio", _t.n},
                      {"bar_depth_m", _t.d},
                      {"i_uncracked_m4", _t.i_uncracked},
                      {"i_cracked_m4", _t.i_cracked},
                      {"neutral_axis_cracked_m", _t.c_cracked},
                      {"flexural_tensile_strength_pa", _t.f_ct_fl},
                      {"flexural_tensile_strength_ec2_pa", _t.f_ct_fl_ec2},
                      {"cracking_moment_n_m", _t.m_cracking},
                      {"cracking_load_n", _t.p_cracking},
                      {"yield_moment_n_m", _t.m_yield},
                      {"yield_load_n", _t.p_yield}};
    if (_c.quiet)
      return;
    std::cout << "# " << _p.size() << " spheres, " << _links.size() << " links, " << _bars.elements()
              << " bar elements, " << _bonds << " bonds; dt " << _dt << " s, damping " << _damping
              << " /s, ramp " << _ramp << " s\n# theory: cracking load " << _t.p_cracking << " N, first yield "
              << _t.p_yield << " N; loading to " << _target << " m\n"
              << "      time [s]  deflection [m]  load [N]  broken links  bar stress max [Pa]\n";
  }

  double deflection() const
  {
    double s = 0.0;
    for (auto i : _gauge)
      s += _p.x[3 * i + 2] - _p.x0[3 * i + 2];
    return -s / _gauge.size();
  }
  /// The plate's push on the beam, downwards > 0 [N].
  double load() const { return -_solver->reaction("plate")[2]; }
  double bar_stress() const
  {
    double s = 0.0;
    for (std::size_t e = 0; e < _solver->bars().elements(); ++e)
      s = std::max(s, _solver->bars().force[e] / _solver->bars().area[e]);
    return s;
  }
  /// Some bar element has yielded (its plastic strain grew; without
  /// hardening its stress stays at f_y only to round-off).
  bool yielded() const
  {
    const auto& b = _solver->bars();
    return std::any_of(b.alpha.begin(), b.alpha.end(), [](double a) { return a > 0.0; });
  }
  /// Where along the beam a bar yields first: the middle of the element
  /// with the largest plastic strain [m from midspan].
  double yield_section() const
  {
    const auto& b = _solver->bars();
    const auto e = std::max_element(b.alpha.begin(), b.alpha.end()) - b.alpha.begin();
    return 0.5 * (b.x0[3 * b.a[e]] + b.x0[3 * b.b[e]]);
  }
  /// The bars' elements at first yield: the axial force and plastic
  /// strain along each bar.
  void write_bars_at_yield(const std::filesystem::path& file) const
  {
    const auto& b = _solver->bars();
    std::ofstream out(file);
    out << "bar,x_m,axial_force_n,stress_pa,plastic_strain\n" << std::setprecision(10);
    for (std::size_t e = 0; e < b.elements(); ++e)
      out << b.line[e] << "," << 0.5 * (b.x0[3 * b.a[e]] + b.x0[3 * b.b[e]]) << "," << b.force[e] << ","
          << b.force[e] / b.area[e] << "," << b.alpha[e] << "\n";
    out.flush();
    if (!out)
      throw std::runtime_error("writing " + file.string() + " failed (disk full?)");
  }
  /// The forces along the beam (x) across the section x = xs: the bars'
  /// and the concrete links' that cross it (tension > 0), with their mean
  /// heights above the bottom face (reference positions), and the moment
  /// they make, sum N_i (z_ref - z_i) (independent of z_ref when they
  /// balance). The contacts of spheres whose links broke are left out: the
  /// balance says how much they carry.
  nlohmann::json section_forces(double xs) const
  {
    double steel = 0.0, steel_z = 0.0, tension = 0.0, tension_z = 0.0, compression = 0.0, compression_z = 0.0;
    const auto& bars = _solver->bars();
    for (std::size_t e = 0; e < bars.elements(); ++e)
    {
      const std::int32_t a = bars.a[e], b = bars.b[e];
      if ((bars.x[3 * a] - xs) * (bars.x[3 * b] - xs) < 0.0)
      {
        steel += bars.force[e];
        steel_z += bars.force[e] * 0.5 * (bars.x0[3 * a + 2] + bars.x0[3 * b + 2]);
      }
    }
    const LinkLaw base = _c.material.law(1.0, 1.0, 1.0);
    const bool compacting = _c.material.compaction.on() && _links.compaction.size() == _links.size();
    for (std::size_t k = 0; k < _links.size(); ++k)
    {
      const std::int32_t a = _links.a[k], b = _links.b[k];
      const double* xa = &_p.x[3 * a];
      const double* xb = &_p.x[3 * b];
      if (_links.state[k] != LinkState::intact || !((xa[0] - xs) * (xb[0] - xs) < 0.0))
        continue;
      const double d[3] = {xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]};
      const double D = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      // the link's law as the force loop applies it (its K_n, strength
      // factor and compaction set; rc_beam's links carry no weights)
      LinkLaw law = base;
      law.kn = _links.kn[k];
      law.s_int = link_surface(_p, _links, k);
      if (!_links.strength.empty())
        law.tensile *= _links.strength[k];
      double delta = D - _links.d0[k];
      if (compacting)
        delta -= compaction_set(_links.compaction[k], _links.d0[k], link_compaction(_links, k, _c.material.compaction));
      const double fn = link_normal_force(delta, _links.delta_max[k], law).fn;
      // the force on b, -fn n + fs, along x; on the right part's sphere
      double fx = -fn * d[0] / D + _links.fs[3 * k];
      if (xb[0] < xs)
        fx = -fx;
      const double N = -fx, z = 0.5 * (_p.x0[3 * a + 2] + _p.x0[3 * b + 2]);
      (N > 0.0 ? tension : compression) += N;
      (N > 0.0 ? tension_z : compression_z) += N * z;
    }
    const double moment = -(steel_z + tension_z + compression_z); // sum N_i (0 - z_i)
    return {{"x_m", xs},
            {"steel_n", steel},
            {"steel_height_m", steel != 0.0 ? steel_z / steel : 0.0},
            {"concrete_tension_n", tension},
            {"concrete_tension_height_m", tension > 0.0 ? tension_z / tension : 0.0},
            {"concrete_compression_n", compression},
            {"concrete_compression_height_m", compression < 0.0 ? compression_z / compression : 0.0},
            {"balance_n", steel + tension + compression},
            {"internal_moment_n_m", moment}};
  }
  /// Records first yield at this sample: the interval's mean load and the
  /// supports' reactions, the deflection, where, and the forces across that
  /// section (with the load's moment there: none outside the span).
  void first_yield(double load, double left, double right)
  {
    _p_yield_model = load;
    _yield_sample = _load.size(); // the index this sample takes
    _d_yield_model = deflection();
    _x_yield_model = yield_section();
    _yield_forces = section_forces(_x_yield_model);
    const double arm = 0.5 * _c.span - std::abs(_x_yield_model), m_ext = 0.5 * load * arm;
    const bool inside = arm > 0.0 && m_ext > 0.0;
    auto maybe = [](bool ok, double v) { return ok ? nlohmann::json(v) : nlohmann::json(nullptr); };
    _yield_forces["external_moment_n_m"] = maybe(inside, m_ext);
    _yield_forces["moment_ratio"] = maybe(inside, _yield_forces["internal_moment_n_m"].get<double>() / m_ext);
    _yield_forces["left_support_n"] = left;
    _yield_forces["right_support_n"] = right;
    if (!_c.output_dir.empty())
      write_bars_at_yield(std::filesystem::path(_c.output_dir) / "bars_first_yield.csv");
  }

  std::size_t broken() const
  {
    return _links.count(LinkState::broken_tension) + _links.count(LinkState::broken_shear);
  }

  void loop()
  {
    std::unique_ptr<ParticleWriter> pw;
    std::unique_ptr<BarWriter> bw;
    std::ofstream csv;
    const std::filesystem::path dir = _c.output_dir;
    if (!_c.output_dir.empty())
    {
      std::filesystem::create_directories(dir);
      pw = std::make_unique<ParticleWriter>(dir / "particles.xdmf", _links, _p.size(), true);
      bw = std::make_unique<BarWriter>(dir / "bars.xdmf", _solver->bars());
      csv.open(dir / "load_deflection.csv");
      csv << "time_s,deflection_m,load_n,links_broken,bar_stress_max_pa\n";
    }
    const double t_end = _ramp / 2.0 + _target / _c.speed;
    const auto steps = static_cast<std::int64_t>(t_end / _dt);
    const std::int64_t every = std::max<std::int64_t>(1, steps / 1000), frame = std::max<std::int64_t>(1, steps / _c.frames);
    // the load recorded is the plate's reaction averaged over the steps
    // since the last sample, as a load cell averages: sampled once in a
    // while, the reaction would alias the spheres' own vibration under
    // the plate (some 5-15 % of the load while the concrete cracks)
    double load_sum = 0.0, left_sum = 0.0, right_sum = 0.0; // and the supports' upward reactions
    std::int64_t load_steps = 0;
    // the shared time loop (time_loop.h): to the target deflection (at most
    // twice the steps it takes at the plate's speed); a sample every
    // `every` steps, progress every 2 s; the last frame after the loop
    const LoopPlan plan{.done = _solver->steps(),
                        .last = 2 * steps,
                        .rows = {every, false},
                        .frames = {frame, false},
                        .prints = {0, false},
                        .print_seconds = 2.0};
    LoopHooks h = solver_hooks(*_solver);
    h.after_step = [&](std::int64_t)
    {
      load_sum += load();
      left_sum += _solver->reaction("left")[2];
      right_sum += _solver->reaction("right")[2];
      ++load_steps;
    };
    h.finished = [this](std::int64_t) { return deflection() >= _target; };
    if (pw)
      h.frame = [&](std::int64_t, bool)
      {
        pw->write(_solver->time(), _p, _links);
        bw->write(_solver->time(), _solver->bars());
      };
    h.row = [&](std::int64_t, bool)
    {
      // first yield is read at the samples only, with the interval's
      // mean load, so that it does not depend on the progress prints
      const double mean_load = load_sum / static_cast<double>(load_steps);
      if (_p_yield_model == 0.0 && yielded())
        first_yield(mean_load, left_sum / static_cast<double>(load_steps),
                    right_sum / static_cast<double>(load_steps));
      _times.push_back(_solver->time());
      _delta.push_back(deflection());
      _load.push_back(mean_load);
      _supports.push_back((left_sum + right_sum) / static_cast<double>(load_steps));
      if (_strip_joined && _cut_sample < 0)
        if (const auto [cut, x] = cover_cut(); cut)
        {
          _cut_sample = static_cast<std::int64_t>(_load.size()) - 1;
          _cut_x = x;
        }
      load_sum = left_sum = right_sum = 0.0;
      load_steps = 0;
      if (csv.is_open())
        csv << std::setprecision(10) << _solver->time() << "," << _delta.back() << "," << _load.back() << ","
            << broken() << "," << bar_stress() << "\n" << std::flush; // whole rows if the run is killed
    };
    if (!_c.quiet)
      h.progress = [&](std::int64_t, bool)
      {
        std::cout << std::setw(14) << _solver->time() << std::setw(16) << deflection() << std::setw(10)
                  << (_load.empty() ? load() : _load.back()) << std::setw(14) << broken() << std::setw(21)
                  << bar_stress() << std::endl;
      };
    run_time_loop(plan, h);
    if (pw)
    {
      pw->write(_solver->time(), _p, _links);
      bw->write(_solver->time(), _solver->bars());
    }
  }

  /// The cracking point, read on the load averaged over a quarter period of
  /// the first bending mode either side (smoothed_load: the samples carry the beam's
  /// vibration, some 10-20 % of the load once cracks open). The crack is
  /// the first to cut the cover's strip (cover_cut); the peak is the
  /// largest averaged load up to that sample. If the averaged load then
  /// falls by more than 10 % before first yield, the crack formed at once
  /// and the peak is the cracking point. Otherwise the bars carried the
  /// tension while the crack formed, and the load rose on: the crack shows
  /// as the change of slope of the curve up to first yield
  /// (change_of_slope), the point where the section theory's curve turns
  /// from the uncracked to the cracked branch. (10 %: about twice the dips
  /// of the averaged load on curves that do not drop; those that do drop
  /// 25-65 %: validation.md 2.10.)
  /// Without first yield, the fall and the fit run to the last sample; where
  /// the bars yield before the peak, or the fit gives no reading, the peak.
  struct CrackingPoint
  {
    double load = 0.0, deflection = 0.0; ///< 0 if no crack cut the strip
    bool peak = false;                   ///< read at the peak (else at the change of slope)
    double peak_load = 0.0, drop = 0.0;  ///< the peak; the averaged load's largest fall after it, over it
    std::array<double, 2> kink{};        ///< change of slope: deflection, load
  };

  CrackingPoint cracking_point() const
  {
    CrackingPoint c;
    if (_cut_sample < 0)
      return c;
    const std::vector<double> s = smoothed_load();
    const auto top = std::max_element(s.begin(), s.begin() + _cut_sample + 1) - s.begin();
    // the bars may yield before the peak (a beam too lightly reinforced to
    // carry its cracking load): then the peak, where the beam breaks
    const bool has_yield = _p_yield_model > 0.0;
    const bool yield_first = has_yield && _yield_sample <= static_cast<std::size_t>(top);
    const std::size_t last = has_yield && !yield_first ? _yield_sample : s.size() - 1;
    c.peak_load = s[top];
    c.drop = s[top] > 0.0 ? 1.0 - *std::min_element(s.begin() + top, s.begin() + last + 1) / s[top] : 0.0;
    c.kink = change_of_slope(_delta, _load, has_yield ? _d_yield_model : _delta.back());
    c.peak = yield_first || c.drop > 0.1 || c.kink[1] <= 0.0;
    c.load = c.peak ? c.peak_load : c.kink[1];
    c.deflection = c.peak ? _delta[top] : c.kink[0];
    return c;
  }

  /// Each sample's load averaged over the samples within a quarter period
  /// of the first bending mode either side.
  std::vector<double> smoothed_load() const
  {
    std::vector<double> s(_load.size());
    for (std::size_t j = 0; j < _load.size(); ++j)
    {
      const auto [lo, hi] = samples_within(j, 0.25 * _period);
      s[j] = std::accumulate(_load.begin() + lo, _load.begin() + hi, 0.0) / static_cast<double>(hi - lo);
    }
    return s;
  }

  /// The samples within `half` [s] of sample k's time: [first, end) (the
  /// samples' times increase).
  std::array<std::size_t, 2> samples_within(std::size_t k, double half) const
  {
    const auto lo = std::lower_bound(_times.begin(), _times.end(), _times[k] - half);
    const auto hi = std::upper_bound(_times.begin(), _times.end(), _times[k] + half);
    return {static_cast<std::size_t>(lo - _times.begin()), static_cast<std::size_t>(hi - _times.begin())};
  }

  /// The load at first yield, read on a straight line fitted (least
  /// squares) to the load against the deflection over one period of the
  /// first bending mode centred on it (after the cover was cut, if it was
  /// before). Once cracks open, the samples' load carries the beam's
  /// vibration (up to 18 % either way on the 1 m beam): a single sample
  /// reads it wherever the vibration has it, a period's fit averages it
  /// out. With fewer than 3 samples in that window: the sample's own load.
  double yield_load_fitted() const
  {
    const std::size_t k = _yield_sample;
    LineFit fit; // deflections counted from first yield's (conditioning)
    for (std::size_t j : yield_window())
      fit.add(_delta[j] - _delta[k], _load[j]);
    if (fit.n < 3 || !(fit.det() > 1e-12 * fit.n * fit.sxx))
      return _load[k];
    return fit.intercept(); // at first yield's deflection
  }

  /// The samples within half a period of the first bending mode of first
  /// yield, those up to the cover's cut left out if it came before.
  std::vector<std::size_t> yield_window() const
  {
    const std::size_t k = _yield_sample;
    const std::size_t first = _cut_sample >= 0 && static_cast<std::size_t>(_cut_sample) < k ? _cut_sample + 1 : 0;
    const auto [lo, hi] = samples_within(k, 0.5 * _period);
    std::vector<std::size_t> window;
    for (std::size_t j = std::max(lo, first); j < hi; ++j)
      window.push_back(j);
    return window;
  }

  /// The supports' reactions over the load, both summed over the first
  /// yield's window: at any one sample they differ by the beam's inertia
  /// force (its vibration once cracked), whose mean over a period of that
  /// vibration is small; quasi-static equilibrium makes the ratio 1.
  nlohmann::json supports_over_load() const
  {
    double supports = 0.0, load = 0.0;
    for (std::size_t j : yield_window())
    {
      supports += _supports[j];
      load += _load[j];
    }
    return load > 0.0 ? nlohmann::json(supports / load) : nlohmann::json(nullptr);
  }

  /// change_of_slope read on the section theory's own curve, 0 to first
  /// yield (where its cracked branch bends, the fit cuts the corner and
  /// reads below P_cr): the reading's bias on a curve whose kink is known.
  /// (null in the summary where the theory's bars yield before it cracks)
  double theory_change_of_slope() const
  {
    const auto [p, d, d_ts] = theory_curve();
    return change_of_slope(d, p, d.back())[1];
  }

  /// The section theory's loads from 0 to first yield (400 steps) and its
  /// deflections under them, smeared and with tension stiffening.
  std::array<std::vector<double>, 3> theory_curve() const
  {
    std::array<std::vector<double>, 3> c;
    for (int i = 0; i <= 400; ++i)
    {
      c[0].push_back(_t.p_yield * i / 400.0);
      c[1].push_back(_t.deflection(_c, c[0].back()));
      c[2].push_back(_t.deflection(_c, c[0].back(), true));
    }
    return c;
  }

  /// theory_curve, for the plot beside the run's curve.
  void write_theory_curve(const std::filesystem::path& file) const
  {
    const auto [p, d, d_ts] = theory_curve();
    std::ofstream out(file);
    out << "load_n,deflection_m,deflection_tension_stiffening_m\n" << std::setprecision(10);
    for (std::size_t i = 0; i < p.size(); ++i)
      out << p[i] << "," << d[i] << "," << d_ts[i] << "\n";
    out.flush();
    if (!out)
      throw std::runtime_error("cannot write " + file.string());
  }

  void report()
  {
    // initial stiffness: over 10-50 % of the theory's cracking load;
    // cracking: cracking_point(); cracked stiffness: the secant from
    // cracking to first yield (the theory's likewise, between its own
    // cracking and first-yield points)
    const double k0 = slope(_delta, _load, 0.1 * _t.p_cracking, 0.5 * _t.p_cracking);
    const CrackingPoint crack = cracking_point();
    const double p_cr = crack.load, d_cr = crack.deflection;
    // first yield: its deflection, and its load on the fitted line
    const double p_y = _p_yield_model > 0.0 ? yield_load_fitted() : 0.0;
    const double k_cr = _d_yield_model > d_cr && p_cr > 0.0 ? (p_y - p_cr) / (_d_yield_model - d_cr) : 0.0;
    // (0 where the bars yield before the concrete cracks: no cracked branch)
    auto secant = [&](bool ts)
    {
      const double dd = _t.deflection(_c, _t.p_yield, ts) - _t.deflection(_c, _t.p_cracking, ts);
      return _t.p_yield > _t.p_cracking && dd > 0.0 ? (_t.p_yield - _t.p_cracking) / dd : 0.0;
    };
    const double k_cr_theory = secant(false), k_cr_ec2 = secant(true);
    const double k0_theory = 0.1 * _t.p_cracking / _t.deflection(_c, 0.1 * _t.p_cracking);
    const double G = _c.concrete_modulus / (2.0 * (1.0 + _c.concrete_poisson));
    const double k_fully_cracked = 1.0 / (std::pow(_c.span, 3) / (48.0 * _c.concrete_modulus * _t.i_cracked)
                                          + _c.span / (4.0 * 5.0 / 6.0 * G * _c.width * _c.height));
    // a quantity the run did not reach (no crack, no yield: the beam failed
    // otherwise, e.g. in shear, or the deflection stopped short) is null
    auto value = [](double a, bool reached) { return reached ? nlohmann::json(a) : nlohmann::json(nullptr); };
    auto rel = [](double a, double b, bool reached)
    { return reached && b != 0.0 ? nlohmann::json(a / b - 1.0) : nlohmann::json(nullptr); };
    // the cracked stiffness needs both points (it may come out <= 0: a
    // first yield below the cracking peak, after the crack's load drop)
    const bool cracked = p_cr > 0.0, yielded = _p_yield_model > 0.0, both = cracked && yielded && _d_yield_model > d_cr;
    _out["initial_stiffness_n_m"] = k0;
    _out["initial_stiffness_theory_n_m"] = k0_theory;
    _out["cracking_load_n"] = value(p_cr, cracked);
    _out["cracking_load_ec2_theory_n"] = 4.0 * _t.f_ct_fl_ec2 / _t.f_ct_fl * _t.m_cracking / _c.span;
    _out["cracking_deflection_m"] = value(d_cr, cracked);
    _out["cracking_read_at"] = cracked ? nlohmann::json(crack.peak ? "peak" : "change of slope") : nullptr;
    _out["cracking_peak_load_n"] = value(crack.peak_load, cracked);
    _out["cracking_load_drop"] = value(crack.drop, cracked);
    _out["cracking_change_of_slope_load_n"] = value(crack.kink[1], cracked && crack.kink[1] > 0.0);
    _out["cracking_change_of_slope_deflection_m"] = value(crack.kink[0], cracked && crack.kink[1] > 0.0);
    _out["cracking_change_of_slope_theory_n"] = value(theory_change_of_slope(), _t.p_yield > _t.p_cracking);
    _out["cracking_section_x_m"] = value(_cut_x, cracked);
    _out["cracked_stiffness_n_m"] = value(k_cr, both);
    _out["cracked_stiffness_theory_n_m"] = k_cr_theory;
    _out["fully_cracked_stiffness_theory_n_m"] = k_fully_cracked;
    _out["cracked_stiffness_tension_stiffening_theory_n_m"] = k_cr_ec2;
    // the secant from the origin to first yield, P_y / delta_y: the
    // effective stiffness of a cracked member (EI_eff = M_y / phi_y), which
    // needs no cracking point
    const double k_y = yielded && _d_yield_model > 0.0 ? p_y / _d_yield_model : 0.0;
    const double k_y_theory = _t.p_yield / _t.deflection(_c, _t.p_yield);
    _out["yield_secant_stiffness_n_m"] = value(k_y, k_y > 0.0);
    _out["yield_secant_stiffness_theory_n_m"] = k_y_theory;
    _out["yield_load_n"] = value(p_y, yielded);
    _out["yield_load_sample_n"] = value(_p_yield_model, yielded);
    _out["yield_deflection_m"] = value(_d_yield_model, yielded);
    // the theory's first yield at the section where the bars yield, M_y =
    // P (L / 2 - |x|) / 2: the crack that yields first need not be at midspan
    const bool inside = yielded && std::abs(_x_yield_model) < 0.5 * _c.span;
    const double p_yield_there = inside ? 2.0 * _t.m_yield / (_c.span / 2.0 - std::abs(_x_yield_model)) : 0.0;
    _out["yield_section_x_m"] = value(_x_yield_model, yielded);
    _out["yield_load_at_section_theory_n"] = value(p_yield_there, inside);
    if (yielded)
      _yield_forces["supports_over_load"] = supports_over_load();
    _out["yield_section_forces"] = _yield_forces;
    _out["relative_error"] = {{"initial_stiffness", rel(k0, k0_theory, k0 > 0.0)},
                              {"cracking_load", rel(p_cr, _t.p_cracking, cracked)},
                              {"cracked_stiffness", rel(k_cr, k_cr_theory, both)},
                              {"yield_secant_stiffness", rel(k_y, k_y_theory, k_y > 0.0)},
                              {"yield_load", rel(p_y, _t.p_yield, yielded)},
                              {"yield_load_at_section", rel(p_y, p_yield_there, inside)}};
    _out["bars_yielded"] = yielded;
    _out["peak_load_n"] = _load.empty() ? 0.0 : *std::max_element(_load.begin(), _load.end());
    _out["final_deflection_m"] = deflection();
    _out["final_load_n"] = _load.empty() ? load() : _load.back();
    _out["links_broken"] = broken();
    _out["steps"] = _solver->steps();
    const auto e = _solver->energy();
    _out["energy"] = {{"prescribed_work_j", e.prescribed_work}, {"bar_plastic_j", e.bar_plastic},
                      {"bond_slip_j", e.bar_slip}, {"breakage_j", e.breakage}, {"softening_j", e.softening},
                      {"damping_j", e.damping}, {"imbalance_j", e.imbalance()}};
  }

  const BeamConfig& _c;
  BeamTheory _t;
  nlohmann::json _out;
  Bars _bars;
  Particles _p;
  Links _links;
  std::size_t _bonds = 0;
  SkinCompensation _skin;
  double _rmax = 0.0, _dt = 0.0, _damping = 0.0, _ramp = 0.0, _target = 0.0, _p_yield_model = 0.0,
         _d_yield_model = 0.0, _x_yield_model = 0.0;
  std::vector<std::int32_t> _left, _right, _plate, _gauge;
  std::unique_ptr<DemSolver> _solver;
  std::vector<double> _delta, _load, _times;
  std::vector<double> _supports; ///< the supports' upward reactions, summed, at each sample
  std::size_t _yield_sample = 0; ///< the sample at first yield (with _p_yield_model > 0)
  double _period = 0.0;          ///< the first bending mode's period [s]
  // the cover's strip (cover_strip) and the sample where a crack first cut it
  std::vector<std::int32_t> _strip_local, _strip_links;
  std::vector<double> _strip_x;
  bool _strip_joined = false;
  std::int64_t _cut_sample = -1;
  double _cut_x = 0.0;
  nlohmann::json _yield_forces; ///< section_forces at the first yield's section then
};
} // namespace

nlohmann::json run_beam(const BeamConfig& c)
{
  if (!(c.cover > 0.5 * c.bar_diameter && c.cover < c.height - 0.5 * c.bar_diameter))
    throw std::runtime_error("--cover " + std::to_string(c.cover) + " m: the bars' axes must lie more than their radius "
                             + std::to_string(0.5 * c.bar_diameter) + " m inside the beam (height "
                             + std::to_string(c.height) + " m)");
  if (!(c.width / c.bars > c.bar_diameter))
    throw std::runtime_error("--bars " + std::to_string(c.bars) + " of " + std::to_string(c.bar_diameter)
                             + " m do not fit side by side in the width " + std::to_string(c.width) + " m");
  Stopwatch clock;
  auto out = BeamRun(c).run();
  out["wall_s"] = clock.seconds();
  return out;
}

} // namespace dembridge::demo
