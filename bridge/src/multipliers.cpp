#include "dembridge/bridge/multipliers.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <omp.h>
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
  std::vector<std::int32_t> dofs;  // compact dof -> FE dof
  std::vector<std::int32_t> node;  // (points, npc): compact node of each entry of G
  std::vector<double> normal;      // (compact nodes, 3): the node's n_bar (shells)
  // G^T as a gather: the entries q = p npc + k of compact node c are
  // entry[first[c] .. first[c + 1]), point[e] = q / npc, so G^T f is
  // computed node by node, in parallel, with no write conflict
  std::vector<std::int32_t> first, entry, point;
  std::vector<double> vc;          // compact FE velocities
  std::vector<double> terms;       // (compact nodes, 6): v_J and omega_J x n_J
  Eigen::VectorXd z, s;
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
  F.node.resize(np * npc);
  F.first.assign(k + 1, 0);
  for (std::size_t q = 0; q < np * npc; ++q)
  {
    F.node[q] = compact.at(nodes[q]);
    ++F.first[F.node[q] + 1];
  }
  for (std::int32_t c = 0; c < k; ++c)
    F.first[c + 1] += F.first[c];
  F.entry.resize(np * npc);
  {
    std::vector<std::int32_t> fill(F.first.begin(), F.first.end() - 1);
    for (std::size_t q = 0; q < np * npc; ++q)
      F.entry[fill[F.node[q]]++] = static_cast<std::int32_t>(q);
  }
  F.point.resize(F.entry.size());
  for (std::size_t e = 0; e < F.entry.size(); ++e)
    F.point[e] = F.entry[e] / npc;
  // each node's normal, stored by the operator once per entry
  F.normal.assign(3 * k, 0.0);
  if (bs == 6)
    for (std::int32_t c = 0; c < k; ++c)
      for (std::int32_t e = F.first[c]; e < F.first[c + 1]; ++e)
        for (int i = 0; i < 3; ++i)
        {
          const double n = op.normals()[3 * F.entry[e] + i];
          if (e > F.first[c] && n != F.normal[3 * c + i])
            throw std::logic_error("multipliers: shell node " + std::to_string(F.dofs[bs * c] / bs)
                                   + " has two normals in the coupling operator");
          F.normal[3 * c + i] = n;
        }
  F.terms.assign(6 * k, 0.0);
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
  F.vc.assign(ns, 0.0);
  F.z.resize(ns);
  F.s.resize(ns);
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

namespace
{
/// Threads for a pass over n points: a pass costs ~10 ns per point, and a
/// team's start ~4 us on the 2-core machine; the bar's 1,211 points gained
/// nothing from a second thread (multipliers 0.44-0.50 s on two, 0.39-0.41 s
/// on one), so a team only from a few thousand points.
int threads_for(std::size_t n) { return n >= 4096 ? omp_get_max_threads() : 1; }

/// v_J and b-free part omega_J x n_J of each compact node (shells), or v_J
/// and zero (solids): G then reads v_p = sum_k a_pk t_J(p,k)[0..2] +
/// b_pk t_J(p,k)[3..5], 6 multiply-adds per entry.
void node_terms(std::span<const double> uc, int bs, const std::vector<double>& normal,
                std::vector<double>& t)
{
  const std::size_t nn = t.size() / 6;
  for (std::size_t c = 0; c < nn; ++c)
  {
    const double* u = &uc[bs * c];
    double* o = &t[6 * c];
    o[0] = u[0];
    o[1] = u[1];
    o[2] = u[2];
    if (bs == 6)
    {
      const double* w = u + 3;
      const double* n = &normal[3 * c];
      o[3] = w[1] * n[2] - w[2] * n[1];
      o[4] = w[2] * n[0] - w[0] * n[2];
      o[5] = w[0] * n[1] - w[1] * n[0];
    }
    else
      o[3] = o[4] = o[5] = 0.0;
  }
}

/// G_p u from the node terms, (3).
inline void row(const double* a, const double* b, const std::int32_t* node, int npc,
                const double* t, double out[3])
{
  out[0] = out[1] = out[2] = 0.0;
  for (int k = 0; k < npc; ++k)
  {
    const double* tk = t + 6 * node[k];
    for (int i = 0; i < 3; ++i)
      out[i] += a[k] * tk[i] + b[k] * tk[3 + i];
  }
}
} // namespace

