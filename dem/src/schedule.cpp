// The force loop's thread schedule (SweepIndex) and the size of its scratch
// space (ForceScratch): see force_loop.h.
#include "force_loop.h"

#include <algorithm>

#include "pairs.h"
#include "threads.h"

namespace dembridge::dem
{

void SweepIndex::build(std::size_t np, std::span<const std::int32_t> a,
                       std::span<const std::int32_t> b, int nt)
{
  first = impl::first_by_a(np, a, b, "force loop: links and pairs");
  threads = nt;
  // thread t sweeps spheres [bounds[t], bounds[t + 1]): equal shares of
  // items + spheres (a sphere's own cost, reset and sums, ~ one item),
  // not of spheres -- where the sphere order makes the early spheres own
  // more items (a Morton curve over a box whose sides are not in powers of
  // 2) a split by spheres left one thread 24 % more items (coupled bar).
  // upto[i]: the items of spheres [0, i), plus i; and the most items of one
  // sphere
  std::vector<std::int64_t> upto(np + 1, 0);
  std::int32_t most = 0;
#pragma omp parallel for schedule(static) reduction(max : most) num_threads(nt)
  for (std::size_t i = 0; i < np; ++i)
  {
    upto[i + 1] = static_cast<std::int64_t>(first[i + 1]) + static_cast<std::int64_t>(i) + 1;
    most = std::max(most, first[i + 1] - first[i]);
  }
  bounds.assign(nt + 1, np);
  bounds[0] = 0;
  for (int t = 1; t < nt; ++t)
  {
    const double share = static_cast<double>(upto[np]) * t / nt;
    bounds[t] = static_cast<std::size_t>(
        std::lower_bound(upto.begin() + static_cast<std::ptrdiff_t>(bounds[t - 1]),
                         upto.begin() + static_cast<std::ptrdiff_t>(np), share,
                         [](std::int64_t u, double v) { return static_cast<double>(u) < v; })
        - upto.begin());
  }
  // each thread's cross items, in item order (b is sorted within i: they
  // are the tail of i's items), found by the team, one thread's spheres each
  std::vector<std::vector<std::int32_t>> ci(nt), ck(nt);
#pragma omp parallel for schedule(static, 1) num_threads(nt)
  for (int t = 0; t < nt; ++t)
    for (std::size_t i = bounds[t]; i < bounds[t + 1]; ++i)
    {
      std::int32_t k0 = first[i + 1];
      while (k0 > first[i] && static_cast<std::size_t>(b[k0 - 1]) >= bounds[t + 1])
        --k0;
      for (std::int32_t k = k0; k < first[i + 1]; ++k)
      {
        ci[t].push_back(static_cast<std::int32_t>(i));
        ck[t].push_back(k);
      }
    }
  cross_first.assign(nt + 1, 0);
  cross_i.clear();
  cross_k.clear();
  for (int t = 0; t < nt; ++t)
  {
    cross_first[t + 1] = cross_first[t] + static_cast<std::int32_t>(ci[t].size());
    cross_i.insert(cross_i.end(), ci[t].begin(), ci[t].end());
    cross_k.insert(cross_k.end(), ck[t].begin(), ck[t].end());
  }
  // the slots into each sphere b (CSR), in item order
  in_first.assign(np + 1, 0);
  for (auto k : cross_k)
    ++in_first[b[k] + 1];
  for (std::size_t i = 0; i < np; ++i)
    in_first[i + 1] += in_first[i];
  in.resize(cross_k.size());
  std::vector<std::int32_t> fill(in_first.begin(), in_first.end() - 1);
  for (std::size_t s = 0; s < cross_k.size(); ++s)
    in[fill[b[cross_k[s]]]++] = static_cast<std::int32_t>(s);
  // (every slot is written by the sweep before it is read)
  out.resize(max_out * cross_k.size());
  geometry.resize(nt);
  for (auto& g : geometry)
    g.resize(prepared * most);
}

void set_min_spheres_per_thread_team(std::size_t n) { impl::min_items_per_team() = n; }
std::size_t min_spheres_per_thread_team() { return impl::min_items_per_team(); }

std::size_t SweepIndex::bytes() const
{
  std::size_t s = (first.capacity() + cross_first.capacity() + in_first.capacity() + in.capacity()
                   + cross_i.capacity() + cross_k.capacity())
             * sizeof(std::int32_t)
         + out.capacity() * sizeof(double) + bounds.capacity() * sizeof(std::size_t);
  for (const auto& g : geometry)
    s += g.capacity() * sizeof(double);
  return s;
}

std::size_t ForceScratch::bytes() const
{
  std::size_t s = (records.capacity() + pair_slip.capacity() + demand.capacity() + stretch.capacity()
                   + link_stretch.capacity())
                      * sizeof(double)
                  + links.bytes()
                  + pairs.bytes() + broken_ids.capacity() * sizeof(std::int32_t)
                  + broken_all.capacity() * sizeof(broken_all[0]);
  for (const auto& b : broken)
    s += b.capacity() * sizeof(b[0]);
  return s;
}

} // namespace dembridge::dem
