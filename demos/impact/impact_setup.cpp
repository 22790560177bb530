// The impact run's set-up (impact_run.h): the slab's spheres and links, or
// the coupled slab's core and band, its bars, the projectile, the supports
// and the solver.
#include "impact_run.h"
#include "support.h"

#include "dembridge/dem/skin.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace dembridge::demo::impl
{

void ImpactRun::build_target()
{
  const TargetSpec& t = _s.target;
  _lo = {-0.5 * t.size[0], -0.5 * t.size[1], -t.thickness};
  _hi = {0.5 * t.size[0], 0.5 * t.size[1], 0.0};
  const Region region = _coupling ? _coupling->de_region() : box_region(_lo, _hi);
  if (_s.reinforcement.any())
    make_the_bars();
  // the dem module's errors name the region; the user's keys are these
  const std::string keys = "target.mean_radius_m = " + fmt(t.mean_radius) + " m in the slab (target.size_m ["
                           + fmt(t.size[0]) + ", " + fmt(t.size[1]) + "] m, thickness_m " + fmt(t.thickness)
                           + " m)";
  if (!t.packing_file.empty())
    _pk = read_target_packing(region);
  else
    _pk = with_context(keys, [&] { return pack(region); });
  if (_pk.size() == 0)
    throw std::runtime_error("target: no sphere in the slab (target.mean_radius_m " + fmt(t.mean_radius)
                             + " m against its size): use smaller spheres");
  // a packing file's spheres that overlap a bar are left out (a generated
  // packing was made around the bars: pack_around_bars), unless the bars
  // are embedded; the solid fraction is then taken over the spheres kept
  if (bars() && !_s.reinforcement.embedded && !t.packing_file.empty())
    clear_bars(_pk.x, _pk.r);
  _fraction = concrete_fraction(_pk, region, _bars); // over the slab's volume less the bars'
  const Material& mat = _s.material.material;
  _p = make_particles(_pk.x, _pk.r, mat.density, _fraction);
  const auto bulk = with_context(keys, [&] { return bulk_spheres(region, _p.x, _p.r); });
  _lambda = lambda_for_mean_links(_p.x, _p.r, _s.material.links_per_sphere, bulk);
  _links = create_links(_p, _lambda, mat);
  if (t.skin_compensation)
  {
    // the slab's faces (not the coupled core's band, which the shells continue)
    const double depth = 2.0 * *std::max_element(_p.r.begin(), _p.r.end());
    const auto skin = compensate_skin(_p, _links, box_region(_lo, _hi), depth);
    _out["skin_compensation"] = {{"spheres", skin.spheres}, {"links", skin.links}, {"bulk_links", skin.bulk_links},
                                 {"mean_link_factor", skin.mean_link_factor}};
  }
  if (bars())
    _bonds = create_bonds(_bars, _p, _s.reinforcement.bond_reach > 0.0 ? _s.reinforcement.bond_reach
                                                                       : 0.5 * mean(_p.r));
  describe_bars();
  _rmax = *std::max_element(_p.r.begin(), _p.r.end());
  _rmin = *std::min_element(_p.r.begin(), _p.r.end());
  _initial_links.assign(_p.size(), 0);
  for (std::size_t k = 0; k < _links.size(); ++k)
  {
    ++_initial_links[_links.a[k]];
    ++_initial_links[_links.b[k]];
  }
}

Packing ImpactRun::pack(const Region& region) const
{
  const TargetSpec& t = _s.target;
  PackingOptions po;
  po.mean_radius = t.mean_radius;
  po.radius_ratio = t.radius_ratio;
  po.seed = t.seed;
  if (t.fine())
    po.size_scale = fine_scale(_s);
  if (!_cfg.quiet)
  {
    std::cout << "packing the slab (" << fmt(region.volume) << " m^3, mean radius " << t.mean_radius << " m";
    if (t.fine())
      std::cout << ", " << t.fine_mean() << " m within " << t.fine_radius << " m of the path";
    std::cout << ")..." << std::endl;
  }
  if (!bars() || _s.reinforcement.embedded)
    return generate_packing(region, po);
  ConcretePacking c = pack_around_bars(region, _bars, po);
  if (!_cfg.quiet)
    std::cout << "the bars' room: " << c.removed << " spheres removed, " << c.added << " added against the bars"
              << std::endl;
  return std::move(c.packing);
}

void ImpactRun::make_the_bars()
{
  const ReinforcementSpec& b = _s.reinforcement;
  const double h = b.element_length > 0.0 ? b.element_length : 2.0 * _s.target.mean_radius;
  try
  {
    const auto lines = _coupling ? _coupling->cut_bars(bar_lines(_s)) : bar_lines(_s);
    if (lines.empty())
      return; // the mats lie beyond the DE region: the shells carry them
    _bars = make_bars(lines, {b.steel}, {b.bond}, h);
    _has_bars = true;
    _bars.sphere_contacts = !b.embedded;
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(std::string("reinforcement: ") + e.what());
  }
}

void ImpactRun::clear_bars(std::vector<double>& x, std::vector<double>& r)
{
  const double rmin = *std::min_element(r.begin(), r.end());
  const auto on = spheres_on_bars(_bars, x, r, 1e-3 * rmin);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < r.size(); ++i)
    if (!on[i])
    {
      for (int k = 0; k < 3; ++k)
        x[3 * kept + k] = x[3 * i + k];
      r[kept++] = r[i];
    }
  _spheres_on_bars = r.size() - kept;
  x.resize(3 * kept);
  r.resize(kept);
}

