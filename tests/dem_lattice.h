#pragma once
// A test packing shared by the dem_tests files.
#include "dembridge/dem/assembly.h"

#include <random>
#include <vector>

namespace dembridge::dem::testing
{
/// n^3 spheres on a cubic lattice of the given spacing [m], each centre
/// shifted by up to +-jitter per axis, radii uniform in [0.8, 1.0] mm
/// (deterministic for a seed).
inline Particles jittered_lattice(int n, double spacing, double jitter, unsigned seed)
{
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> jit(-jitter, jitter), rad(0.8e-3, 1.0e-3);
  std::vector<double> x, r;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
      {
        x.insert(x.end(), {spacing * i + jit(gen), spacing * j + jit(gen), spacing * k + jit(gen)});
        r.push_back(rad(gen));
      }
  return make_particles(x, r, 2400.0, 0.6);
}
} // namespace dembridge::dem::testing
