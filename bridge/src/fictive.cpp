#include "dembridge/bridge/fictive.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <sstream>
#include <stdexcept>

namespace dembridge::bridge
{
namespace
{
using V3 = std::array<double, 3>;

/// Shape functions of the fictive element at reference (s, t, z), z in
/// [-1, 1]: for each shell node k of the cell, {N_k^-, N_k^+}.
void shape(int npc, double s, double t, double z, double* nm, double* np)
{
  double m[4];
  if (npc == 3)
  {
    m[0] = 1.0 - s - t;
    m[1] = s;
    m[2] = t;
  }
  else
  {
    m[0] = (1 - s) * (1 - t);
    m[1] = s * (1 - t);
    m[2] = (1 - s) * t;
    m[3] = s * t;
  }
  for (int k = 0; k < npc; ++k)
  {
    nm[k] = m[k] * 0.5 * (1.0 - z);
    np[k] = m[k] * 0.5 * (1.0 + z);
  }
}

/// Derivatives of the mid-surface functions m_k w.r.t. (s, t).
void dshape(int npc, double s, double t, double* ds, double* dt)
{
  if (npc == 3)
  {
    ds[0] = -1; ds[1] = 1; ds[2] = 0;
    dt[0] = -1; dt[1] = 0; dt[2] = 1;
  }
  else
  {
    ds[0] = -(1 - t); ds[1] = 1 - t; ds[2] = -t; ds[3] = t;
    dt[0] = -(1 - s); dt[1] = -s; dt[2] = 1 - s; dt[3] = s;
  }
}

struct Element
{
  int npc;
  double xm[4][3], xp[4][3]; // fictive nodes (bottom, top) of each shell node
};

V3 map(const Element& e, double s, double t, double z)
{
  double nm[4], np[4];
  shape(e.npc, s, t, z, nm, np);
  V3 x{0, 0, 0};
  for (int k = 0; k < e.npc; ++k)
    for (int i = 0; i < 3; ++i)
      x[i] += nm[k] * e.xm[k][i] + np[k] * e.xp[k][i];
  return x;
}

/// Newton inversion of the isoparametric map; returns false if it fails.
bool invert(const Element& e, const V3& p, V3& ref)
{
  double s = e.npc == 3 ? 1.0 / 3.0 : 0.5, t = s, z = 0.0;
  for (int it = 0; it < 50; ++it)
  {
    const V3 x = map(e, s, t, z);
    const V3 r{p[0] - x[0], p[1] - x[1], p[2] - x[2]};
    double ds[4], dt[4];
    dshape(e.npc, s, t, ds, dt);
    double J[3][3] = {};
    double nm[4], np[4];
    shape(e.npc, s, t, z, nm, np);
    for (int k = 0; k < e.npc; ++k)
      for (int i = 0; i < 3; ++i)
      {
        const double mid = 0.5 * (e.xm[k][i] + e.xp[k][i]);
        const double half = 0.5 * (e.xp[k][i] - e.xm[k][i]);
        J[i][0] += ds[k] * (mid + z * half);
        J[i][1] += dt[k] * (mid + z * half);
        // dm_k/dz = 0; d/dz of (m_k (mid + z half)) = m_k half
        J[i][2] += (nm[k] + np[k]) * half;
      }
    const double det = J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1])
                       - J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0])
                       + J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
    if (!(std::abs(det) > 0.0))
      return false;
    // Cramer's rule
    auto solve = [&](int col)
    {
      double M[3][3];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          M[i][j] = j == col ? r[i] : J[i][j];
      return (M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1])
              - M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0])
              + M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]))
             / det;
    };
    const double d0 = solve(0), d1 = solve(1), d2 = solve(2);
    s += d0;
    t += d1;
    z += d2;
    if (std::abs(d0) + std::abs(d1) + std::abs(d2) < 1e-14)
      break;
  }
  ref = {s, t, z};
  if (!(std::isfinite(s) && std::isfinite(t) && std::isfinite(z)))
    return false;
  // converged only if the point is where the map puts ref: for a point
  // outside a quadrilateral, Newton on the bilinear map may wander and stop
  // anywhere, also inside the reference square, which would place the
  // point in an element far from it
  double size = 0.0;
  for (int k = 1; k < e.npc; ++k)
    for (const auto* x : {e.xm[k], e.xp[k]})
      size = std::max(size, std::hypot(x[0] - e.xm[0][0], x[1] - e.xm[0][1], x[2] - e.xm[0][2]));
  const V3 y = map(e, s, t, z);
  return std::hypot(y[0] - p[0], y[1] - p[1], y[2] - p[2]) <= 1e-9 * size;
}