void MultiplierSolver::apply_transpose(std::span<const double> f, std::span<double> zc) const
{
  const auto& F = *_factor;
  const std::size_t nn = F.first.size() - 1;
  const int bs = _op.block_size();
  const double* a = _op.a().data();
  const double* b = _op.b().data();
#pragma omp parallel for schedule(static) num_threads(threads_for(F.entry.size() / _op.nodes_per_cell()))
  for (std::size_t c = 0; c < nn; ++c)
  {
    // sum a f over the node's entries, and sum b f, whose moment is n x (sum b f)
    double fa[3] = {0.0, 0.0, 0.0}, fb[3] = {0.0, 0.0, 0.0};
    for (std::int32_t e = F.first[c]; e < F.first[c + 1]; ++e)
    {
      const std::int32_t q = F.entry[e];
      const double* fp = &f[3 * F.point[e]];
      for (int i = 0; i < 3; ++i)
      {
        fa[i] += a[q] * fp[i];
        fb[i] += b[q] * fp[i];
      }
    }
    double* z = &zc[bs * c];
    z[0] = fa[0];
    z[1] = fa[1];
    z[2] = fa[2];
    if (bs == 6)
    {
      const double* n = &F.normal[3 * c];
      z[3] = n[1] * fb[2] - n[2] * fb[1];
      z[4] = n[2] * fb[0] - n[0] * fb[2];
      z[5] = n[0] * fb[1] - n[1] * fb[0];
    }
  }
}

double MultiplierSolver::correct(std::span<double> v_de, std::span<double> v_fe, bool residual)
{
  // With r = v_de - G v_fe the trial residual and s = K^-1 G^T D^-1 r, the
  // Woodbury form of the correction is v_fe += s, v_de -= r - G s, and
  // lambda = D^-1 (r - G s) / dt: one pass of G^T and two of G over the
  // points (a third for the residual), all in the compact numbering of the
  // FE dofs the overlap touches. G's passes are fused with the point loops.
  auto& F = *_factor;
  const std::size_t np = _op.size();
  const std::size_t ns = F.dofs.size();
  const int npc = _op.nodes_per_cell(), bs = _op.block_size();
  const double* a = _op.a().data();
  const double* b = _op.b().data();
  const std::int32_t* node = F.node.data();
  const double* t = F.terms.data();
  const int nt = threads_for(np);
  for (std::size_t i = 0; i < ns; ++i)
    F.vc[i] = v_fe[F.dofs[i]];
  node_terms(F.vc, bs, F.normal, F.terms);
#pragma omp parallel for schedule(static) num_threads(nt)
  for (std::size_t p = 0; p < np; ++p)
  {
    double g[3];
    row(a + npc * p, b + npc * p, node + npc * p, npc, t, g);
    for (int i = 0; i < 3; ++i)
    {
      _rhs[3 * p + i] = v_de[3 * p + i] - g[i];
      _tmp[3 * p + i] = _m_de[p] * _rhs[3 * p + i];
    }
  }
  apply_transpose(_tmp, {F.z.data(), ns});
  F.s = F.ldlt.solve(F.z);
  for (std::size_t i = 0; i < ns; ++i)
  {
    F.vc[i] += F.s[i];
    v_fe[F.dofs[i]] = F.vc[i];
  }
  node_terms({F.s.data(), ns}, bs, F.normal, F.terms);
  const double idt = 1.0 / _dt;
#pragma omp parallel for schedule(static) num_threads(nt)
  for (std::size_t p = 0; p < np; ++p)
  {
    double g[3];
    row(a + npc * p, b + npc * p, node + npc * p, npc, t, g);
    for (int i = 0; i < 3; ++i)
    {
      const double d = _rhs[3 * p + i] - g[i];
      _lambda[3 * p + i] = _m_de[p] * d * idt;
      v_de[3 * p + i] -= d;
    }
  }
  if (!residual)
    return std::numeric_limits<double>::quiet_NaN();
  // residual after the correction (no allocation per step)
  node_terms(F.vc, bs, F.normal, F.terms);
  double worst = 0.0;
  for (std::size_t p = 0; p < np; ++p)
  {
    double g[3];
    row(a + npc * p, b + npc * p, node + npc * p, npc, t, g);
    for (int i = 0; i < 3; ++i)
      worst = std::max(worst, std::abs(v_de[3 * p + i] - g[i]));
  }
  return worst;
}

} // namespace dembridge::bridge
