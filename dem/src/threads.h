#pragma once
// Thread count for a parallel loop over n items: below a few thousand items
// the fork/join and barriers cost more than the work saves (measured: the
// identification's 1,000-sphere samples ran slower on 2 threads than on 1).
#include <cstddef>
#include <omp.h>

namespace dembridge::dem::impl
{
inline std::size_t& min_items_per_team()
{
  static std::size_t value = 4096;
  return value;
}
inline int threads_for(std::size_t n)
{
  return n >= min_items_per_team() ? omp_get_max_threads() : 1;
}
} // namespace dembridge::dem::impl