/// Smallest margin of the reference coordinates (>= 0 inside).
double margin(int npc, const V3& r)
{
  double m = std::min(1.0 - std::abs(r[2]), std::min(r[0], r[1]));
  m = std::min(m, npc == 3 ? 1.0 - r[0] - r[1] : std::min(1.0 - r[0], 1.0 - r[1]));
  return m;
}

V3 clamp(int npc, V3 r)
{
  r[2] = std::clamp(r[2], -1.0, 1.0);
  r[0] = std::clamp(r[0], 0.0, 1.0);
  r[1] = std::clamp(r[1], 0.0, 1.0);
  if (npc == 3 && r[0] + r[1] > 1.0)
  {
    const double excess = 0.5 * (r[0] + r[1] - 1.0);
    r[0] = std::clamp(r[0] - excess, 0.0, 1.0);
    r[1] = 1.0 - r[0];
  }
  return r;
}
/// Result of the search for the element of one point.
struct Found
{
  int cell = -1;      ///< -1: none within reach
  V3 ref{};           ///< reference coordinates (clamped for outside points)
  bool outside = false, ambiguous = false;
  double distance = 0.0; ///< to the nearest element, for outside points
};

using Box = std::array<double, 6>; ///< lower corner (3), upper corner (3)

/// The cells' bounding boxes binned on a uniform grid: the cells whose box
/// holds a point are among those of the point's bin, in increasing index.
/// Bins about the size of the mean box, at most 8 per cell.
class CellBins
{
public:
  explicit CellBins(const std::vector<Box>& box)
  {
    const std::size_t nc = box.size();
    std::array<double, 3> mean{};
    _lo = {1e300, 1e300, 1e300};
    _hi = {-1e300, -1e300, -1e300};
    for (const auto& b : box)
      for (int i = 0; i < 3; ++i)
      {
        _lo[i] = std::min(_lo[i], b[i]);
        _hi[i] = std::max(_hi[i], b[3 + i]);
        mean[i] += (b[3 + i] - b[i]) / double(nc);
      }
    for (int i = 0; i < 3; ++i)
    {
      const double span = _hi[i] - _lo[i];
      _n[i] = span > 0.0 && mean[i] > 0.0 ? std::max<std::int64_t>(1, std::int64_t(std::min(span / mean[i], 1e6))) : 1;
    }
    while (_n[0] * _n[1] * _n[2] > std::int64_t(8 * nc + 8))
    {
      auto& big = *std::max_element(_n.begin(), _n.end());
      big = (big + 1) / 2;
    }
    for (int i = 0; i < 3; ++i)
      _h[i] = _hi[i] > _lo[i] ? (_hi[i] - _lo[i]) / double(_n[i]) : 1.0;
    // CSR: count, then fill in increasing cell index
    _first.assign(_n[0] * _n[1] * _n[2] + 1, 0);
    for (const auto& b : box)
      each_bin(b, [&](std::int64_t k) { ++_first[k + 1]; });
    for (std::size_t k = 1; k < _first.size(); ++k)
      _first[k] += _first[k - 1];
    _cells.resize(_first.back());
    std::vector<std::int64_t> next(_first.begin(), _first.end() - 1);
    for (std::size_t c = 0; c < nc; ++c)
      each_bin(box[c], [&](std::int64_t k) { _cells[next[k]++] = static_cast<std::int32_t>(c); });
  }

  /// The cells of pt's bin (none if pt lies outside every box).
  std::span<const std::int32_t> near(const V3& pt) const
  {
    for (int i = 0; i < 3; ++i)
      if (!(pt[i] >= _lo[i] && pt[i] <= _hi[i]))
        return {};
    const auto b = (bin(0, pt[0]) * _n[1] + bin(1, pt[1])) * _n[2] + bin(2, pt[2]);
    return std::span<const std::int32_t>(_cells).subspan(_first[b], _first[b + 1] - _first[b]);
  }

private:
  /// Bin of coordinate v along axis i (monotone in v, so that a point in a
  /// box falls in one of the box's bins).
  std::int64_t bin(int i, double v) const
  {
    return std::clamp<std::int64_t>(std::int64_t(std::floor((v - _lo[i]) / _h[i])), 0, _n[i] - 1);
  }
  /// f(k) for each bin k that box b meets.
  template <typename F>
  void each_bin(const Box& b, F&& f) const
  {
    for (auto i = bin(0, b[0]); i <= bin(0, b[3]); ++i)
      for (auto j = bin(1, b[1]); j <= bin(1, b[4]); ++j)
        for (auto k = bin(2, b[2]); k <= bin(2, b[5]); ++k)
          f((i * _n[1] + j) * _n[2] + k);
  }
  std::array<double, 3> _lo{}, _hi{}, _h{};
  std::array<std::int64_t, 3> _n{};
  std::vector<std::int64_t> _first;
  std::vector<std::int32_t> _cells;
};

