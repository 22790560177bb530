#include "dembridge/dem/skin.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace dembridge::dem
{

SkinCompensation compensate_skin(const Particles& p, Links& l, const Region& region, double depth)
{
  if (!(depth > 0.0) || !std::isfinite(depth))
  {
    std::ostringstream m;
    m << "skin depth " << depth << " m: allowed is a finite value > 0 (e.g. 2 Rmax)";
    throw std::runtime_error(m.str());
  }
  const std::size_t n = p.size();
  std::vector<double> z(n, 0.0);
  for (std::size_t k = 0; k < l.size(); ++k)
  {
    if (static_cast<std::size_t>(l.a[k]) >= n || static_cast<std::size_t>(l.b[k]) >= n)
      throw std::runtime_error("compensate_skin: link " + std::to_string(k) + " names a sphere beyond the "
                               + std::to_string(n) + " given");
    z[l.a[k]] += 1.0;
    z[l.b[k]] += 1.0;
  }
  SkinCompensation s;
  const auto bulk = bulk_spheres(region, p.x, p.r);
  double nb = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    if (bulk[i])
    {
      s.bulk_links += z[i];
      nb += 1.0;
    }
  s.bulk_links /= nb;
  std::vector<double> f(n, 1.0);
  for (std::size_t i = 0; i < n; ++i)
    if (z[i] > 0.0 && region.sdf({p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]}) > -depth)
    {
      f[i] = std::max(1.0, s.bulk_links / z[i]);
      if (f[i] > 1.0)
        ++s.spheres;
      s.max_factor = std::max(s.max_factor, f[i]);
    }
  double sum = 0.0;
  for (std::size_t k = 0; k < l.size(); ++k)
  {
    const double g = 0.5 * (f[l.a[k]] + f[l.b[k]]);
    if (g == 1.0)
      continue;
    l.kn[k] *= g;
    l.ks[k] *= g;
    sum += g;
    ++s.links;
  }
  s.mean_link_factor = s.links ? sum / s.links : 1.0;
  return s;
}

} // namespace dembridge::dem
