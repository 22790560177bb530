#include "dembridge/dem/neighbours.h"

#include <algorithm>
#include <omp.h>

#include "pairs.h"
#include "threads.h"
#include <cmath>
#include <stdexcept>
#include <string>

namespace dembridge::dem
{

CellGrid::CellGrid(std::span<const double> x, double cell, std::span<const std::uint8_t> skip)
{
  if (!(cell > 0.0))
    throw std::runtime_error("cell grid: cell size " + std::to_string(cell) + " must be > 0");
  const std::size_t n = x.size() / 3;
  auto kept = [&](std::size_t i) { return skip.empty() || !skip[i]; };
  double hi[3];
  std::size_t first = 0;
  while (first < n && !kept(first))
    ++first;
  for (int k = 0; k < 3; ++k)
  {
    _lo[k] = first < n ? x[3 * first + k] : 0.0;
    hi[k] = _lo[k];
  }
  std::size_t count = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    if (!kept(i))
      continue;
    ++count;
    for (int k = 0; k < 3; ++k)
    {
      _lo[k] = std::min(_lo[k], x[3 * i + k]);
      hi[k] = std::max(hi[k], x[3 * i + k]);
    }
  }
  // cap the grid size for very spread-out sets (cells stay >= `cell`)
  _h = cell;
  std::size_t total = 1;
  for (int k = 0; k < 3; ++k)
  {
    _n[k] = std::max(1, static_cast<int>((hi[k] - _lo[k]) / _h) + 1);
    total *= _n[k];
  }
  while (total > 4 * count + 64)
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
    if (!kept(i))
      continue;
    id[i] = (std::size_t(cell_of(x[3 * i], 0)) * _n[1] + cell_of(x[3 * i + 1], 1)) * _n[2]
            + cell_of(x[3 * i + 2], 2);
    ++_start[id[i] + 1];
  }
  for (std::size_t c = 0; c < total; ++c)
    _start[c + 1] += _start[c];
  _items.resize(count);
  std::vector<std::int32_t> fill(_start.begin(), _start.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
    if (kept(i))
      _items[fill[id[i]]++] = static_cast<std::int32_t>(i);
}

int CellGrid::cell_of(double v, int k) const
{
  // clamped before the conversion: a far (or infinite) coordinate lies in
  // an edge cell
  const double c = (v - _lo[k]) / _h;
  return c <= 0.0 ? 0 : c >= _n[k] - 1 ? _n[k] - 1 : static_cast<int>(c);
}

NeighbourList::NeighbourList(double skin) : _skin(skin)
{
  if (!(skin > 0.0))
    throw std::runtime_error("neighbour skin " + std::to_string(skin) + " m: must be > 0");
}

