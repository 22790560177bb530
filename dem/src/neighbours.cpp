#include "dembridge/dem/neighbours.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace dembridge::dem
{

CellGrid::CellGrid(std::span<const double> x, double cell)
{
  if (!(cell > 0.0))
    throw std::runtime_error("cell grid: cell size " + std::to_string(cell) + " must be > 0");
  const std::size_t n = x.size() / 3;
  double hi[3];
  for (int k = 0; k < 3; ++k)
  {
    _lo[k] = n ? x[k] : 0.0;
    hi[k] = _lo[k];
  }
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k)
    {
      _lo[k] = std::min(_lo[k], x[3 * i + k]);
      hi[k] = std::max(hi[k], x[3 * i + k]);
    }
  // cap the grid size for very spread-out sets (cells stay >= `cell`)
  _h = cell;
  std::size_t total = 1;
  for (int k = 0; k < 3; ++k)
  {
    _n[k] = std::max(1, static_cast<int>((hi[k] - _lo[k]) / _h) + 1);
    total *= _n[k];
  }
  while (total > 4 * n + 64)
  {
    _h *= 1.26;
    total = 1;
    for (int k = 0; k < 3; ++k)
    {
      _n[k] = std::max(1, static_cast<int>((hi[k] - _lo[k]) / _h) + 1);
      total *= _n[k];
    }
  }
  _start.assign(total + 1, 0);
  std::vector<std::size_t> id(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    id[i] = (std::size_t(cell_of(x[3 * i], 0)) * _n[1] + cell_of(x[3 * i + 1], 1)) * _n[2]
            + cell_of(x[3 * i + 2], 2);
    ++_start[id[i] + 1];
  }
  for (std::size_t c = 0; c < total; ++c)
    _start[c + 1] += _start[c];
  _items.resize(n);
  std::vector<std::int32_t> fill(_start.begin(), _start.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
    _items[fill[id[i]]++] = static_cast<std::int32_t>(i);
}

int CellGrid::cell_of(double v, int k) const
{
  const int c = static_cast<int>((v - _lo[k]) / _h);
  return std::clamp(c, 0, _n[k] - 1);
}

NeighbourList::NeighbourList(double skin) : _skin(skin)
{
  if (!(skin > 0.0))
    throw std::runtime_error("neighbour skin " + std::to_string(skin) + " m: must be > 0");
}

bool NeighbourList::update(std::span<const double> x, std::span<const double> r,
                           std::span<const std::int32_t> link_a,
                           std::span<const std::int32_t> link_b)
{
  const std::size_t np = r.size();
  if (_builds > 0 && _x_build.size() == x.size())
  {
    double max2 = 0.0;
    for (std::size_t i = 0; i < np; ++i)
    {
      const double dx = x[3 * i] - _x_build[3 * i], dy = x[3 * i + 1] - _x_build[3 * i + 1],
                   dz = x[3 * i + 2] - _x_build[3 * i + 2];
      max2 = std::max(max2, dx * dx + dy * dy + dz * dz);
    }
    if (max2 < 0.25 * _skin * _skin)
      return false;
  }
  const double rmax = np ? *std::max_element(r.begin(), r.end()) : 0.0;
  CellGrid grid(x, 2.0 * rmax + _skin);
  std::vector<std::int32_t> na, nb;
  std::vector<std::int32_t> found;
  for (std::size_t i = 0; i < np; ++i)
  {
    found.clear();
    grid.for_each_later_near(x, i,
                             [&](std::int32_t j, double d2)
                             {
                               const double lim = r[i] + r[j] + _skin;
                               if (d2 < lim * lim)
                                 found.push_back(j);
                             });
    std::sort(found.begin(), found.end());
    for (auto j : found)
    {
      na.push_back(static_cast<std::int32_t>(i));
      nb.push_back(j);
    }
  }
  // carry the contact history over (both lists sorted by (a, b))
  std::vector<double> nfs(3 * na.size(), 0.0), nn(3 * na.size(), 0.0);
  std::vector<std::uint8_t> nt(na.size(), 0);
  std::vector<std::int32_t> nl(na.size(), -1);
  std::size_t q = 0, l = 0;
  for (std::size_t p = 0; p < na.size(); ++p)
  {
    while (q < a.size() && (a[q] < na[p] || (a[q] == na[p] && b[q] < nb[p])))
      ++q;
    if (q < a.size() && a[q] == na[p] && b[q] == nb[p])
    {
      for (int k = 0; k < 3; ++k)
      {
        nfs[3 * p + k] = fs[3 * q + k];
        nn[3 * p + k] = n[3 * q + k];
      }
      nt[p] = touching[q];
    }
    while (l < link_a.size() && (link_a[l] < na[p] || (link_a[l] == na[p] && link_b[l] < nb[p])))
      ++l;
    if (l < link_a.size() && link_a[l] == na[p] && link_b[l] == nb[p])
      nl[p] = static_cast<std::int32_t>(l);
  }
  a = std::move(na);
  b = std::move(nb);
  fs = std::move(nfs);
  n = std::move(nn);
  touching = std::move(nt);
  link = std::move(nl);
  _x_build.assign(x.begin(), x.end());
  ++_builds;
  return true;
}

} // namespace dembridge::dem
