#include "dembridge/core/stepping.h"

#include <cmath>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace dembridge::core
{

double max_eigenvalue(std::span<const double> mass, const LinearAction& k, double rtol, int max_iter,
                      const std::function<void(std::span<double>)>& project)
{
  // Power iteration on S = M^-1/2 K M^-1/2 (on P S P with the projection P,
  // which is Euclidean in these scaled coordinates): y -> S y, with the
  // Rayleigh quotient z.Kz / z.Mz of z = M^-1/2 y as the estimate.
  const std::size_t n = mass.size();
  std::vector<double> y(n), z(n), f(n), minv_sqrt(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    minv_sqrt[i] = 1.0 / std::sqrt(mass[i]);
    // deterministic, rich in high-frequency content
    y[i] = ((i * 2654435761u) % 1000) / 1000.0 - 0.5;
  }
  double lambda = 0.0;
  for (int it = 0; it < max_iter; ++it)
  {
    const double norm = std::sqrt(std::inner_product(y.begin(), y.end(), y.begin(), 0.0));
    if (!(norm > 0.0))
      throw std::runtime_error("max_eigenvalue: the iteration vanished (no free motion)");
    for (std::size_t i = 0; i < n; ++i)
      z[i] = y[i] / norm * minv_sqrt[i];
    if (project)
      project(z);
    k(z, f);
    double zkz = 0.0, zmz = 0.0;
    for (std::size_t i = 0; i < n; ++i)
    {
      y[i] = f[i] * minv_sqrt[i];
      zkz += f[i] * z[i];
      zmz += z[i] * z[i] * mass[i];
    }
    const double rq = zkz / zmz;
    if (it > 10 && std::abs(rq - lambda) < rtol * rq)
      return rq;
    lambda = rq;
  }
  return lambda;
}

void EnergyGuard::set(double margin, std::int64_t every)
{
  if (!(margin >= 0.0) || !std::isfinite(margin) || every < 1)
    throw std::runtime_error("energy guard: margin " + std::to_string(margin) + " must be >= 0 (0 = off), every "
                             + std::to_string(every) + " steps >= 1");
  _margin = margin;
  _every = every;
}

void EnergyGuard::check(const Budget& b) const
{
  if (!(b.scale > 0.0) || b.imbalance <= _margin * b.scale)
    return;
  std::ostringstream s;
  s << b.system << " grows without cause at t = " << b.t << " s (step " << b.step << "): " << b.stored_name << " "
    << b.stored << " J against initial " << b.initial << " J + work " << b.work << " J (" << b.imbalance
    << " J unaccounted for, more than " << _margin << " x the energy scale): the run is unstable; reduce the time step";
  throw std::runtime_error(s.str());
}

} // namespace dembridge::core
