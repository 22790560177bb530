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
  if (_builds == 0 || _x_build.size() != x.size() || _stale)
  {
    build(x, r, links, skip);
    return true;
  }
  // the movers, in increasing order (each thread a contiguous block, the
  // blocks joined in thread order)
  const double lim2 = mover_share * mover_share * _skin * _skin;
  std::vector<std::vector<std::int32_t>> found(omp_get_max_threads());
#pragma omp parallel num_threads(impl::threads_for(np))
  {
    std::vector<std::int32_t>& mine = found[omp_get_thread_num()];
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < np; ++i)
    {
      const double dx = x[3 * i] - _x_build[3 * i], dy = x[3 * i + 1] - _x_build[3 * i + 1],
                   dz = x[3 * i + 2] - _x_build[3 * i + 2];
      if (dx * dx + dy * dy + dz * dz > lim2 && (skip.empty() || !skip[i]))
        mine.push_back(static_cast<std::int32_t>(i));
    }
  }
  std::vector<std::int32_t> movers;
  for (const auto& f : found)
    movers.insert(movers.end(), f.begin(), f.end());
  if (movers.empty())
    return false;
  if (movers.size() > np / 8)
    build(x, r, links, skip);
  else
    search_movers(x, r, links, movers);
  return true;
}

namespace
{
/// Pairs (a, b, link) found by one thread.
struct Found
{
  std::vector<std::int32_t> a, b, link;
  void push(std::int32_t i, std::int32_t j, std::int32_t k)
  {
    a.push_back(i);
    b.push_back(j);
    link.push_back(k);
  }
};

/// The threads' pairs joined in thread order.
Found joined(const std::vector<Found>& chunks)
{
  Found all;
  std::size_t total = 0;
  for (const auto& f : chunks)
    total += f.a.size();
  all.a.reserve(total);
  all.b.reserve(total);
  all.link.reserve(total);
  for (const auto& f : chunks)
  {
    all.a.insert(all.a.end(), f.a.begin(), f.a.end());
    all.b.insert(all.b.end(), f.b.begin(), f.b.end());
    all.link.insert(all.link.end(), f.link.begin(), f.link.end());
  }
  return all;
}

/// Index of the link joining a < b (links sorted by (a, b)), or -1.
std::int32_t find_link(const Links& links, std::int32_t a, std::int32_t b)
{
  std::size_t lo = 0, hi = links.size();
  while (lo < hi)
  {
    const std::size_t mid = (lo + hi) / 2;
    if (links.a[mid] < a || (links.a[mid] == a && links.b[mid] < b))
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < links.size() && links.a[lo] == a && links.b[lo] == b ? static_cast<std::int32_t>(lo) : -1;
}
} // namespace

void NeighbourList::search_movers(std::span<const double> x, std::span<const double> r,
                                  const Links& links, const std::vector<std::int32_t>& movers)
{
  const std::size_t np = r.size();
  _grid.emplace(x, _cell, _skip);
  const CellGrid& grid = *_grid;
  std::vector<std::uint8_t> moving(np, 0);
  for (auto m : movers)
    moving[m] = 1;
  // each mover's pairs with every sphere (a pair of two movers found by the
  // lower one), as (a, b, link); each thread a contiguous block of movers
  std::vector<Found> chunk(omp_get_max_threads());
#pragma omp parallel num_threads(impl::threads_for(movers.size()))
  {
    Found& out = chunk[omp_get_thread_num()];
#pragma omp for schedule(static)
    for (std::size_t q = 0; q < movers.size(); ++q)
    {
      const std::int32_t m = movers[q];
      grid.for_each_near(&x[3 * m],
                         [&](std::int32_t j)
                         {
                           if (j == m || (moving[j] && j < m))
                             return;
                           const double dx = x[3 * j] - x[3 * m], dy = x[3 * j + 1] - x[3 * m + 1],
                                        dz = x[3 * j + 2] - x[3 * m + 2];
                           const double lim = r[m] + r[j] + _skin;
                           if (dx * dx + dy * dy + dz * dz >= lim * lim)
                             return;
                           const std::int32_t lo = std::min(m, j), hi = std::max(m, j);
                           const std::int32_t k = find_link(links, lo, hi);
                           if (k >= 0 && links.state[k] == LinkState::intact)
                             return;
                           out.push(lo, hi, k);
                         });
    }
  }
  // sorted by (a, b), as merge() takes them
  const Found add = joined(chunk);
  std::vector<std::size_t> order(add.a.size());
  for (std::size_t k = 0; k < order.size(); ++k)
    order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t u, std::size_t v)
            { return add.a[u] < add.a[v] || (add.a[u] == add.a[v] && add.b[u] < add.b[v]); });
  Found sorted;
  for (const std::size_t k : order)
    sorted.push(add.a[k], add.b[k], add.link[k]);
  merge(sorted.a, sorted.b, sorted.link, moving, false);
  for (auto m : movers)
    for (int k = 0; k < 3; ++k)
      _x_build[3 * m + k] = x[3 * m + k];
  _x_grid.assign(x.begin(), x.end());
  ++_builds;
  ++_partial;
}

