#include "dembridge/bridge/multipliers.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

namespace dembridge::bridge
{

struct MultiplierSolver::Factor
{
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
};

namespace
{
/// 3 x 6 block of G_FE for one (point, node) pair: [a I, -b [n]x] (the
/// rotation part maps omega to b (omega x n) = -b n x omega).
void block(double a, double b, const double* n, double G[3][6])
{
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 6; ++j)
      G[i][j] = 0.0;
  for (int i = 0; i < 3; ++i)
    G[i][i] = a;
  // [n]x = [[0, -n2, n1], [n2, 0, -n0], [-n1, n0, 0]]
  const double nx[3][3] = {{0, -n[2], n[1]}, {n[2], 0, -n[0]}, {-n[1], n[0], 0}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      G[i][3 + j] = -b * nx[i][j];
}
} // namespace

MultiplierSolver::MultiplierSolver(const CouplingOperator& op, std::span<const double> m_de,
                                   std::span<const double> m_fe, double dt)
    : _op(op), _m_de(m_de.begin(), m_de.end()), _m_fe(m_fe.begin(), m_fe.end()), _dt(dt),
      _factor(std::make_unique<Factor>())
{
  const std::size_t np = op.size();
  if (m_de.size() != np)
    throw std::runtime_error("multipliers: " + std::to_string(m_de.size()) + " particle masses for "
                             + std::to_string(np) + " constrained particles");
  if (!(dt > 0.0))
    throw std::runtime_error("multipliers: time step must be > 0");
  for (std::size_t i = 0; i < np; ++i)
    if (!(m_de[i] > 0.0))
      throw std::runtime_error("multipliers: weighted mass of constrained particle "
                               + std::to_string(i) + " is " + std::to_string(m_de[i])
                               + ": must be > 0 (use a weight floor)");
  for (std::size_t i = 0; i < m_fe.size(); ++i)
    if (!(m_fe[i] > 0.0))
      throw std::runtime_error("multipliers: weighted mass of shell dof " + std::to_string(i)
                               + " must be > 0 (use a weight floor)");
  const int npc = op.nodes_per_cell();
  const int bs = op.block_size();
  // rows of G_FE grouped by shell node: node -> list of (point, local k)
  std::map<std::int32_t, std::vector<std::pair<std::size_t, int>>> by_node;
  const auto nodes = op.nodes();
  for (std::size_t p = 0; p < np; ++p)
    for (int k = 0; k < npc; ++k)
      by_node[nodes[p * npc + k]].push_back({p, k});
  std::vector<Eigen::Triplet<double>> trip;
  for (std::size_t p = 0; p < np; ++p)
    for (int i = 0; i < 3; ++i)
      trip.emplace_back(3 * p + i, 3 * p + i, dt / m_de[p]);
  for (const auto& [node, rows] : by_node)
  {
    const double* M = &m_fe[bs * node];
    for (const auto& [p, k] : rows)
    {
      double Gp[3][6];
      block(op.a()[p * npc + k], op.b()[p * npc + k], &op.normals()[3 * (p * npc + k)], Gp);
      for (const auto& [q, l] : rows)
      {
        double Gq[3][6];
        block(op.a()[q * npc + l], op.b()[q * npc + l], &op.normals()[3 * (q * npc + l)], Gq);
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
          {
            double s = 0.0;
            for (int c = 0; c < bs; ++c)
              s += Gp[i][c] * Gq[j][c] / M[c];
            if (s != 0.0)
              trip.emplace_back(3 * p + i, 3 * q + j, dt * s);
          }
      }
    }
  }
  Eigen::SparseMatrix<double> A(3 * np, 3 * np);
  A.setFromTriplets(trip.begin(), trip.end());
  _factor->ldlt.compute(A);
  if (_factor->ldlt.info() != Eigen::Success)
    throw std::runtime_error("multipliers: the constraint matrix is not symmetric positive definite");
  _lambda.assign(3 * np, 0.0);
  _rhs.assign(3 * np, 0.0);
  _tmp.assign(3 * np, 0.0);
}

MultiplierSolver::~MultiplierSolver() = default;

std::vector<double> MultiplierSolver::residual(std::span<const double> v_de,
                                               std::span<const double> v_fe) const
{
  std::vector<double> r(3 * _op.size());
  _op.interpolate(v_fe, r);
  for (std::size_t i = 0; i < r.size(); ++i)
    r[i] = v_de[i] - r[i];
  return r;
}

double MultiplierSolver::correct(std::span<double> v_de, std::span<double> v_fe)
{
  const std::size_t np = _op.size();
  _op.interpolate(v_fe, _tmp);
  for (std::size_t i = 0; i < 3 * np; ++i)
    _rhs[i] = v_de[i] - _tmp[i];
  Eigen::Map<const Eigen::VectorXd> rhs(_rhs.data(), 3 * np);
  Eigen::Map<Eigen::VectorXd> lambda(_lambda.data(), 3 * np);
  lambda = _factor->ldlt.solve(rhs);
  for (std::size_t p = 0; p < np; ++p)
    for (int i = 0; i < 3; ++i)
      v_de[3 * p + i] -= _dt / _m_de[p] * _lambda[3 * p + i];
  std::vector<double> f(v_fe.size(), 0.0);
  _op.add_transpose(_lambda, f);
  for (std::size_t i = 0; i < v_fe.size(); ++i)
    v_fe[i] += _dt / _m_fe[i] * f[i];
  const auto r = residual(v_de, v_fe);
  double worst = 0.0;
  for (double x : r)
    worst = std::max(worst, std::abs(x));
  return worst;
}

} // namespace dembridge::bridge
