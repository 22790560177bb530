#include "dembridge/dem/neighbours.h"

#include <algorithm>
#include <omp.h>

#include "pairs.h"
#include "threads.h"
#include <cmath>
#include <limits>
#include <ranges>
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
  // the bounds of the kept centres (min and max: the same in any order, but
  // for the sign of a zero bound, which changes no cell)
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k)
  {
    lo[k] = std::numeric_limits<double>::infinity();
    hi[k] = -lo[k];
  }
  std::size_t count = 0;
#pragma omp parallel for schedule(static) reduction(min : lo[:3]) reduction(max : hi[:3]) reduction(+ : count) \
  num_threads(impl::threads_for(n))
  for (std::size_t i = 0; i < n; ++i)
  {
    if (!kept(i))
      continue;
    ++count;
    for (int k = 0; k < 3; ++k)
    {
      lo[k] = std::min(lo[k], x[3 * i + k]);
      hi[k] = std::max(hi[k], x[3 * i + k]);
    }
  }
  for (int k = 0; k < 3; ++k)
  {
    _lo[k] = count ? lo[k] : 0.0;
    if (!count)
      hi[k] = 0.0;
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
#pragma omp parallel for schedule(static) num_threads(impl::threads_for(n))
  for (std::size_t i = 0; i < n; ++i)
    if (kept(i))
      id[i] = (std::size_t(cell_of(x[3 * i], 0)) * _n[1] + cell_of(x[3 * i + 1], 1)) * _n[2]
              + cell_of(x[3 * i + 2], 2);
  for (std::size_t i = 0; i < n; ++i)
    if (kept(i))
      ++_start[id[i] + 1];
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
                           const Links& links, std::span<const std::uint8_t> skip, bool defer)
{
  if (_pending) // a deferred search nobody merged: merge it first
    add_broken_links(links, {});
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
  if (movers.empty() && _dropped.empty())
    return false;
  if (movers.size() > np / 8)
    build(x, r, links, skip);
  else
    search_movers(x, r, links, movers, defer);
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
                                  const Links& links, const std::vector<std::int32_t>& movers,
                                  bool defer)
{
  const std::size_t np = r.size();
  const double reach = this->reach(r, links);
  _grid.emplace(x, _cell, _skip);
  const CellGrid& grid = *_grid;
  if (_moving.size() != np)
    _moving.assign(np, 0);
  _movers = movers;
  for (auto m : movers)
    _moving[m] = 1;
  const std::vector<std::uint8_t>& moving = _moving;
  // each mover's pairs with every sphere (a pair of two movers found by the
  // lower one), as (a, b, link); each thread a contiguous block of movers
  std::vector<Found> chunk(omp_get_max_threads());
#pragma omp parallel num_threads(impl::threads_for_searches(movers.size()))
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
                           const double lim = r[m] + r[j] + _skin + reach;
                           const double d2 = dx * dx + dy * dy + dz * dz;
                           if (d2 >= lim * lim)
                             return;
                           const std::int32_t lo = std::min(m, j), hi = std::max(m, j);
                           const std::int32_t k = find_link(links, lo, hi);
                           if ((k >= 0 && links.state[k] == LinkState::intact) || !keeps(d2, r[m] + r[j], links, k))
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
  _pend_a.resize(order.size());
  _pend_b.resize(order.size());
  _pend_link.resize(order.size());
  for (std::size_t k = 0; k < order.size(); ++k)
  {
    _pend_a[k] = add.a[order[k]];
    _pend_b[k] = add.b[order[k]];
    _pend_link[k] = add.link[order[k]];
  }
  if (defer)
    _pending = true;
  else
  {
    merge(_pend_a, _pend_b, _pend_link, _moving, false);
    end_search();
  }
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
  const double reach = this->reach(r, links);
  _cell = 2.0 * rmax + _skin + reach;
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
    std::vector<std::pair<std::int32_t, double>> near; // (j, squared distance)
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < np; ++i)
    {
      if (!skip.empty() && skip[i])
        continue; // left out: not in the grid either
      near.clear();
      grid.for_each_later_near(x, i,
                               [&](std::int32_t j, double d2)
                               {
                                 const double lim = r[i] + r[j] + _skin + reach;
                                 if (d2 < lim * lim)
                                   near.emplace_back(j, d2);
                               });
      std::sort(near.begin(), near.end());
      std::int32_t k = first[i];
      for (const auto& [j, d2] : near)
      {
        while (k < first[i + 1] && links.b[k] < j)
          ++k;
        const bool linked = k < first[i + 1] && links.b[k] == j;
        if ((linked && links.state[k] == LinkState::intact) || !keeps(d2, r[i] + r[j], links, linked ? k : -1))
          continue;
        out.push(static_cast<std::int32_t>(i), j, linked ? k : -1);
      }
    }
  }
  // the new list, with the history of the pairs listed before
  const Found all = joined(chunk);
  merge(all.a, all.b, all.link, {}, true);
  end_search(); // (the removed spheres' flags clear: the rebuild left their pairs out)
  _x_build.assign(x.begin(), x.end());
  _x_grid.assign(x.begin(), x.end());
  ++_builds;
}

