#include "dembridge/bridge/multipliers.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

namespace dembridge::bridge
{

struct MultiplierSolver::Factor
{
  // A^-1 by the Woodbury identity: A = dt (D + G W G^T), D = diag(1 / m_de),
  // W = diag(1 / M_fe), so A^-1 = (D^-1 - D^-1 G K^-1 G^T D^-1) / dt with
  // K = W^-1 + G^T D^-1 G over the FE dofs the overlap touches: as small
  // as the overlap's shell nodes x 6, sparse, factorised once. Each solve
  // then costs O(nonzeros of G) instead of a factor of the particles' A,
  // which is nearly dense when many particles share an element.
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  std::vector<std::int32_t> dofs; // compact index -> FE dof
  std::vector<double> full;       // FE-sized scratch
  Eigen::VectorXd z;
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
  // FE dofs touched by the overlap, compact numbering
  const auto nodes = op.nodes();
  std::map<std::int32_t, std::int32_t> compact; // node -> compact node index
  for (auto n : nodes)
    compact.emplace(n, 0);
  std::int32_t k = 0;
  for (auto& [n, c] : compact)
    c = k++;
  const std::int32_t ns = k * bs;
  auto& F = *_factor;
  F.dofs.resize(ns);
  for (const auto& [n, c] : compact)
    for (int d = 0; d < bs; ++d)
      F.dofs[bs * c + d] = bs * n + d;
  std::vector<Eigen::Triplet<double>> trip;
  for (std::int32_t i = 0; i < ns; ++i)
    trip.emplace_back(i, i, m_fe[F.dofs[i]]);
  // + sum over points of m_p G_p^T G_p (G_p: 3 x (npc bs))
  std::vector<double> Gp(3 * npc * bs);
  std::vector<std::int32_t> col(npc * bs);
  for (std::size_t p = 0; p < np; ++p)
  {
    for (int kk = 0; kk < npc; ++kk)
    {
      double G[3][6];
      block(op.a()[p * npc + kk], op.b()[p * npc + kk], &op.normals()[3 * (p * npc + kk)], G);
      for (int i = 0; i < 3; ++i)
        for (int d = 0; d < bs; ++d)
          Gp[i * npc * bs + kk * bs + d] = G[i][d];
      for (int d = 0; d < bs; ++d)
        col[kk * bs + d] = bs * compact.at(nodes[p * npc + kk]) + d;
    }
    for (int r = 0; r < npc * bs; ++r)
      for (int q = 0; q < npc * bs; ++q)
      {
        double v = 0.0;
        for (int i = 0; i < 3; ++i)
          v += Gp[i * npc * bs + r] * Gp[i * npc * bs + q];
        if (v != 0.0)
          trip.emplace_back(col[r], col[q], m_de[p] * v);
      }
  }
  Eigen::SparseMatrix<double> K(ns, ns);
  K.setFromTriplets(trip.begin(), trip.end());
  F.ldlt.compute(K);
  if (F.ldlt.info() != Eigen::Success)
    throw std::runtime_error("multipliers: the constraint matrix is not symmetric positive definite");
  F.full.assign(m_fe.size(), 0.0);
  F.z.resize(ns);
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

double MultiplierSolver::correct(std::span<double> v_de, std::span<double> v_fe, bool residual)
{
  const std::size_t np = _op.size();
  _op.interpolate(v_fe, _tmp);
  for (std::size_t i = 0; i < 3 * np; ++i)
    _rhs[i] = v_de[i] - _tmp[i];
  // y = D^-1 r, z = G^T y, s = K^-1 z, lambda = D^-1 (r - G s) / dt
  auto& F = *_factor;
  for (std::size_t p = 0; p < np; ++p)
    for (int i = 0; i < 3; ++i)
      _tmp[3 * p + i] = _m_de[p] * _rhs[3 * p + i];
  std::fill(F.full.begin(), F.full.end(), 0.0);
  _op.add_transpose(_tmp, F.full);
  for (std::size_t i = 0; i < F.dofs.size(); ++i)
    F.z[i] = F.full[F.dofs[i]];
  const Eigen::VectorXd sol = F.ldlt.solve(F.z);
  std::fill(F.full.begin(), F.full.end(), 0.0);
  for (std::size_t i = 0; i < F.dofs.size(); ++i)
    F.full[F.dofs[i]] = sol[i];
  _op.interpolate(F.full, _tmp);
  for (std::size_t p = 0; p < np; ++p)
    for (int i = 0; i < 3; ++i)
      _lambda[3 * p + i] = _m_de[p] * (_rhs[3 * p + i] - _tmp[3 * p + i]) / _dt;
  for (std::size_t p = 0; p < np; ++p)
    for (int i = 0; i < 3; ++i)
      v_de[3 * p + i] -= _dt / _m_de[p] * _lambda[3 * p + i];
  std::fill(F.full.begin(), F.full.end(), 0.0);
  _op.add_transpose(_lambda, F.full);
  for (auto i : F.dofs)
    v_fe[i] += _dt / _m_fe[i] * F.full[i];
  if (!residual)
    return std::numeric_limits<double>::quiet_NaN();
  // residual after the correction, in the scratch buffer (no allocation per step)
  _op.interpolate(v_fe, _tmp);
  double worst = 0.0;
  for (std::size_t i = 0; i < 3 * np; ++i)
    worst = std::max(worst, std::abs(v_de[i] - _tmp[i]));
  return worst;
}

} // namespace dembridge::bridge