void NeighbourList::build(std::span<const double> x, std::span<const double> r, const Links& links,
                          std::span<const std::uint8_t> skip)
{
  const std::size_t np = r.size();
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
        out.push(static_cast<std::int32_t>(i), j, linked ? k : -1);
      }
    }
  }
  // the new list, with the history of the pairs listed before
  const Found all = joined(chunk);
  merge(all.a, all.b, all.link, {}, true);
  _x_build.assign(x.begin(), x.end());
  _x_grid.assign(x.begin(), x.end());
  ++_builds;
}

void NeighbourList::replace(std::vector<std::int32_t>&& na, std::vector<std::int32_t>&& nb,
                            std::vector<std::int32_t>&& nl, std::vector<double>&& nfs,
                            std::vector<double>&& nmr, std::vector<double>&& nn,
                            std::vector<std::uint8_t>&& nt)
{
  a = std::move(na);
  b = std::move(nb);
  link = std::move(nl);
  fs = std::move(nfs);
  mr = std::move(nmr);
  n = std::move(nn);
  touching = std::move(nt);
  ++_version;
}

void NeighbourList::merge(std::span<const std::int32_t> na, std::span<const std::int32_t> nb,
                          std::span<const std::int32_t> nlink, std::span<const std::uint8_t> moving,
                          bool replace_all)
{
  // the new pairs (sorted by (a, b)) go in order among the listed ones; a
  // listed pair of a mover (of any sphere with replace_all) is dropped
  // unless it is among the new ones, and then keeps its history (a touching
  // pair always is: its gap is below the skin); a new pair already listed
  // keeps the listed one's history. Written into arrays of the largest size
  // the list can have, then cut: no growth in the step loop.
  auto drops = [&](std::size_t q) { return replace_all || (!moving.empty() && (moving[a[q]] || moving[b[q]])); };
  auto before = [&](std::size_t q, std::size_t p) { return a[q] < na[p] || (a[q] == na[p] && b[q] < nb[p]); };
  auto same = [&](std::size_t q, std::size_t p) { return a[q] == na[p] && b[q] == nb[p]; };
  const std::size_t total = (replace_all ? 0 : a.size()) + na.size(); // at most; cut to size below
  std::vector<std::int32_t> oa(total), ob(total), ol(total);
  std::vector<double> ofs(3 * total, 0.0), on(3 * total, 0.0), omr(_rolling ? 3 * total : 0, 0.0);
  std::vector<std::uint8_t> ot(total, 0);
  auto copy_old = [&](std::size_t q, std::size_t o, std::int32_t link_index)
  {
    oa[o] = a[q];
    ob[o] = b[q];
    ol[o] = link_index;
    std::copy_n(&fs[3 * q], 3, &ofs[3 * o]);
    if (_rolling)
      std::copy_n(&mr[3 * q], 3, &omr[3 * o]);
    std::copy_n(&n[3 * q], 3, &on[3 * o]);
    ot[o] = touching[q];
  };
  std::size_t o = 0;
  for (std::size_t q = 0, p = 0; q < a.size() || p < na.size();)
  {
    if (p == na.size() || (q < a.size() && before(q, p)))
    {
      if (!drops(q))
        copy_old(q, o++, link[q]);
      ++q;
      continue;
    }
    if (q < a.size() && same(q, p))
      copy_old(q++, o, nlink[p]);
    else
    {
      oa[o] = na[p];
      ob[o] = nb[p];
      ol[o] = nlink[p];
    }
    ++o;
    ++p;
  }
  oa.resize(o);
  ob.resize(o);
  ol.resize(o);
  ofs.resize(3 * o);
  if (_rolling)
    omr.resize(3 * o);
  on.resize(3 * o);
  ot.resize(o);
  replace(std::move(oa), std::move(ob), std::move(ol), std::move(ofs), std::move(omr), std::move(on),
          std::move(ot));
}

void NeighbourList::add_broken_links(const Links& links, std::span<const std::int32_t> ids)
{
  if (ids.empty())
    return;
  std::vector<std::int32_t> na(ids.size()), nb(ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k)
  {
    na[k] = links.a[ids[k]];
    nb[k] = links.b[ids[k]];
  }
  merge(na, nb, ids, {}, false);
}

void NeighbourList::keep_rolling()
{
  if (_rolling)
    return;
  _rolling = true;
  mr.assign(3 * a.size(), 0.0);
}

std::size_t NeighbourList::bytes() const
{
  return (a.capacity() + b.capacity() + link.capacity()) * sizeof(std::int32_t)
         + (fs.capacity() + mr.capacity() + n.capacity() + _x_build.capacity() + _x_grid.capacity()) * sizeof(double)
         + touching.capacity() + (_grid ? _grid->bytes() : 0);
}

} // namespace dembridge::dem