Packing ImpactRun::read_target_packing(const Region& region) const
{
  Packing pk = read_packing(_s.target.packing_file);
  std::size_t outside = 0;
  for (std::size_t i = 0; i < pk.size(); ++i)
    if (region.sdf({pk.x[3 * i], pk.x[3 * i + 1], pk.x[3 * i + 2]}) > 0.0)
      ++outside;
  if (pk.size() == 0 || outside == pk.size())
    throw std::runtime_error("target.packing_file " + _s.target.packing_file + ": no sphere in the slab ["
                             + fmt(_lo[0]) + ", " + fmt(_hi[0]) + "] x [" + fmt(_lo[1]) + ", " + fmt(_hi[1])
                             + "] x [" + fmt(_lo[2]) + ", 0] m");
  if (outside > 0)
    throw std::runtime_error("target.packing_file " + _s.target.packing_file + ": " + std::to_string(outside) + " of "
                             + std::to_string(pk.size()) + " spheres are centred outside the slab (size_m, "
                             "thickness_m): not this slab's packing");
  check_packing_fits(region, pk, "target.packing_file " + _s.target.packing_file);
  return pk;
}

void ImpactRun::build_projectile()
{
  const ProjectileSpec& q = _s.projectile;
  _dir = path_direction(q);
  if (pulsed())
    return; // the pulse loads the slab in its place
  const Shape sh = projectile_shape(q); // checked when the scenario was read
  const V3 aim{q.aim[0], q.aim[1], 0.0};
  const V3 tip{aim[0] - q.standoff * _dir[0], aim[1], aim[2] - q.standoff * _dir[2]};
  const double density = q.mass > 0.0 ? q.mass / sh.volume() : q.density;
  RigidBody b = make_projectile("projectile", sh, density, tip, _dir,
                                {q.velocity * _dir[0], q.velocity * _dir[1], q.velocity * _dir[2]});
  b.friction = q.friction;
  _shape = sh;
  // no sphere may overlap the projectile at the start
  for (std::size_t i = 0; i < _p.size(); ++i)
  {
    const auto d = signed_distance(sh, b.to_body({_p.x[3 * i], _p.x[3 * i + 1], _p.x[3 * i + 2]}));
    if (d.d < _p.r[i])
      throw std::runtime_error("projectile: it overlaps the target at the start (a sphere at (" + fmt(_p.x[3 * i]) + ", "
                               + fmt(_p.x[3 * i + 1]) + ", " + fmt(_p.x[3 * i + 2]) + ") m is "
                               + fmt(_p.r[i] - d.d) + " m into it): increase projectile.standoff_m or move "
                               "projectile.aim_m");
  }
  _body = b;
  _ke0 = b.kinetic_energy();
}

