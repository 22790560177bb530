#pragma once
// Thread count for a parallel loop over n items: below a couple of thousand
// items the fork/join and barriers cost more than the work saves (measured,
// dem_throughput, 2 cores: 1.35 x faster on 2 threads at 1,000 spheres, 1.6 x
// at 2,000, 1.4 x at 3,600; the identification's 1,000-sphere samples ran
// slower on 2 threads than on 1, so the line sits above them).
#include <algorithm>
#include <cstddef>
#include <omp.h>
#include <vector>

namespace dembridge::dem::impl
{
inline std::size_t& min_items_per_team()
{
  static std::size_t value = 2048;
  return value;
}
inline int threads_for(std::size_t n)
{
  return n >= min_items_per_team() ? omp_get_max_threads() : 1;
}
/// The same for items that each cost a microsecond or more (a neighbour
/// search around one sphere: 27 cells), where a team pays from a few dozen.
inline int threads_for_searches(std::size_t n)
{
  return n >= std::min<std::size_t>(64, min_items_per_team()) ? omp_get_max_threads() : 1;
}
} // namespace dembridge::dem::impl

namespace dembridge::dem::impl
{
/// Sum of term(k) over k in [0, n), in parallel and the same bit for bit
/// whatever the thread count: each fixed block of 4,096 items is summed in
/// item order, then the blocks in block order.
template <typename Term>
double block_sum(std::size_t n, Term&& term)
{
  constexpr std::size_t block = 4096;
  const std::size_t nb = (n + block - 1) / block;
  if (nb <= 1)
  {
    double s = 0.0;
    for (std::size_t k = 0; k < n; ++k)
      s += term(k);
    return s;
  }
  std::vector<double> part(nb, 0.0);
#pragma omp parallel for schedule(static) num_threads(threads_for(n))
  for (std::size_t b = 0; b < nb; ++b)
  {
    double s = 0.0;
    const std::size_t end = std::min(n, (b + 1) * block);
    for (std::size_t k = b * block; k < end; ++k)
      s += term(k);
    part[b] = s;
  }
  double s = 0.0;
  for (double v : part)
    s += v;
  return s;
}
} // namespace dembridge::dem::impl