void NeighbourList::close_cracks(double c)
{
  if (!(c > 0.0 && c <= 1.0))
    throw std::runtime_error("neighbour list: crack closure " + std::to_string(c) + ": must be in (0, 1]");
  _closure = c;
  _reach_known = false;
}

double NeighbourList::reach(std::span<const double> r, const Links& links)
{
  if (!(_closure > 0.0))
    return 0.0;
  if (!_reach_known)
  {
    // (the links' initial distances never change: once per list)
    _reach = impl::closing_reach(r, links, _closure);
    _reach_known = true;
  }
  return _reach;
}

bool NeighbourList::keeps(double d2, double rs, const Links& links, std::int32_t k) const
{
  const double touch = _closure > 0.0 && k >= 0 ? std::max(rs, impl::closing_distance(links.d0[k], rs, _closure)) : rs;
  const double lim = touch + _skin;
  return d2 < lim * lim;
}

void NeighbourList::end_search()
{
  for (auto m : _movers)
    _moving[m] = 0;
  _movers.clear();
  for (auto i : _dropped)
    _moving[i] = 0;
  _dropped.clear();
  _pending = false;
}

void NeighbourList::copy_pairs(std::size_t q0, std::size_t q1, Columns& out, std::size_t o) const
{
  if (q1 <= q0)
    return;
  std::copy(a.begin() + q0, a.begin() + q1, out.a.begin() + o);
  std::copy(b.begin() + q0, b.begin() + q1, out.b.begin() + o);
  std::copy(link.begin() + q0, link.begin() + q1, out.link.begin() + o);
  std::copy(fs.begin() + 3 * q0, fs.begin() + 3 * q1, out.fs.begin() + 3 * o);
  if (_rolling)
    std::copy(mr.begin() + 3 * q0, mr.begin() + 3 * q1, out.mr.begin() + 3 * o);
  std::copy(n.begin() + 3 * q0, n.begin() + 3 * q1, out.n.begin() + 3 * o);
  std::copy(touching.begin() + q0, touching.begin() + q1, out.touching.begin() + o);
}