void ImpactRun::set_up_solver()
{
  const RunSpec& run = _s.run;
  const Material& mat = _s.material.material;
  const double skin = run.skin > 0.0 ? run.skin : 0.5 * _rmin;
  if (_coupling)
  {
    _masses = _p.m; // as built: the coupler weights them in the overlap
    _solver = &_coupling->couple(_p, _links, mat, std::move(_bars), {run.dt, run.safety, run.damping, skin});
    _dt_crit = _coupling->dt_critical();
    _dt = _coupling->dt();
  }
  else
  {
    _dt_crit = bars() ? critical_time_step(_p, _links, mat, _bars) : critical_time_step(_p, _links, mat);
    if (run.dt > _dt_crit)
      throw std::runtime_error("run.dt_s = " + fmt(run.dt) + " s is above the critical time step " + fmt(_dt_crit)
                               + " s (links, projectile contact and bars): give a smaller one, or 0 for "
                                 "safety_factor x critical");
    _dt = run.dt > 0.0 ? run.dt : run.safety * _dt_crit;
    _own_solver = std::make_unique<DemSolver>(_p, _links, mat, _dt, run.damping, skin);
    _solver = _own_solver.get();
    set_up_supports();
  }
  const ProjectileSpec& q = _s.projectile;
  // the time to cross the slab at the striking speed sets the output's
  // pace; the run goes on for up to 4 x that, unless decided earlier (a
  // pulse: its run's duration, given)
  _crossing = pulsed() ? run.duration : (q.standoff + _s.target.thickness / std::abs(_dir[2]) + q.length) / q.velocity;
  _duration = run.duration > 0.0 ? run.duration : 4.0 * _crossing;
  _nsteps = static_cast<std::int64_t>(std::ceil(_duration / _dt));
  _crossing_steps = std::max<std::int64_t>(1, static_cast<std::int64_t>(_crossing / _dt));
  const double margin = run.domain_margin > 0.0 ? run.domain_margin : _s.target.thickness;
  _solver->set_domain({_lo[0] - margin, _lo[1] - margin, _lo[2] - margin},
                      {_hi[0] + margin, _hi[1] + margin, _hi[2] + margin});
  if (pulsed())
    set_up_pulse();
  else
    _solver->add_body(_body);
  if (!_coupling && _s.target.supports == "frame")
    add_frame();
  if (!_coupling)
    locate_points();
  if (!_s.shells.deflection_points.empty())
    _track = std::make_unique<DeflectionTrack>(_s.shells.deflection_points,
                                               pulsed() ? _s.pulse.duration : std::numeric_limits<double>::infinity());
  if (_coupling)
    _coupling->start(); // both sides, the bars given to the coupler
  else
  {
    if (bars())
      _solver->add_bars(_bars);
    _solver->start();
  }
  _history_every = run.history_every > 0 ? run.history_every : std::max<std::int64_t>(1, _crossing_steps / 250);
}

void ImpactRun::set_up_pulse()
{
  const PulseSpec& pu = _s.pulse;
  const double radius = pu.radius > 0.0 ? pu.radius : 0.5 * _s.projectile.diameter;
  const auto& aim = _s.projectile.aim;
  for (std::size_t i = 0; i < _p.size(); ++i)
  {
    const double* x = &_p.x[3 * i];
    if (std::hypot(x[0] - aim[0], x[1] - aim[1]) <= radius && (pu.in_plane() || x[2] + _p.r[i] >= -_rmin))
      _loaded.push_back(static_cast<std::int32_t>(i));
  }
  if (_loaded.empty())
    throw std::runtime_error(pulse_radius_text(_s) + ": no sphere " + (pu.in_plane() ? "" : "of the struck face ")
                             + "is centred within it of projectile.aim_m; give a larger disc");
  // (a coupled slab's disc lies in its core: CoupledSlab::check_pulse)
  const double share = 1.0 / static_cast<double>(_loaded.size());
  const V3 along = pu.in_plane() ? V3{1.0, 0.0, 0.0} : V3{0.0, 0.0, -1.0};
  _solver->add_force({"pulse", _loaded, along, [pu, share](double t) { return share * pu.force(t); }});
}

void ImpactRun::locate_points()
{
  const double reach = 2.0 * _s.target.mean_radius;
  for (const auto& pt : _s.shells.deflection_points)
  {
    std::vector<std::int32_t> ids;
    for (std::size_t i = 0; i < _p.size(); ++i)
      if (std::hypot(_p.x[3 * i] - pt[0], _p.x[3 * i + 1] - pt[1]) <= reach)
        ids.push_back(static_cast<std::int32_t>(i));
    if (ids.empty())
      throw std::runtime_error("shells.deflection_points_m: no sphere is centred within 2 mean radii (" + fmt(reach)
                               + " m) of (" + fmt(pt[0]) + ", " + fmt(pt[1]) + ") m: a point outside the slab?");
    _point_spheres.push_back(std::move(ids));
  }
}

std::vector<double> ImpactRun::point_deflections() const
{
  if (_coupling)
    return _coupling->point_deflections();
  std::vector<double> w;
  const int c = _s.pulse.in_plane() ? 0 : 2; // u_z, or u_x under an in-plane pulse
  for (const auto& ids : _point_spheres)
  {
    double mu = 0.0, m = 0.0;
    for (auto i : ids)
    {
      mu += _p.m[i] * (_p.x[3 * i + c] - _p.x0[3 * i + c]);
      m += _p.m[i];
    }
    w.push_back(mu / m);
  }
  return w;
}

void ImpactRun::set_up_supports()
{
  const TargetSpec& t = _s.target;
  if (t.supports == "none" || t.supports == "frame")
    return;
  const double w = t.support_width > 0.0 ? t.support_width : 2.0 * _rmax;
  const V3 lo = _lo, hi = _hi;
  auto near_side = [=](const V3& x)
  { return x[0] < lo[0] + w || x[0] > hi[0] - w || x[1] < lo[1] + w || x[1] > hi[1] - w; };
  std::vector<std::int32_t> ids;
  if (t.supports == "sides")
    ids = DemSolver::select(_p, near_side, "target.supports = \"sides\": the lateral faces' band (support_width_m)");
  else
    ids = DemSolver::select(_p, [&](const V3& x) { return x[2] < lo[2] + w && near_side(x); },
                            "target.supports = \"rear-edges\": the rear face's edge band (support_width_m)");
  _supported = ids.size();
  _solver->add_motion({"supports", std::move(ids), MotionKind::fixed, {true, true, true}, {}});
}