/// The cells' bounding boxes grown by what a point counted inside with
/// reference-coordinate tolerance tol can lie beyond them (a map extended
/// past the reference element by tol moves the point at most a few tol
/// times the cell's size; the inversion places it to 1e-9 of the size).
std::vector<Box> holding_boxes(const std::vector<Box>& box, double tol)
{
  std::vector<Box> out(box);
  for (auto& b : out)
  {
    if (!std::all_of(b.begin(), b.end(), [](double v) { return std::isfinite(v); }))
      throw std::runtime_error("locating points in the FE mesh: a cell has a node coordinate that is not finite");
    const double size = std::max({b[3] - b[0], b[4] - b[1], b[5] - b[2]});
    const double grow = (16.0 * std::max(tol, 0.0) + 1e-6) * size + 1e-12;
    for (int i = 0; i < 3; ++i)
    {
      b[i] -= grow;
      b[3 + i] += grow;
    }
  }
  return out;
}

/// The element of point pt (the rules of the paper's Figure 6, see
/// fictive.h): deepest of the cells containing it, else the nearest
/// (reference coordinates clamped) of those whose bounding box `box` lies
/// within max_distance. `holding`: the cells that can contain pt (CellBins
/// of holding_boxes), in increasing index, as is the scan of all cells for
/// the nearest; a point inside no cell is rare (the overlap lies in the
/// mesh), so that scan costs little.
/// invert(c, pt, r) -> bool, margin(r) -> double (>= 0 inside),
/// nearest(c, r) -> {clamped r, its physical point}.
template <typename Invert, typename Margin, typename Nearest>
Found find_cell(const V3& pt, std::span<const std::int32_t> holding, const std::vector<Box>& box, double maxd,
                double tol, Invert&& invert, Margin&& margin, Nearest&& nearest)
{
  const auto beyond = [&](std::size_t c)
  {
    const auto& b = box[c];
    double out = 0.0;
    for (int i = 0; i < 3; ++i)
      out = std::max({out, b[i] - pt[i], pt[i] - b[3 + i]});
    return out > maxd;
  };
  Found f;
  int inside = 0;
  double best_margin = -1e300;
  for (const std::int32_t c : holding)
  {
    V3 r;
    if (beyond(std::size_t(c)) || !invert(std::size_t(c), pt, r))
      continue;
    const double m = margin(r);
    if (m >= -tol)
    {
      ++inside;
      if (m > best_margin)
      {
        best_margin = m;
        f.cell = c;
        f.ref = r;
      }
    }
  }
  if (f.cell >= 0)
  {
    f.ambiguous = inside > 1;
    return f;
  }
  int best_out = -1;
  double best_dist = 1e300;
  V3 ref_out{};
  for (std::size_t c = 0; c < box.size(); ++c)
  {
    V3 r;
    if (beyond(c) || !invert(c, pt, r) || margin(r) >= -tol) // (a cell holding pt is among `holding`)
      continue;
    const auto [rc, y] = nearest(c, r);
    const double d = std::hypot(y[0] - pt[0], y[1] - pt[1], y[2] - pt[2]);
    if (d < best_dist)
    {
      best_dist = d;
      best_out = static_cast<int>(c);
      ref_out = rc;
    }
  }
  f.distance = best_dist;
  if (best_out >= 0 && best_dist <= maxd)
  {
    f.cell = best_out;
    f.ref = ref_out;
    f.outside = true;
  }
  return f;
}

[[noreturn]] void unplaced(std::size_t p, const V3& x, double maxd, const char* what)
{
  std::ostringstream s;
  s << "particle " << p << " at (" << x[0] << ", " << x[1] << ", " << x[2] << ") lies in no "
    << what << " element and is farther than " << maxd
    << " m from all of them: check the overlap region against the FE mesh";
  throw std::runtime_error(s.str());
}
} // namespace

