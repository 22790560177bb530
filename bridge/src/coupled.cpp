#include "dembridge/bridge/coupled.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace dembridge::bridge
{

CoupledSolver::CoupledSolver(shell::FEModel& fe, dem::Particles& p, dem::Links& l,
                             const dem::Material& mat, const CouplingOptions& o)
    : _model(fe), _p(p)
{
  o.overlap.validate();
  const double floor = o.weight_floor;
  (void)floored(0.5, floor); // validates the floor
  // FE side: weight field and weighted lumped masses
  const auto x = fe.node_coordinates();
  const std::size_t nn = fe.num_nodes();
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
  fe.set_weight(eta);
  _m_fe = fe.lumped_mass();
  const int bs = fe.block_size();
  for (std::size_t k = 0; k < nn; ++k)
    for (int c = 0; c < bs; ++c)
      _m_fe[bs * k + c] *= floored(eta[k], floor);
  // DE side: masses, sphere and link weights
  const std::size_t np = p.size();
  p.weight.resize(np);
  for (std::size_t i = 0; i < np; ++i)
  {
    const std::array<double, 3> xi{p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]};
    const double w = 1.0 - o.overlap.weight(xi);
    p.weight[i] = w;
    p.m[i] *= floored(w, floor);
    p.inertia[i] *= floored(w, floor);
    if (o.overlap.contains(xi))
      _ids.push_back(static_cast<std::int32_t>(i));
  }
  if (_ids.empty())
    throw std::runtime_error("no particle lies in the overlap: the DE and FE regions must overlap");
  l.weight.resize(l.size());
  for (std::size_t k = 0; k < l.size(); ++k)
  {
    std::array<double, 3> mid;
    for (int d = 0; d < 3; ++d)
      mid[d] = 0.5 * (p.x[3 * l.a[k] + d] + p.x[3 * l.b[k] + d]);
    l.weight[k] = 1.0 - o.overlap.weight(mid);
  }
  // location in the fictive elements
  std::vector<double> pts;
  for (auto i : _ids)
    pts.insert(pts.end(), {p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]});
  _op = fe.is_shell()
            ? locate({x, fe.nodal_normals(), fe.cell_nodes(), fe.nodes_per_cell(),
                      fe.material().thickness},
                     pts)
            : locate_in_solid(x, fe.cell_nodes(), fe.nodes_per_cell(), pts);
  // time step
  _dt_fe = fe.critical_time_step(_m_fe);
  _dt_de = dem::critical_time_step(p, l);
  const double dt_est = o.safety * std::min(_dt_fe, _dt_de);
  if (o.dt > dt_est)
  {
    std::ostringstream s;
    s << "time step " << o.dt << " s is above the coupled estimate " << dt_est << " s ("
      << o.safety << " x min(FE " << _dt_fe << ", DE " << _dt_de << "))";
    throw std::runtime_error(s.str());
  }
  _dt = o.dt > 0.0 ? o.dt : dt_est;
  _m_de.resize(_ids.size());
  for (std::size_t q = 0; q < _ids.size(); ++q)
    _m_de[q] = p.m[_ids[q]];
  _v_de.assign(3 * _ids.size(), 0.0);
  _mult = std::make_unique<MultiplierSolver>(_op, _m_de, _m_fe, _dt);
  _fe_solver = std::make_unique<shell::ExplicitSolver>(_m_fe, fe.internal_force_fn(), _dt, o.damping_fe);
  const double rmin = *std::min_element(p.r.begin(), p.r.end());
  _de_solver = std::make_unique<dem::DemSolver>(p, l, mat, _dt, o.damping_de,
                                                o.skin > 0.0 ? o.skin : 0.5 * rmin);
}

CoupledSolver::~CoupledSolver() = default;

void CoupledSolver::correct()
{
  auto v_fe = _fe_solver->v_mut();
  for (std::size_t q = 0; q < _ids.size(); ++q)
    for (int d = 0; d < 3; ++d)
      _v_de[3 * q + d] = _p.v[3 * _ids[q] + d];
  _residual = _mult->correct(_v_de, v_fe);
  // work of the multipliers on the shell over the step: dt lambda . G_FE v_FE
  // (= dt lambda . v_DE, the constraint holding)
  const auto lambda = _mult->multipliers();
  double w = 0.0;
  for (std::size_t i = 0; i < lambda.size(); ++i)
    w += lambda[i] * _v_de[i];
  _multiplier_energy += _dt * w;
  for (std::size_t q = 0; q < _ids.size(); ++q)
    for (int d = 0; d < 3; ++d)
      _p.v[3 * _ids[q] + d] = _v_de[3 * q + d];
}

void CoupledSolver::start(std::span<const double> u_fe, std::span<const double> v_fe)
{
  _fe_solver->set_state(u_fe, v_fe);
  // make the initial velocities compatible
  correct();
  std::vector<double> v(_fe_solver->v().begin(), _fe_solver->v().end());
  _fe_solver->set_state(u_fe, v);
  _de_solver->start();
  _multiplier_energy = 0.0;
}

double CoupledSolver::step()
{
  _fe_solver->begin_step();
  _de_solver->begin_step();
  correct();
  _fe_solver->end_step();
  _de_solver->end_step();
  return _residual;
}

CoupledEnergy CoupledSolver::energy() const
{
  return {_fe_solver->energy(), _de_solver->energy(), _multiplier_energy};
}

} // namespace dembridge::bridge