std::size_t NeighbourList::first_at_or_after(std::size_t q, std::size_t end, std::int32_t i, std::int32_t j) const
{
  // the first listed pair in [q, end) not below (i, j), or end: galloping
  // from q, then bisection (a dense merge steps, a sparse one jumps)
  auto less = [&](std::size_t k) { return a[k] < i || (a[k] == i && b[k] < j); };
  std::size_t lo = q, hi = q, step = 1;
  while (hi < end && less(hi))
  {
    lo = hi + 1;
    hi += step;
    step *= 2;
  }
  hi = std::min(hi, end);
  while (lo < hi)
  {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (less(mid))
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo;
}

std::size_t NeighbourList::merge_chunk(std::size_t q0, std::size_t q1, std::span<const std::int32_t> na,
                                       std::span<const std::int32_t> nb, std::span<const std::int32_t> nlink,
                                       std::size_t p0, std::size_t p1, std::span<const std::uint8_t> moving,
                                       bool replace_all, Columns* out, std::size_t o) const
{
  const std::size_t o0 = o;
  // the listed pairs [r0, r1) that stay, copied in runs (into out, if any)
  auto keep = [&](std::size_t r0, std::size_t r1)
  {
    if (replace_all)
      return;
    std::size_t run = r0;
    if (!moving.empty())
      for (std::size_t q = r0; q < r1; ++q)
        if (moving[a[q]] || moving[b[q]])
        {
          if (out)
            copy_pairs(run, q, *out, o);
          o += q - run;
          run = q + 1;
        }
    if (out)
      copy_pairs(run, r1, *out, o);
    o += r1 - run;
  };
  std::size_t q = q0;
  for (std::size_t p = p0; p < p1; ++p, ++o)
  {
    const std::size_t at = first_at_or_after(q, q1, na[p], nb[p]);
    keep(q, at);
    q = at;
    const bool listed = q < q1 && a[q] == na[p] && b[q] == nb[p];
    if (out && listed)
      copy_pairs(q, q + 1, *out, o); // listed already: its history stays
    else if (out)
    {
      out->a[o] = na[p];
      out->b[o] = nb[p];
      std::fill_n(out->fs.begin() + 3 * o, 3, 0.0);
      if (_rolling)
        std::fill_n(out->mr.begin() + 3 * o, 3, 0.0);
      std::fill_n(out->n.begin() + 3 * o, 3, 0.0);
      out->touching[o] = 0;
    }
    if (out)
      out->link[o] = nlink[p];
    if (listed)
      ++q;
  }
  keep(q, q1);
  return o - o0;
}

void NeighbourList::merge(std::span<const std::int32_t> na, std::span<const std::int32_t> nb,
                          std::span<const std::int32_t> nlink, std::span<const std::uint8_t> moving,
                          bool replace_all)
{
  // the new pairs (sorted by (a, b)) go in order among the listed ones; a
  // listed pair of a mover (of any sphere with replace_all) is dropped
  // unless it is among the new ones, and then keeps its history (a touching
  // pair always is: its gap is below the skin); a new pair already listed
  // keeps the listed one's history. The listed pairs between two new ones
  // are copied as runs.
  //
  // In parallel: chunk t takes the listed pairs [q[t], q[t + 1]) and the new
  // ones that go among them, [p[t], p[t + 1]) (those after the listed pair
  // q[t] - 1); a first pass counts each chunk's pairs, a second writes them
  // from the sum of the counts before. The list is the same for any thread
  // count.
  const std::size_t m = a.size();
  const int nt = impl::threads_for(m + na.size());
  std::vector<std::size_t> q(nt + 1), p(nt + 1), o(nt + 1, 0);
  for (int t = 0; t <= nt; ++t)
    q[t] = m * static_cast<std::size_t>(t) / static_cast<std::size_t>(nt);
  p[0] = 0;
  p[nt] = na.size();
  for (int t = 1; t < nt; ++t)
  {
    p[t] = p[t - 1];
    if (q[t] == 0)
      continue;
    // the first new pair after the listed pair q[t] - 1
    const std::int32_t la = a[q[t] - 1], lb = b[q[t] - 1];
    p[t] = *std::ranges::partition_point(std::views::iota(p[t], na.size()), [&](std::size_t k)
                                         { return na[k] < la || (na[k] == la && nb[k] <= lb); });
  }
  // (one chunk: no count, the columns sized for the most it can give)
  if (nt > 1)
  {
#pragma omp parallel for schedule(static) num_threads(nt)
    for (int t = 0; t < nt; ++t)
      o[t + 1] = merge_chunk(q[t], q[t + 1], na, nb, nlink, p[t], p[t + 1], moving, replace_all, nullptr, 0);
    for (int t = 0; t < nt; ++t)
      o[t + 1] += o[t];
  }
  const std::size_t total = nt > 1 ? o[nt] : (replace_all ? 0 : m) + na.size();
  Columns& out = _spare;
  out.resize(total, _rolling);
  std::size_t written = 0;
#pragma omp parallel for schedule(static) num_threads(nt) reduction(+ : written)
  for (int t = 0; t < nt; ++t)
    written += merge_chunk(q[t], q[t + 1], na, nb, nlink, p[t], p[t + 1], moving, replace_all, &out, o[t]);
  out.resize(written, _rolling);
  a.swap(out.a);
  b.swap(out.b);
  link.swap(out.link);
  fs.swap(out.fs);
  mr.swap(out.mr);
  n.swap(out.n);
  touching.swap(out.touching);
  ++_version;
}

void NeighbourList::add_broken_links(const Links& links, std::span<const std::int32_t> ids)
{
  if (!_pending && ids.empty())
    return;
  // the broken links' pairs joined with a deferred search's (both sorted by
  // (a, b); a pair found by the search had no intact link then, so none is
  // in both)
  std::vector<std::int32_t> na, nb, nl;
  na.reserve(_pend_a.size() + ids.size());
  nb.reserve(na.capacity());
  nl.reserve(na.capacity());
  const std::size_t np = _pending ? _pend_a.size() : 0;
  for (std::size_t u = 0, k = 0; u < np || k < ids.size();)
  {
    const bool take_link = u == np || (k < ids.size() && (links.a[ids[k]] < _pend_a[u]
                                                         || (links.a[ids[k]] == _pend_a[u] && links.b[ids[k]] <= _pend_b[u])));
    if (take_link)
    {
      const std::int32_t i = links.a[ids[k]], j = links.b[ids[k]];
      if (u < np && _pend_a[u] == i && _pend_b[u] == j)
        ++u;
      na.push_back(i);
      nb.push_back(j);
      nl.push_back(ids[k++]);
    }
    else
    {
      na.push_back(_pend_a[u]);
      nb.push_back(_pend_b[u]);
      nl.push_back(_pend_link[u++]);
    }
  }
  merge(na, nb, nl, _pending ? std::span<const std::uint8_t>(_moving) : std::span<const std::uint8_t>(), false);
  if (_pending)
    end_search();
}

void NeighbourList::remove(std::span<const double> x, std::span<const std::int32_t> gone,
                           std::span<const std::uint8_t> skip)
{
  if (_pending)
    throw std::logic_error("neighbour list: spheres removed while a search waits for add_broken_links()");
  const std::size_t np = x.size() / 3;
  if (skip.size() != np)
    throw std::logic_error("neighbour list: " + std::to_string(skip.size()) + " removal flags for "
                           + std::to_string(np) + " spheres");
  for (auto i : gone)
    if (i < 0 || static_cast<std::size_t>(i) >= np || !skip[i])
      throw std::logic_error("neighbour list: removed sphere " + std::to_string(i) + " out of range or not flagged");
  if (_builds == 0 || _stale || _x_build.size() != x.size())
  {
    _stale = true; // nothing listed yet, or a rebuild due anyway
    return;
  }
  // their pairs go at the next update()'s merge, flagged as movers are
  // (the flags are all clear between searches: end_search)
  _skip.assign(skip.begin(), skip.end());
  if (_moving.size() != np)
    _moving.assign(np, 0);
  for (auto i : gone)
    if (!_moving[i])
    {
      _moving[i] = 1;
      _dropped.push_back(i);
    }
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
  return (a.capacity() + b.capacity() + link.capacity() + _pend_a.capacity() + _pend_b.capacity()
          + _pend_link.capacity() + _movers.capacity() + _dropped.capacity())
             * sizeof(std::int32_t)
         + (fs.capacity() + mr.capacity() + n.capacity() + _x_build.capacity() + _x_grid.capacity())
             * sizeof(double)
         + touching.capacity() + _moving.capacity() + (_grid ? _grid->bytes() : 0)
         + (_spare.a.capacity() + _spare.b.capacity() + _spare.link.capacity()) * sizeof(std::int32_t)
         + (_spare.fs.capacity() + _spare.mr.capacity() + _spare.n.capacity()) * sizeof(double)
         + _spare.touching.capacity();
}

} // namespace dembridge::dem
