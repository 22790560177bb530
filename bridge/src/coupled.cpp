#include "dembridge/bridge/coupled.h"
#include "dembridge/dem/linearised.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace dembridge::bridge
{
namespace
{
/// Steps between two checks of the coupled energy guard (a check costs one
/// pass over the links for the elastic energy, spread over 100 steps: under 1 %
/// of their cost).
constexpr std::int64_t guard_every = 100;

double now_s()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
} // namespace

CoupledSolver::CoupledSolver(shell::FEModel& fe, dem::Particles& p, dem::Links& l,
                             const dem::Material& mat, const CouplingOptions& o)
    : CoupledSolver(fe, p, l, mat, o, dem::Bars{})
{
}

CoupledSolver::CoupledSolver(shell::FEModel& fe, dem::Particles& p, dem::Links& l, const dem::Material& mat,
                             const CouplingOptions& o, dem::Bars bars)
    : _model(fe), _p(p), _l(l), _bars(std::move(bars))
{
  if (!p.weight.empty() || !l.weight.empty())
    throw std::runtime_error("these particles or links already carry energy weights: another "
                             "CoupledSolver holds them (a second one would weight their masses "
                             "twice); couple a copy, or let the first coupler go first");
  validate(o);
  _m_given = p.m;
  _inertia_given = p.inertia;
  try
  {
    own_critical_steps();
    weigh_fe(o);
    weigh_de(o);
    weigh_bars(o);
    locate_overlap();
    coupled_time_step(o, mat);
    _mult = std::make_unique<MultiplierSolver>(_op, _m_de, _m_fe, _dt);
    _fe_solver = std::make_unique<shell::ExplicitSolver>(_m_fe, fe.internal_force_fn(), _dt,
                                                         o.damping_fe);
    const double rmin = *std::min_element(p.r.begin(), p.r.end());
    _de_solver = std::make_unique<dem::DemSolver>(p, l, mat, _dt, o.damping_de,
                                                  o.skin > 0.0 ? o.skin : 0.5 * rmin);
    if (_bars.nodes() > 0)
      _de_solver->add_bars(std::move(_bars));
    // each side's budget carries the multipliers' work, so only the sum
    // closes: the coupler guards that
    _fe_solver->set_energy_guard(0.0);
    _de_solver->set_energy_guard(0.0);
    _guard.set(o.energy_guard, guard_every); // (checked above: >= 0)
  }
  catch (...)
  {
    give_back();
    throw;
  }
}

CoupledSolver::~CoupledSolver() { give_back(); }

void CoupledSolver::give_back() noexcept
{
  if (_m_given.size() != _p.size())
    return;
  _p.m = std::move(_m_given);
  _p.inertia = std::move(_inertia_given);
  _m_given.clear();
  _p.weight.clear();
  _l.weight.clear();
  try
  {
    _model.set_weight(std::vector<double>(_model.num_nodes(), 1.0));
  }
  catch (...)
  {
    // only an allocation can fail here; the model keeps the coupling's
    // weights, which its next coupler or user sets anew
  }
}

void CoupledSolver::validate(const CouplingOptions& o)
{
  o.overlap.validate();
  (void)floored(0.5, o.weight_floor); // validates the floor
  if (!(o.safety > 0.0 && o.safety <= 0.95))
  {
    std::ostringstream m;
    m << "time step safety factor " << o.safety
      << ": allowed is (0, 0.95] (the coupled critical step is an estimate from below)";
    throw std::runtime_error(m.str());
  }
  if (!(o.energy_guard >= 0.0) || !std::isfinite(o.energy_guard))
    throw std::runtime_error("energy guard " + std::to_string(o.energy_guard) + ": allowed is >= 0 (0 = off)");
}

void CoupledSolver::own_critical_steps()
{
  _model.set_weight(std::vector<double>(_model.num_nodes(), 1.0));
  _dt_fe = _model.critical_time_step(_model.lumped_mass());
  _dt_de = dem::particle_critical_time_step(_p, _l);
}

void CoupledSolver::weigh_fe(const CouplingOptions& o)
{
  // FE side: the weight field eta and the lumped masses max(eta, floor) M
  const auto x = _model.node_coordinates();
  const std::size_t nn = _model.num_nodes();
  std::vector<double> eta(nn);
  bool any_in = false;
  for (std::size_t k = 0; k < nn; ++k)
  {
    const std::array<double, 3> xk{x[3 * k], x[3 * k + 1], x[3 * k + 2]};
    eta[k] = o.overlap.weight(xk);
    any_in = any_in || o.overlap.contains(xk);
  }
  if (!any_in)
    throw std::runtime_error("the overlap holds no node of the FE mesh: the overlap must lie "
                             "inside the shell's region");
  _model.set_weight(eta);
  _m_fe = _model.lumped_mass();
  const int bs = _model.block_size();
  for (std::size_t k = 0; k < nn; ++k)
    for (int c = 0; c < bs; ++c)
      _m_fe[bs * k + c] *= floored(eta[k], o.weight_floor);
}

void CoupledSolver::weigh_de(const CouplingOptions& o)
{
  // DE side: sphere weights 1 - eta, masses and inertias max(1 - eta, floor) m,
  // link weights 1 - eta at the link's mid-point
  const std::size_t np = _p.size();
  _p.weight.resize(np);
  for (std::size_t i = 0; i < np; ++i)
  {
    const std::array<double, 3> xi{_p.x[3 * i], _p.x[3 * i + 1], _p.x[3 * i + 2]};
    const double w = 1.0 - o.overlap.weight(xi);
    _p.weight[i] = w;
    _p.m[i] *= floored(w, o.weight_floor);
    _p.inertia[i] *= floored(w, o.weight_floor);
    if (o.overlap.contains(xi))
      _ids.push_back(static_cast<std::int32_t>(i));
  }
  if (_ids.empty())
    throw std::runtime_error("no particle lies in the overlap: the DE and FE regions must overlap");
  refuse_beyond(o.overlap, _p.x, "spheres",
                "Keep the spheres within the DE core and the band: they would only shrink the coupled time step");
  _l.weight.resize(_l.size());
  for (std::size_t k = 0; k < _l.size(); ++k)
  {
    std::array<double, 3> mid;
    for (int d = 0; d < 3; ++d)
      mid[d] = 0.5 * (_p.x[3 * _l.a[k] + d] + _p.x[3 * _l.b[k] + d]);
    _l.weight[k] = 1.0 - o.overlap.weight(mid);
  }
}

void CoupledSolver::refuse_beyond(const Overlap& overlap, std::span<const double> x, const char* what,
                                  const char* advice)
{
  // points past the band on the FE side have weight 0 and floored masses:
  // they add nothing to the model but shrink the coupled step
  std::size_t n = 0;
  double worst = -1.0;
  std::array<double, 3> at{0, 0, 0};
  for (std::size_t i = 0; 3 * i < x.size(); ++i)
  {
    const std::array<double, 3> xi{x[3 * i], x[3 * i + 1], x[3 * i + 2]};
    if (!overlap.beyond(xi))
      continue;
    ++n;
    const double past = overlap.distance(xi) - overlap.width();
    if (past > worst)
    {
      worst = past;
      at = xi;
    }
  }
  if (n == 0)
    return;
  std::ostringstream m;
  m << n << " of the " << x.size() / 3 << " " << what << " lie beyond the overlap on the FE side (weight 1: the "
    << "shells alone carry the structure there), up to " << worst << " m past its FE edge, the farthest at (" << at[0]
    << ", " << at[1] << ", " << at[2] << ") m; the overlap is " << overlap.what() << ". " << advice;
  throw std::runtime_error(m.str());
}

void CoupledSolver::refuse_ends_in_band(const Overlap& overlap) const
{
  // Within the band the bar carries (1 - eta) of the steel's force and the
  // shells' steel layers eta: the two add up to the whole only where the bar
  // runs on to the band's FE edge (eta = 1). A bar ending inside the band
  // would leave the steel short by (1 - eta) from its end to that edge.
  constexpr double tol = 1e-3; // of the band's width, from either of its edges
  std::vector<int> degree(_bars.nodes(), 0);
  for (std::size_t e = 0; e < _bars.elements(); ++e)
  {
    ++degree[_bars.a[e]];
    ++degree[_bars.b[e]];
  }
  for (std::size_t n = 0; n < _bars.nodes(); ++n)
  {
    const double* x = &_bars.x[3 * n];
    const double eta = overlap.weight({x[0], x[1], x[2]});
    if (degree[n] == 1 && eta > tol && eta < 1.0 - tol)
    {
      std::ostringstream m;
      m << "bar node " << n << ", an end of its bar, lies inside the overlap at (" << x[0] << ", " << x[1] << ", "
        << x[2] << ") m (the shells' weight " << eta << "; the overlap is " << overlap.what()
        << "): a bar that enters the band must run on to its FE edge, where the shells' steel layers carry the "
           "whole force; end it in the DE-only part or at the band's FE edge";
      throw std::runtime_error(m.str());
    }
  }
}

void CoupledSolver::weigh_bars(const CouplingOptions& o)
{
  // the bars' energies weighted as the links', their masses as the
  // spheres': an element's force and energy scale with its area, a bending
  // spring's with its stiffness, a bond's with its surface
  if (_bars.nodes() == 0)
    return;
  auto weight = [&](const double* x) { return 1.0 - o.overlap.weight({x[0], x[1], x[2]}); };
  refuse_beyond(o.overlap, _bars.x, "bar nodes",
                "End the bars within the band: the shells' steel layers carry the reinforcement beyond it");
  refuse_ends_in_band(o.overlap);
  for (std::size_t n = 0; n < _bars.nodes(); ++n)
    if (o.overlap.contains({_bars.x[3 * n], _bars.x[3 * n + 1], _bars.x[3 * n + 2]}))
      _bar_ids.push_back(static_cast<std::int32_t>(n));
  for (std::size_t e = 0; e < _bars.elements(); ++e)
  {
    double mid[3];
    for (int d = 0; d < 3; ++d)
      mid[d] = 0.5 * (_bars.x[3 * _bars.a[e] + d] + _bars.x[3 * _bars.b[e] + d]);
    const double w = weight(mid);
    if (!(w > 0.0)) // (its stress, force over area, would be 0 / 0)
      throw std::runtime_error("bar element " + std::to_string(e) + " lies along the overlap's FE edge (weight 0 at "
                               + "its middle): it would carry nothing; end the bar inside the band");
    _bars.area[e] *= w;
  }
  for (std::size_t k = 0; k < _bars.bend_k.size(); ++k)
    _bars.bend_k[k] *= weight(&_bars.x[3 * _bars.bend_b[k]]);
  for (std::size_t k = 0; k < _bars.bonds(); ++k)
    _bars.surface[k] *= _p.weight[_bars.sphere[k]];
  for (std::size_t n = 0; n < _bars.nodes(); ++n)
    _bars.m[n] *= floored(weight(&_bars.x[3 * n]), o.weight_floor);
}

CouplingOperator CoupledSolver::locate_points(const std::vector<double>& pts) const
{
  // points in the fictive elements (shell) or the cells (solid)
  const auto x = _model.node_coordinates();
  return _model.is_shell() ? locate({x, _model.nodal_normals(), _model.cell_nodes(), _model.nodes_per_cell(),
                                     _model.material().thickness},
                                    pts)
                           : locate_in_solid(x, _model.cell_nodes(), _model.nodes_per_cell(), pts);
}

void CoupledSolver::locate_overlap()
{
  // the overlap's particles, then its bar nodes
  std::vector<double> pts;
  for (auto i : _ids)
    pts.insert(pts.end(), {_p.x[3 * i], _p.x[3 * i + 1], _p.x[3 * i + 2]});
  for (auto n : _bar_ids)
    pts.insert(pts.end(), {_bars.x[3 * n], _bars.x[3 * n + 1], _bars.x[3 * n + 2]});
  _op = locate_points(pts);
  _m_de.resize(_ids.size() + _bar_ids.size());
  for (std::size_t q = 0; q < _ids.size(); ++q)
    _m_de[q] = _p.m[_ids[q]];
  for (std::size_t q = 0; q < _bar_ids.size(); ++q)
    _m_de[_ids.size() + q] = _bars.m[_bar_ids[q]];
  _v_de.assign(3 * _m_de.size(), 0.0);
}

void CoupledSolver::coupled_time_step(const CouplingOptions& o, const dem::Material& mat)
{
  // power iteration on the coupled system's motions that satisfy the
  // constraint (the multiplier correction is their mass-orthogonal
  // projection, whatever dt it is built with)
  const std::size_t nf = _m_fe.size(), np = _p.size();
  std::vector<double> mass(_m_fe);
  for (int rot = 0; rot < 2; ++rot)
    for (std::size_t i = 0; i < np; ++i)
      for (int d = 0; d < 3; ++d)
        mass.push_back(rot ? _p.inertia[i] : _p.m[i]);
  const auto f_fe = _model.bounding_force_fn();
  dem::StiffnessOperator k_de(_p, _l);
  auto f_all = [&](std::span<const double> z, std::span<double> f) {
    f_fe(z.first(nf), f.first(nf));
    k_de.apply(z.subspan(nf), f.subspan(nf));
  };
  // the iteration moves the spheres and the shell: with tied bar nodes its
  // projector ties the spheres only
  const bool bars = !_bar_ids.empty();
  CouplingOperator spheres_only;
  if (bars)
  {
    std::vector<double> pts;
    for (auto i : _ids)
      pts.insert(pts.end(), {_p.x[3 * i], _p.x[3 * i + 1], _p.x[3 * i + 2]});
    spheres_only = locate_points(pts);
  }
  MultiplierSolver projector(bars ? spheres_only : _op, std::span<const double>(_m_de).first(_ids.size()), _m_fe, 1.0);
  std::vector<double> v(3 * _ids.size());
  auto project = [&](std::span<double> z) {
    for (std::size_t q = 0; q < _ids.size(); ++q)
      for (int d = 0; d < 3; ++d)
        v[3 * q + d] = z[nf + 3 * _ids[q] + d];
    projector.correct(v, z.first(nf), false);
    for (std::size_t q = 0; q < _ids.size(); ++q)
      for (int d = 0; d < 3; ++d)
        z[nf + 3 * _ids[q] + d] = v[3 * q + d];
  };
  _dt_coupled = 2.0 / std::sqrt(core::max_eigenvalue(mass, f_all, 1e-6, 20000, project));
  if (_bars.nodes() > 0 || o.body_contacts)
  {
    // what the multipliers leave free, with one body contact per sphere and
    // the bars' elements and bonds
    std::vector<std::uint8_t> tied_spheres(np, 0), tied_nodes(_bars.nodes(), 0);
    for (auto i : _ids)
      tied_spheres[i] = 1;
    for (auto n : _bar_ids)
      tied_nodes[n] = 1;
    _dt_coupled = std::min(_dt_coupled, dem::critical_time_step(_p, _l, mat, _bars, tied_spheres, tied_nodes));
  }
  if (o.dt > _dt_coupled)
  {
    std::ostringstream s;
    s << "time step " << o.dt << " s is above the coupled estimate " << _dt_coupled
      << " s (critical step of the coupled, weighted system; alone: FE " << _dt_fe << " s, DE "
      << _dt_de << " s)";
    throw std::runtime_error(s.str());
  }
  _dt = o.dt > 0.0 ? o.dt : o.safety * _dt_coupled;
}

void CoupledSolver::correct(bool half_step, bool residual)
{
  auto v_fe = _fe_solver->v_mut();
  const std::size_t ns = _ids.size();
  double* v_bars = _bar_ids.empty() ? nullptr : _de_solver->bars_for_coupling().v.data();
  for (std::size_t q = 0; q < ns; ++q)
    for (int d = 0; d < 3; ++d)
      _v_de[3 * q + d] = _p.v[3 * _ids[q] + d];
  for (std::size_t q = 0; q < _bar_ids.size(); ++q)
    for (int d = 0; d < 3; ++d)
      _v_de[3 * (ns + q) + d] = v_bars[3 * _bar_ids[q] + d];
  // the residual is checked after the half-step correction (the one the
  // positions move with); the full-step one only makes v(n+1) consistent
  const double r = _mult->correct(_v_de, v_fe, half_step && residual);
  for (std::size_t q = 0; q < ns; ++q)
    for (int d = 0; d < 3; ++d)
      _p.v[3 * _ids[q] + d] = _v_de[3 * q + d];
  for (std::size_t q = 0; q < _bar_ids.size(); ++q)
    for (int d = 0; d < 3; ++d)
      v_bars[3 * _bar_ids[q] + d] = _v_de[3 * (ns + q) + d];
  if (!half_step)
    return;
  if (residual)
    _residual = r;
  // work of the multipliers on the shell over the step: dt lambda . G_FE v_FE
  // (= dt lambda . v_DE, the constraint holding)
  const auto lambda = _mult->multipliers();
  double w = 0.0;
  for (std::size_t i = 0; i < lambda.size(); ++i)
    w += lambda[i] * _v_de[i];
  _multiplier_energy += _dt * w;
}

void CoupledSolver::start(std::span<const double> u_fe, std::span<const double> v_fe)
{
  _fe_solver->set_state(u_fe, v_fe);
  // make the initial velocities compatible
  correct(true);
  std::vector<double> v(_fe_solver->v().begin(), _fe_solver->v().end());
  _fe_solver->set_state(u_fe, v);
  _de_solver->start();
  _multiplier_energy = 0.0;
}

double CoupledSolver::step(bool observed)
{
  const double t0 = now_s();
  _fe_solver->begin_step();
  const double t1 = now_s();
  _de_solver->begin_step();
  const double t2 = now_s();
  correct(true, observed);
  const double t3 = now_s();
  _fe_solver->end_step();
  const double t4 = now_s();
  _de_solver->end_step();
  const double t5 = now_s();
  // RATTLE: the full-step velocities projected too. The positions do not
  // change (the projection is linear and the next half-step velocities are
  // projected anyway), but v(n+1) -- written out, and in the kinetic
  // energy -- then satisfies the constraint instead of carrying the
  // unconstrained dt/2 a of the lightest (floored) masses.
  _projected = observed || _fe_solver->damping() > 0.0 || _de_solver->damping() > 0.0;
  if (_projected)
    correct(false, false);
  const double t6 = now_s();
  _time.fe += (t1 - t0) + (t4 - t3);
  _time.de += (t2 - t1) + (t5 - t4);
  _time.multipliers += (t3 - t2) + (t6 - t5);
  if (_guard.due(_de_solver->steps()))
    check_energy();
  return _residual;
}

void CoupledSolver::observe()
{
  if (_projected)
    return;
  const double t0 = now_s();
  correct(false, false);
  _projected = true;
  _time.multipliers += now_s() - t0;
}

void CoupledSolver::check_energy() const
{
  const CoupledEnergy e = energy();
  const double initial = e.fe.initial + e.de.initial;
  const double work = e.fe.external_work + e.fe.prescribed_work + e.de.external_work + e.de.prescribed_work;
  const double scale = initial + std::abs(e.fe.external_work) + std::abs(e.fe.prescribed_work)
                       + std::abs(e.de.external_work) + std::abs(e.de.prescribed_work) + e.total();
  _guard.check({_de_solver->time(), _de_solver->steps(), "the coupled system's energy", "kinetic + stored", e.total(),
                initial, work, e.imbalance(), scale});
}

CoupledEnergy CoupledSolver::energy() const
{
  return {_fe_solver->energy(), _de_solver->energy(), _multiplier_energy};
}

} // namespace dembridge::bridge

namespace dembridge::bridge
{

void CoupledSolver::save(const checkpoint::Group& g) const
{
  _fe_solver->save(g.group("shell"));
  _de_solver->save(g.group("dem"));
  g.write("multiplier_energy", _multiplier_energy);
  g.write("residual", _residual);
  g.write("dt", _dt);
}

void CoupledSolver::load(const checkpoint::Group& g)
{
  if (g.read_double("dt") != _dt)
    g.fail("dt", "the coupled time step differs from this run's");
  _fe_solver->load(g.group("shell"));
  _de_solver->load(g.group("dem"));
  _multiplier_energy = g.read_double("multiplier_energy");
  _residual = g.read_double("residual");
}

} // namespace dembridge::bridge
