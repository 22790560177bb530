#pragma once
// Internal to dem/: what the packing's generator (packing_generate.cpp) and
// its boundary fill (packing_fill.cpp) share.
#include "dembridge/dem/packing.h"

#include <cstddef>

namespace dembridge::dem::impl
{

/// The unit gradient of the region's signed distance at x (the outward
/// normal of the boundary there), by central differences of step h.
Point gradient(const Region& g, const Point& x, double h);

/// Renumbers the spheres along a Morton (z-order) curve.
void morton_sort(Packing& p, const Region& g);

/// Where the boundary is left uncovered (a point of it farther than 0.75
/// Rmax from every sphere surface), inserts the largest sphere of at most
/// Rmax tangent to the boundary there that overlaps nothing, if it is at
/// least Rmin; h: the gradient's step. Returns the number of spheres added
/// (appended to p).
std::size_t fill_uncovered(Packing& p, const Region& g, double rmin, double rmax, double h);

} // namespace dembridge::dem::impl
