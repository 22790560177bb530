#pragma once
// Internal to dem/: items (links or neighbour pairs) sorted by (a, b).
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace dembridge::dem::impl
{
/// Crack closure (Material::crack_closure = c in (0, 1], method.md 1.7): the
/// distance from which the spheres of a broken link, D_init apart at rest
/// and rs = R_a + R_b, touch again: D_init - (1 - c) (D_init - rs), D_init
/// itself at c = 1. The force loop's contacts and the neighbour list's reach
/// both take it from here.
inline double closing_distance(double d0, double rs, double c) { return d0 - (1.0 - c) * (d0 - rs); }

/// first[i]: the start of the items with a = i, so they are
/// [first[i], first[i + 1]). @throws std::runtime_error naming `what` if the
/// items are not sorted by (a, b) without repeats or not 0 <= a < b < np.
inline std::vector<std::int32_t> first_by_a(std::size_t np, std::span<const std::int32_t> a,
                                            std::span<const std::int32_t> b,
                                            const std::string& what)
{
  std::vector<std::int32_t> first(np + 1, 0);
  for (std::size_t k = 0; k < a.size(); ++k)
  {
    if (k > 0 && (a[k] < a[k - 1] || (a[k] == a[k - 1] && b[k] <= b[k - 1])))
      throw std::runtime_error(what + " must be sorted by (a, b) without repeats (item "
                               + std::to_string(k) + ")");
    if (a[k] < 0 || b[k] <= a[k] || static_cast<std::size_t>(b[k]) >= np)
      throw std::runtime_error(what + ": item " + std::to_string(k) + " (" + std::to_string(a[k])
                               + ", " + std::to_string(b[k]) + ") needs 0 <= a < b < "
                               + std::to_string(np));
    ++first[a[k] + 1];
  }
  for (std::size_t i = 0; i < np; ++i)
    first[i + 1] += first[i];
  return first;
}
} // namespace dembridge::dem::impl