void ImpactRun::add_frame()
{
  const double w = _s.target.support_width, depth = _s.target.thickness;
  const V3 lo = _lo, hi = _hi;
  // the strips along x whole, those along y between them: no sphere is
  // pressed by two boxes' faces at once
  const std::array<std::array<V3, 2>, 4> boxes{{
      {{{lo[0] - w, lo[1] - w, lo[2] - depth}, {hi[0] + w, lo[1] + w, lo[2]}}},
      {{{lo[0] - w, hi[1] - w, lo[2] - depth}, {hi[0] + w, hi[1] + w, lo[2]}}},
      {{{lo[0] - w, lo[1] + w, lo[2] - depth}, {lo[0] + w, hi[1] - w, lo[2]}}},
      {{{hi[0] - w, lo[1] + w, lo[2] - depth}, {hi[0] + w, hi[1] - w, lo[2]}}},
  }};
  for (std::size_t k = 0; k < boxes.size(); ++k)
  {
    Shape box;
    box.kind = Shape::Kind::box;
    box.lo = boxes[k][0];
    box.hi = boxes[k][1];
    _frame.push_back(_solver->add_body(make_wall("frame " + std::to_string(k), box)));
  }
}

double ImpactRun::support_reaction() const
{
  if (_coupling)
    return _coupling->support_reaction();
  if (!_frame.empty())
  {
    double r = 0.0;
    for (auto k : _frame)
      r -= _solver->body(k).f[2];
    return r;
  }
  return _supported > 0 ? _solver->reaction("supports")[2] : 0.0;
}

std::optional<double> ImpactRun::fine_mean_radius() const
{
  if (!_s.target.fine())
    return std::nullopt;
  const auto scale = fine_scale(_s);
  const double fine = _s.target.fine_mean() / _s.target.mean_radius;
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < _p.size(); ++i)
    if (scale({_p.x[3 * i], _p.x[3 * i + 1], _p.x[3 * i + 2]}) <= fine)
    {
      sum += _p.r[i];
      ++n;
    }
  if (n == 0)
    return std::nullopt;
  return sum / static_cast<double>(n);
}

void ImpactRun::describe()
{
  _out["scenario"] = _s.name;
  _out["model"] = _s.shells.model;
  if (_coupling)
    _out["coupling"] = _coupling->describe();
  _out["particles"] = _p.size();
  _out["links"] = _links.size();
  _out["lambda"] = _lambda;
  _out["packing_fraction"] = _fraction;
  _out["mean_radius_m"] = mean(_p.r);
  _out["supported_spheres"] = _supported;
  _out["dt_s"] = _dt;
  _out["dt_critical_s"] = _dt_crit;
  _out["duration_s"] = _duration;
  if (pulsed())
    _out["pulse"] = {{"peak_force_n", _s.pulse.peak_force},
                     {"duration_s", _s.pulse.duration},
                     {"impulse_n_s", 2.0 / std::numbers::pi * _s.pulse.peak_force * _s.pulse.duration},
                     {"loaded_spheres", _loaded.size()}};
  else
  {
    _out["projectile_mass_kg"] = _body.mass;
    _out["striking_velocity_m_s"] = _s.projectile.velocity;
  }
  const auto fine = fine_mean_radius();
  if (fine)
    _out["fine_mean_radius_m"] = *fine;
  else if (_s.target.fine())
    std::cerr << "warning: no sphere centre lies within target.fine_radius_m (" << _s.target.fine_radius
              << " m) of the path: fine_mean_radius_m is left out, spheres_across_diameter counts all the "
                 "spheres"
              << std::endl;
  _out["spheres_across_diameter"] = _s.projectile.diameter / (2.0 * fine.value_or(mean(_p.r)));
}

void ImpactRun::describe_bars()
{
  if (bars())
  {
    double mass = 0.0;
    for (double m : _bars.m)
      mass += m;
    _out["reinforcement"] = {{"bars", _bars.line.empty() ? 0 : _bars.line.back() + 1},
                             {"elements", _bars.elements()},
                             {"bonds", _bonds},
                             {"bar_mass_kg", mass},
                             {"spheres_left_out", _spheres_on_bars},
                             {"embedded", _s.reinforcement.embedded}};
  }
}

} // namespace dembridge::demo::impl