std::vector<double> fictive_nodes(const ShellGeometry& g)
{
  if (!(g.thickness > 0.0))
    throw std::runtime_error("fictive nodes: thickness " + std::to_string(g.thickness)
                             + " m must be > 0");
  const std::size_t n = g.x.size() / 3;
  if (g.normals.size() != g.x.size())
    throw std::runtime_error("fictive nodes: normals and coordinates differ in size");
  std::vector<double> f(6 * n);
  for (std::size_t k = 0; k < n; ++k)
    for (int i = 0; i < 3; ++i)
    {
      f[6 * k + i] = g.x[3 * k + i] - 0.5 * g.thickness * g.normals[3 * k + i];
      f[6 * k + 3 + i] = g.x[3 * k + i] + 0.5 * g.thickness * g.normals[3 * k + i];
    }
  return f;
}

CouplingOperator locate(const ShellGeometry& g, std::span<const double> points,
                        const LocateOptions& opt)
{
  const int npc = g.nodes_per_cell;
  if (npc != 3 && npc != 4)
    throw std::runtime_error("fictive elements need triangles (3 nodes) or quadrilaterals (4)");
  const auto fict = fictive_nodes(g);
  const std::size_t ncell = g.cells.size() / npc, np = points.size() / 3;
  const double maxd = opt.max_distance >= 0.0 ? opt.max_distance : g.thickness;
  // elements and their bounding boxes
  std::vector<Element> el(ncell);
  std::vector<Box> box(ncell);
  for (std::size_t c = 0; c < ncell; ++c)
  {
    el[c].npc = npc;
    auto& b = box[c];
    b = {1e300, 1e300, 1e300, -1e300, -1e300, -1e300};
    for (int k = 0; k < npc; ++k)
    {
      const auto node = g.cells[c * npc + k];
      for (int i = 0; i < 3; ++i)
      {
        el[c].xm[k][i] = fict[6 * node + i];
        el[c].xp[k][i] = fict[6 * node + 3 + i];
        for (double v : {el[c].xm[k][i], el[c].xp[k][i]})
        {
          b[i] = std::min(b[i], v);
          b[3 + i] = std::max(b[3 + i], v);
        }
      }
    }
  }
  CouplingOperator op;
  op._npc = npc;
  const double tol = opt.tolerance;
  const CellBins bins(holding_boxes(box, tol));
  for (std::size_t p = 0; p < np; ++p)
  {
    const V3 x{points[3 * p], points[3 * p + 1], points[3 * p + 2]};
    const Found f = find_cell(
        x, bins.near(x), box, maxd, tol, [&](std::size_t c, const V3& pt, V3& r) { return invert(el[c], pt, r); },
        [&](const V3& r) { return margin(npc, r); },
        [&](std::size_t c, const V3& r)
        {
          const V3 rc = clamp(npc, r);
          return std::pair{rc, map(el[c], rc[0], rc[1], rc[2])};
        });
    if (f.cell < 0)
      unplaced(p, x, maxd, "fictive");
    op._outside += f.outside;
    op._ambiguous += f.ambiguous;
    const int cell = f.cell;
    const V3 ref = f.ref;
    op._cell.push_back(cell);
    op._ref.insert(op._ref.end(), ref.begin(), ref.end());
    double nm[4], npl[4];
    shape(npc, ref[0], ref[1], ref[2], nm, npl);
    for (int k = 0; k < npc; ++k)
    {
      const auto node = g.cells[cell * npc + k];
      op._nodes.push_back(node);
      op._a.push_back(nm[k] + npl[k]);
      op._b.push_back(0.5 * g.thickness * (npl[k] - nm[k]));
      for (int i = 0; i < 3; ++i)
        op._n.push_back(g.normals[3 * node + i]);
    }
  }
  return op;
}

