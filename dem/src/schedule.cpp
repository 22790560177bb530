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
  // 2) a split by spheres left one thread 24 % more items (coupled bar)
  bounds.assign(nt + 1, np);
  bounds[0] = 0;
  {
    const double total = static_cast<double>(first[np]) + static_cast<double>(np);
    std::size_t i = 0;
    for (int t = 1; t < nt; ++t)
    {
      const double share = total * t / nt;
      while (i < np && static_cast<double>(first[i]) + static_cast<double>(i) < share)
        ++i;
      bounds[t] = i;
    }
  }
  cross_first.assign(nt + 1, 0);
  in_first.assign(np + 1, 0);
  cross_i.clear();
  cross_k.clear();
  std::vector<std::int32_t> target;
  for (int t = 0; t < nt; ++t)
  {
    const std::size_t lo = bounds[t], hi = bounds[t + 1];
    cross_first[t + 1] = cross_first[t];
    for (std::size_t i = lo; i < hi; ++i)
    {
      // b is sorted within i: the cross items are the tail of i's items
      std::int32_t k0 = first[i + 1];
      while (k0 > first[i] && static_cast<std::size_t>(b[k0 - 1]) >= hi)
        --k0;
      for (std::int32_t k = k0; k < first[i + 1]; ++k)
      {
        ++cross_first[t + 1];
        ++in_first[b[k] + 1];
        target.push_back(b[k]);
        cross_i.push_back(static_cast<std::int32_t>(i));
        cross_k.push_back(k);
      }
    }
  }
  for (std::size_t i = 0; i < np; ++i)
    in_first[i + 1] += in_first[i];
  in.resize(target.size());
  std::vector<std::int32_t> fill(in_first.begin(), in_first.end() - 1);
  for (std::size_t s = 0; s < target.size(); ++s) // slots are in item order
    in[fill[target[s]]++] = static_cast<std::int32_t>(s);
  // (every slot is written by the sweep before it is read)
  out.resize(max_out * target.size());
  std::int32_t most = 0;
  for (std::size_t i = 0; i < np; ++i)
    most = std::max(most, first[i + 1] - first[i]);
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
