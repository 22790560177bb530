#pragma once
// Internal to dem/: items (links or neighbour pairs) sorted by (a, b).
#include <algorithm>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "threads.h"

namespace dembridge::dem::impl
{
/// Crack closure (Material::crack_closure = c in (0, 1], method.md 1.7): the
/// distance from which the spheres of a broken link, D_init apart at rest
/// and rs = R_a + R_b, touch again: D_init - (1 - c) (D_init - rs), D_init
/// itself at c = 1. The force loop's contacts and the neighbour list's reach
/// both take it from here.
inline double closing_distance(double d0, double rs, double c) { return d0 - (1.0 - c) * (d0 - rs); }

/// The most a broken link's closing distance exceeds R_a + R_b over the
/// links (a < b index radii r), for crack closure c; 0 without closure. The
/// neighbour list reaches that much farther, and no pair touches beyond
/// R_a + R_b plus it (the compaction's set only shortens a link's: law.h).
template <typename Links>
double closing_reach(std::span<const double> r, const Links& l, double c)
{
  if (!(c > 0.0))
    return 0.0;
  double reach = 0.0;
  const auto n = static_cast<std::int64_t>(l.size());
#pragma omp parallel for schedule(static) reduction(max : reach) num_threads(threads_for(l.size()))
  for (std::int64_t k = 0; k < n; ++k)
  {
    const double rs = r[l.a[k]] + r[l.b[k]];
    reach = std::max(reach, closing_distance(l.d0[k], rs, c) - rs);
  }
  return reach;
}

/// first[i]: the start of the items with a = i, so they are
/// [first[i], first[i + 1]). @throws std::runtime_error naming `what` if the
/// items are not sorted by (a, b) without repeats or not 0 <= a < b < np.
/// In parallel: the items are checked first; then item k sets first[i] for
/// the spheres i in (a[k - 1], a[k]].
inline std::vector<std::int32_t> first_by_a(std::size_t np, std::span<const std::int32_t> a,
                                            std::span<const std::int32_t> b,
                                            const std::string& what)
{
  const std::size_t m = a.size();
  auto sorted = [&](std::size_t k) { return k == 0 || a[k] > a[k - 1] || (a[k] == a[k - 1] && b[k] > b[k - 1]); };
  auto in_range = [&](std::size_t k) { return a[k] >= 0 && b[k] > a[k] && static_cast<std::size_t>(b[k]) < np; };
  std::size_t bad = m; // the first item out of order or range
#pragma omp parallel for schedule(static) reduction(min : bad) num_threads(threads_for(m))
  for (std::size_t k = 0; k < m; ++k)
    if (!sorted(k) || !in_range(k))
      bad = std::min(bad, k);
  if (bad < m && !sorted(bad))
    throw std::runtime_error(what + " must be sorted by (a, b) without repeats (item " + std::to_string(bad) + ")");
  if (bad < m)
    throw std::runtime_error(what + ": item " + std::to_string(bad) + " (" + std::to_string(a[bad]) + ", "
                             + std::to_string(b[bad]) + ") needs 0 <= a < b < " + std::to_string(np));
  std::vector<std::int32_t> first(np + 1);
#pragma omp parallel for schedule(static) num_threads(threads_for(m))
  for (std::size_t k = 0; k < m; ++k)
    for (std::int32_t i = k == 0 ? 0 : a[k - 1] + 1; i <= a[k]; ++i)
      first[i] = static_cast<std::int32_t>(k);
  for (std::size_t i = m == 0 ? 0 : static_cast<std::size_t>(a[m - 1]) + 1; i <= np; ++i)
    first[i] = static_cast<std::int32_t>(m);
  return first;
}
} // namespace dembridge::dem::impl