void CouplingOperator::interpolate(std::span<const double> u, std::span<double> v) const
{
  const std::size_t np = size();
  for (std::size_t p = 0; p < np; ++p)
  {
    double out[3] = {0, 0, 0};
    for (int k = 0; k < _npc; ++k)
    {
      const std::size_t q = p * _npc + k;
      const double* uj = &u[_bs * _nodes[q]];
      if (_bs == 3)
      {
        for (int i = 0; i < 3; ++i)
          out[i] += _a[q] * uj[i];
        continue;
      }
      const double* w = uj + 3;
      const double* n = &_n[3 * q];
      const double wxn[3] = {w[1] * n[2] - w[2] * n[1], w[2] * n[0] - w[0] * n[2],
                             w[0] * n[1] - w[1] * n[0]};
      for (int i = 0; i < 3; ++i)
        out[i] += _a[q] * uj[i] + _b[q] * wxn[i];
    }
    for (int i = 0; i < 3; ++i)
      v[3 * p + i] = out[i];
  }
}

void CouplingOperator::add_transpose(std::span<const double> f, std::span<double> fs) const
{
  const std::size_t np = size();
  for (std::size_t p = 0; p < np; ++p)
  {
    const double* fp = &f[3 * p];
    for (int k = 0; k < _npc; ++k)
    {
      const std::size_t q = p * _npc + k;
      double* out = &fs[_bs * _nodes[q]];
      if (_bs == 3)
      {
        for (int i = 0; i < 3; ++i)
          out[i] += _a[q] * fp[i];
        continue;
      }
      const double* n = &_n[3 * q];
      // <b (w x n), f> = <w, b (n x f)>: the moment is b n x f
      const double nxf[3] = {n[1] * fp[2] - n[2] * fp[1], n[2] * fp[0] - n[0] * fp[2],
                             n[0] * fp[1] - n[1] * fp[0]};
      for (int i = 0; i < 3; ++i)
      {
        out[i] += _a[q] * fp[i];
        out[3 + i] += _b[q] * nxf[i];
      }
    }
  }
}

namespace
{
/// P1 solid cell: shape functions at reference r (tet: barycentric on the
/// unit simplex; hex: trilinear on [0, 1]^3, tensor order).
void solid_shape(int npc, const V3& r, double* N, double (*dN)[3])
{
  if (npc == 4)
  {
    N[0] = 1.0 - r[0] - r[1] - r[2];
    N[1] = r[0];
    N[2] = r[1];
    N[3] = r[2];
    const double d[4][3] = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int k = 0; k < 4; ++k)
      for (int i = 0; i < 3; ++i)
        dN[k][i] = d[k][i];
    return;
  }
  for (int k = 0; k < 8; ++k)
  {
    const int bx = k & 1, by = (k >> 1) & 1, bz = (k >> 2) & 1;
    const double fx = bx ? r[0] : 1 - r[0], fy = by ? r[1] : 1 - r[1], fz = bz ? r[2] : 1 - r[2];
    const double gx = bx ? 1 : -1, gy = by ? 1 : -1, gz = bz ? 1 : -1;
    N[k] = fx * fy * fz;
    dN[k][0] = gx * fy * fz;
    dN[k][1] = fx * gy * fz;
    dN[k][2] = fx * fy * gz;
  }
}

bool solid_invert(int npc, const double (*X)[3], const V3& p, V3& r)
{
  r = npc == 4 ? V3{0.25, 0.25, 0.25} : V3{0.5, 0.5, 0.5};
  for (int it = 0; it < 50; ++it)
  {
    double N[8], dN[8][3];
    solid_shape(npc, r, N, dN);
    double x[3] = {0, 0, 0}, J[3][3] = {};
    for (int k = 0; k < npc; ++k)
      for (int i = 0; i < 3; ++i)
      {
        x[i] += N[k] * X[k][i];
        for (int j = 0; j < 3; ++j)
          J[i][j] += dN[k][j] * X[k][i];
      }
    const double res[3] = {p[0] - x[0], p[1] - x[1], p[2] - x[2]};
    const double det = J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1])
                       - J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0])
                       + J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
    if (!(std::abs(det) > 0.0))
      return false;
    double d[3];
    for (int col = 0; col < 3; ++col)
    {
      double M[3][3];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          M[i][j] = j == col ? res[i] : J[i][j];
      d[col] = (M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1])
                - M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0])
                + M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]))
               / det;
    }
    for (int i = 0; i < 3; ++i)
      r[i] += d[i];
    if (std::abs(d[0]) + std::abs(d[1]) + std::abs(d[2]) < 1e-14)
      break;
  }
  if (!(std::isfinite(r[0]) && std::isfinite(r[1]) && std::isfinite(r[2])))
    return false;
  // converged only if the map puts r at p (as the shells' invert): Newton
  // stopped unconverged could leave r anywhere, also inside the cell
  double N[8], dN[8][3], x[3] = {0, 0, 0}, size = 0.0;
  solid_shape(npc, r, N, dN);
  for (int k = 0; k < npc; ++k)
    for (int i = 0; i < 3; ++i)
    {
      x[i] += N[k] * X[k][i];
      size = std::max(size, std::abs(X[k][i] - X[0][i]));
    }
  return std::hypot(x[0] - p[0], x[1] - p[1], x[2] - p[2]) <= 1e-9 * size;
}