bool NeighbourList::update(std::span<const double> x, std::span<const double> r,
                           const Links& links, std::span<const std::uint8_t> skip)
{
  const std::size_t np = r.size();
  if (_builds > 0 && _x_build.size() == x.size() && !_stale)
  {
    double max2 = 0.0;
#pragma omp parallel for schedule(static) reduction(max : max2) num_threads(impl::threads_for(np))
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
  _cell = 2.0 * rmax + _skin;
  _grid.emplace(x, _cell, skip);
  _stale = false;
  _skip.assign(skip.begin(), skip.end());
  const CellGrid& grid = *_grid;
  // links sorted by (a, b): those of sphere i as a are a contiguous range
  const std::vector<std::int32_t> first = impl::first_by_a(np, links.a, links.b, "neighbour list: links");
  // each thread searches a contiguous block of spheres (static schedule), so
  // the blocks joined in thread order give the same list for any thread count
  struct Found
  {
    std::vector<std::int32_t> a, b, link;
  };
  std::vector<Found> chunk;
#pragma omp parallel num_threads(impl::threads_for(np))
  {
#pragma omp single
    chunk.resize(omp_get_num_threads());
    Found& out = chunk[omp_get_thread_num()];
    std::vector<std::int32_t> near;
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < np; ++i)
    {
      if (!skip.empty() && skip[i])
        continue; // left out: not in the grid either
      near.clear();
      grid.for_each_later_near(x, i,
                               [&](std::int32_t j, double d2)
                               {
                                 const double lim = r[i] + r[j] + _skin;
                                 if (d2 < lim * lim)
                                   near.push_back(j);
                               });
      std::sort(near.begin(), near.end());
      std::int32_t k = first[i];
      for (auto j : near)
      {
        while (k < first[i + 1] && links.b[k] < j)
          ++k;
        const bool linked = k < first[i + 1] && links.b[k] == j;
        if (linked && links.state[k] == LinkState::intact)
          continue;
        out.a.push_back(static_cast<std::int32_t>(i));
        out.b.push_back(j);
        out.link.push_back(linked ? k : -1);
      }
    }
  }
  std::size_t total = 0;
  for (const auto& f : chunk)
    total += f.a.size();
  std::vector<std::int32_t> na, nb, nl;
  na.reserve(total);
  nb.reserve(total);
  nl.reserve(total);
  for (const auto& f : chunk)
  {
    na.insert(na.end(), f.a.begin(), f.a.end());
    nb.insert(nb.end(), f.b.begin(), f.b.end());
    nl.insert(nl.end(), f.link.begin(), f.link.end());
  }
  // carry the contact history over (both lists sorted by (a, b))
  std::vector<double> nfs(3 * na.size(), 0.0), nn(3 * na.size(), 0.0);
  std::vector<std::uint8_t> nt(na.size(), 0);
  std::size_t q = 0;
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
  }
  replace(std::move(na), std::move(nb), std::move(nl), std::move(nfs), std::move(nn),
          std::move(nt));
  _x_build.assign(x.begin(), x.end());
  ++_builds;
  return true;
}

void NeighbourList::replace(std::vector<std::int32_t>&& na, std::vector<std::int32_t>&& nb,
                            std::vector<std::int32_t>&& nl, std::vector<double>&& nfs,
                            std::vector<double>&& nn, std::vector<std::uint8_t>&& nt)
{
  a = std::move(na);
  b = std::move(nb);
  link = std::move(nl);
  fs = std::move(nfs);
  n = std::move(nn);
  touching = std::move(nt);
  ++_version;
}

void NeighbourList::add_broken_links(const Links& links, std::span<const std::int32_t> ids)
{
  if (ids.empty())
    return;
  const std::size_t m = a.size() + ids.size();
  std::vector<std::int32_t> na, nb, nl;
  std::vector<double> nfs, nn;
  std::vector<std::uint8_t> nt;
  na.reserve(m);
  nb.reserve(m);
  nl.reserve(m);
  nfs.reserve(3 * m);
  nn.reserve(3 * m);
  nt.reserve(m);
  auto keep = [&](std::size_t q)
  {
    na.push_back(a[q]);
    nb.push_back(b[q]);
    nl.push_back(link[q]);
    nfs.insert(nfs.end(), &fs[3 * q], &fs[3 * q] + 3);
    nn.insert(nn.end(), &n[3 * q], &n[3 * q] + 3);
    nt.push_back(touching[q]);
  };
  std::size_t q = 0;
  for (const std::int32_t k : ids)
  {
    const std::int32_t ka = links.a[k], kb = links.b[k];
    while (q < a.size() && (a[q] < ka || (a[q] == ka && b[q] < kb)))
      keep(q++);
    if (q < a.size() && a[q] == ka && b[q] == kb)
      continue; // already listed
    na.push_back(ka);
    nb.push_back(kb);
    nl.push_back(k);
    nfs.insert(nfs.end(), 3, 0.0);
    nn.insert(nn.end(), 3, 0.0);
    nt.push_back(0);
  }
  while (q < a.size())
    keep(q++);
  replace(std::move(na), std::move(nb), std::move(nl), std::move(nfs), std::move(nn),
          std::move(nt));
}

std::size_t NeighbourList::bytes() const
{
  return (a.capacity() + b.capacity() + link.capacity()) * sizeof(std::int32_t)
         + (fs.capacity() + n.capacity() + _x_build.capacity()) * sizeof(double)
         + touching.capacity() + (_grid ? _grid->bytes() : 0);
}

} // namespace dembridge::dem
