// The craters measured on a slab after an impact (impact.h, measure_craters;
// docs/impact.md, "Measurements").
#include "impact.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace dembridge::demo
{

namespace
{
/// One crater's layers, walking from the face inwards: layer k holds the
/// spheres whose initial centre lies k layers in from the face.
Crater walk_layers(const std::vector<double>& volume, const std::vector<double>& mass, const CraterInput& in)
{
  Crater c;
  for (std::size_t k = 0; k < volume.size(); ++k)
  {
    const double area = volume[k] / (in.layer * in.fraction);
    const double d = std::sqrt(4.0 * area / std::numbers::pi);
    if (d <= in.tunnel)
      break;
    if (k == 0)
      c.diameter = d;
    c.depth = std::min(in.thickness, (k + 1) * in.layer);
    c.mass += mass[k];
  }
  return c;
}
} // namespace

std::pair<Crater, Crater> measure_craters(const CraterInput& in)
{
  const std::size_t layers = static_cast<std::size_t>(std::ceil(in.thickness / in.layer));
  std::vector<double> vf(layers, 0.0), mf(layers, 0.0), vr(layers, 0.0), mr(layers, 0.0);
  for (std::size_t i = 0; i < in.r.size(); ++i)
  {
    if (!in.detached[i])
      continue;
    const double z = in.x0[3 * i + 2];
    const double v = 4.0 / 3.0 * std::numbers::pi * in.r[i] * in.r[i] * in.r[i];
    const auto kf = std::min(layers - 1, static_cast<std::size_t>(std::max(0.0, -z / in.layer)));
    const auto kr = std::min(layers - 1, static_cast<std::size_t>(std::max(0.0, (z + in.thickness) / in.layer)));
    vf[kf] += v;
    mf[kf] += in.m[i];
    vr[kr] += v;
    mr[kr] += in.m[i];
  }
  // the scab's layers end where the crater's begin (a crater through the
  // whole slab leaves no scab of its own)
  const Crater front = walk_layers(vf, mf, in);
  const auto in_front = static_cast<std::size_t>(std::ceil(front.depth / in.layer - 1e-9));
  vr.resize(layers - std::min(layers, in_front));
  return {front, walk_layers(vr, mr, in)};
}

} // namespace dembridge::demo
