#pragma once
// Thread count for a parallel loop over n items: below a couple of thousand
// items the fork/join and barriers cost more than the work saves (measured,
// dem_throughput, 2 cores: 1.35 x faster on 2 threads at 1,000 spheres, 1.6 x
// at 2,000, 1.4 x at 3,600; the identification's 1,000-sphere samples ran
// slower on 2 threads than on 1, so the line sits above them).
#include <cstddef>
#include <omp.h>

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
} // namespace dembridge::dem::impl