double solid_margin(int npc, const V3& r)
{
  if (npc == 4)
    return std::min({r[0], r[1], r[2], 1.0 - r[0] - r[1] - r[2]});
  return std::min({r[0], r[1], r[2], 1.0 - r[0], 1.0 - r[1], 1.0 - r[2]});
}

V3 solid_clamp(int npc, V3 r)
{
  for (auto& c : r)
    c = std::clamp(c, 0.0, 1.0);
  if (npc == 4)
  {
    const double s = r[0] + r[1] + r[2];
    if (s > 1.0)
      for (auto& c : r)
        c /= s;
  }
  return r;
}
} // namespace

CouplingOperator locate_in_solid(std::span<const double> x, std::span<const std::int32_t> cells,
                                 int npc, std::span<const double> points, const LocateOptions& opt)
{
  if (npc != 4 && npc != 8)
    throw std::runtime_error("solid coupling needs P1 tetrahedra (4 nodes) or hexahedra (8)");
  const std::size_t ncell = cells.size() / npc, np = points.size() / 3;
  std::vector<Box> box(ncell);
  double size = 0.0;
  for (std::size_t c = 0; c < ncell; ++c)
  {
    auto& b = box[c];
    b = {1e300, 1e300, 1e300, -1e300, -1e300, -1e300};
    for (int k = 0; k < npc; ++k)
      for (int i = 0; i < 3; ++i)
      {
        const double v = x[3 * cells[c * npc + k] + i];
        b[i] = std::min(b[i], v);
        b[3 + i] = std::max(b[3 + i], v);
      }
    for (int i = 0; i < 3; ++i)
      size = std::max(size, b[3 + i] - b[i]);
  }
  const double maxd = opt.max_distance >= 0.0 ? opt.max_distance : 0.1 * size;
  CouplingOperator op;
  op._npc = npc;
  op._bs = 3;
  const CellBins bins(holding_boxes(box, opt.tolerance));
  for (std::size_t p = 0; p < np; ++p)
  {
    const V3 pt{points[3 * p], points[3 * p + 1], points[3 * p + 2]};
    auto nodes_of = [&](std::size_t c, double (*X)[3])
    {
      for (int k = 0; k < npc; ++k)
        for (int i = 0; i < 3; ++i)
          X[k][i] = x[3 * cells[c * npc + k] + i];
    };
    const Found f = find_cell(
        pt, bins.near(pt), box, maxd, opt.tolerance,
        [&](std::size_t c, const V3& q, V3& r)
        {
          double X[8][3];
          nodes_of(c, X);
          return solid_invert(npc, X, q, r);
        },
        [&](const V3& r) { return solid_margin(npc, r); },
        [&](std::size_t c, const V3& r)
        {
          double X[8][3], N[8], dN[8][3];
          nodes_of(c, X);
          const V3 rc = solid_clamp(npc, r);
          solid_shape(npc, rc, N, dN);
          V3 y{0, 0, 0};
          for (int k = 0; k < npc; ++k)
            for (int i = 0; i < 3; ++i)
              y[i] += N[k] * X[k][i];
          return std::pair{rc, y};
        });
    if (f.cell < 0)
      unplaced(p, pt, maxd, "solid");
    op._outside += f.outside;
    op._ambiguous += f.ambiguous;
    const int cell = f.cell;
    const V3 ref = f.ref;
    op._cell.push_back(cell);
    op._ref.insert(op._ref.end(), ref.begin(), ref.end());
    double N[8], dN[8][3];
    solid_shape(npc, ref, N, dN);
    for (int k = 0; k < npc; ++k)
    {
      op._nodes.push_back(cells[cell * npc + k]);
      op._a.push_back(N[k]);
      op._b.push_back(0.0);
      op._n.insert(op._n.end(), {0.0, 0.0, 0.0});
    }
  }
  return op;
}

} // namespace dembridge::bridge
