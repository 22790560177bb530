// The packing generator (generate_packing, docs/method.md 2): radii drawn
// and scaled to the target fraction, a stratified start, the relaxation of
// the overlaps by FIRE, the last overlaps shrunk away and the boundary
// filled.
#include "packing_internal.h"

#include "dembridge/dem/neighbours.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <omp.h>
#include <random>
#include <sstream>
#include <stdexcept>

#include "errors.h"

namespace dembridge::dem
{
using impl::gradient;

namespace
{

/// Full neighbour lists (both directions) in CSR form.
struct Csr
{
  std::vector<std::int32_t> start, items;
};

/// Sphere centre and radius together: what a neighbour read needs, in one
/// cache line.
struct Ball
{
  double x, y, z, r;
};

/// Full neighbour lists (both directions) in CSR form: every pair closer
/// than r_i + r_j + reach. The spheres are copied in the cell grid's order,
/// so the 27 cells around a sphere are read as 9 contiguous runs; each
/// thread fills a contiguous block of spheres.
Csr neighbours(const std::vector<double>& x, const std::vector<double>& r, double reach)
{
  const std::size_t n = r.size();
  const double rmax = *std::max_element(r.begin(), r.end());
  const CellGrid grid(x, 2.0 * rmax + reach);
  const std::vector<std::int32_t>& index = grid.items();
  std::vector<Ball> sorted(n);
  for (std::size_t k = 0; k < n; ++k)
    sorted[k] = {x[3 * index[k]], x[3 * index[k] + 1], x[3 * index[k] + 2], r[index[k]]};
  Csr c;
  c.start.assign(n + 1, 0);
  std::vector<std::vector<std::int32_t>> chunk;
#pragma omp parallel
  {
#pragma omp single
    chunk.resize(omp_get_num_threads());
    auto& buf = chunk[omp_get_thread_num()];
    std::size_t used = 0;
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < n; ++i)
    {
      const std::size_t first = used;
      const Ball bi{x[3 * i], x[3 * i + 1], x[3 * i + 2], r[i]};
      grid.for_each_run_near(
          &x[3 * i],
          [&](std::int32_t k0, std::int32_t k1)
          {
            if (buf.size() < used + (k1 - k0))
              buf.resize(2 * (used + (k1 - k0)));
            std::int32_t* out = buf.data() + used;
            std::size_t kept = 0;
            for (std::int32_t k = k0; k < k1; ++k) // branch-free: write, keep if near
            {
              const Ball& bj = sorted[k];
              const double dx = bj.x - bi.x, dy = bj.y - bi.y, dz = bj.z - bi.z;
              const double lim = bi.r + bj.r + reach;
              out[kept] = index[k];
              kept += (dx * dx + dy * dy + dz * dz < lim * lim)
                      & (index[k] != static_cast<std::int32_t>(i));
            }
            used += kept;
          });
      c.start[i + 1] = static_cast<std::int32_t>(used - first);
    }
    buf.resize(used);
  }
  for (std::size_t i = 0; i < n; ++i)
    c.start[i + 1] += c.start[i];
  c.items.clear();
  c.items.reserve(c.start[n]);
  for (auto& b2 : chunk) // static schedule: thread blocks are in sphere order
    c.items.insert(c.items.end(), b2.begin(), b2.end());
  return c;
}

/// A size scale's value at x, checked to lie in (0, 1].
double checked_scale(const std::function<double(const Point&)>& scale, const Point& x)
{
  const double v = scale(x);
  if (!(v > 0.0 && v <= 1.0))
    impl::out_of_range("packing size scale at (" + std::to_string(x[0]) + ", " + std::to_string(x[1]) + ", "
                           + std::to_string(x[2]) + ") m",
                       v, "in (0, 1]");
  return v;
}

/// What a graded packing needs of its scale field: the region's volume
/// weighted by scale^-3, and the smallest scale in it.
struct Graded
{
  double weighted, smallest;
};

/// Graded for a region and a size scale, from the cell centres of a 128^3
/// grid over its bounding box (as the volume of sdf_region), in one serial
/// pass (the scale may throw: checked_scale).
Graded graded_volume(const Region& g, const std::function<double(const Point&)>& scale)
{
  constexpr int m = 128;
  double h[3];
  for (int k = 0; k < 3; ++k)
    h[k] = (g.hi[k] - g.lo[k]) / m;
  double sum = 0.0, smallest = 1.0;
  std::size_t count = 0;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j)
      for (int k = 0; k < m; ++k)
      {
        const Point x{g.lo[0] + (i + 0.5) * h[0], g.lo[1] + (j + 0.5) * h[1], g.lo[2] + (k + 0.5) * h[2]};
        if (g.sdf(x) >= 0.0)
          continue;
        const double v = checked_scale(scale, x);
        sum += 1.0 / (v * v * v);
        smallest = std::min(smallest, v);
        ++count;
      }
  if (count == 0)
    return {g.volume, 1.0};
  // the region's own volume times the mean of scale^-3 over its samples
  return {g.volume * sum / count, smallest};
}

void check_options(const PackingOptions& o)
{
  if (!(o.radius_ratio >= 1.0 && o.radius_ratio <= 3.0))
    impl::out_of_range("radius ratio Rmax/Rmin", o.radius_ratio, "in [1, 3]");
  if (!(o.target_fraction > 0.0 && o.target_fraction < 0.74))
    impl::out_of_range("target packing fraction", o.target_fraction, "in (0, 0.74)");
  if (!(o.tolerance > 0.0))
    impl::out_of_range("overlap tolerance", o.tolerance, "> 0");
  if (o.count == 0 && !(o.mean_radius > 0.0))
    impl::out_of_range("mean radius", o.mean_radius, "> 0 m (or give a number of spheres)");
}

/// The number of spheres: o.count, or as many of the mean radius as fill
/// the region's volume (weighted by scale^-3 if graded) to the target
/// fraction. @throws std::runtime_error below 2.
std::size_t sphere_count(const Region& g, const PackingOptions& o, const Graded& grade)
{
  const double q = o.radius_ratio;
  // E[r^3] for r uniform in [a, q a], per a^3
  const double er3 = q > 1.0 ? (std::pow(q, 4) - 1.0) / (4.0 * (q - 1.0)) : 1.0;
  std::size_t n = o.count;
  if (n == 0)
  {
    const double a = 2.0 * o.mean_radius / (1.0 + q);
    n = static_cast<std::size_t>(std::llround(o.target_fraction * grade.weighted
                                              / (4.0 / 3.0 * std::numbers::pi * er3 * a * a * a)));
  }
  if (n < 2)
  {
    std::ostringstream m;
    m << "region '" << g.name << "' (" << g.volume << " m^3) holds fewer than 2 spheres of mean radius "
      << o.mean_radius << " m: use smaller spheres or a larger region";
    throw std::runtime_error(m.str());
  }
  return n;
}

/// The radii's scale: rmin, the smallest radius a draw can give; rmin_unit,
/// the same where the size scale is 1.
struct RadiusScale
{
  double rmin = 0.0, rmin_unit = 0.0;
};

/// Scales the radii to the target fraction.
void fit_radii(Packing& p, const Region& g, const PackingOptions& o, const Graded& grade, RadiusScale& rs)
{
  double vol = 0.0;
  for (const double r : p.r)
    vol += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  const double scale = std::cbrt(o.target_fraction * g.volume / vol);
  for (auto& r : p.r)
    r *= scale;
  rs.rmin_unit = scale;
  rs.rmin = scale * grade.smallest;
}

/// Stratified start: one sphere per cell of a grid over the bounding box
/// (cells whose centre lies inside, chosen at random), jittered within it.
/// Graded: the grid is that of the smallest scale, a cell kept with the
/// probability (smallest / scale)^3 at its centre; the radii are then
/// scaled by the scale where each sphere starts and fit to the fraction.
void stratified_start(Packing& p, const Region& g, const PackingOptions& o, Graded& grade, std::mt19937_64& gen,
                      std::uniform_real_distribution<double>& u01, RadiusScale& rs)
{
  const std::size_t n = p.r.size();
  const bool graded = static_cast<bool>(o.size_scale);
  p.x.resize(3 * n);
  double c = grade.smallest * std::cbrt(grade.weighted / n);
  std::vector<Point> cells;
  for (int attempt = 0; attempt < 50; ++attempt)
  {
    cells.clear();
    int m[3];
    for (int k = 0; k < 3; ++k)
      m[k] = std::max(1, static_cast<int>(std::floor((g.hi[k] - g.lo[k]) / c)));
    double h3[3];
    for (int k = 0; k < 3; ++k)
      h3[k] = (g.hi[k] - g.lo[k]) / m[k];
    for (int i = 0; i < m[0]; ++i)
      for (int j = 0; j < m[1]; ++j)
        for (int k = 0; k < m[2]; ++k)
        {
          const Point centre{g.lo[0] + (i + 0.5) * h3[0], g.lo[1] + (j + 0.5) * h3[1],
                             g.lo[2] + (k + 0.5) * h3[2]};
          if (g.sdf(centre) < 0.0
              && (!graded || u01(gen) < std::pow(grade.smallest / checked_scale(o.size_scale, centre), 3)))
            cells.push_back(centre);
        }
    if (cells.size() >= n)
    {
      c = std::min({h3[0], h3[1], h3[2]});
      break;
    }
    c *= 0.97;
  }
  if (cells.size() < n)
    throw std::runtime_error("packing: the region is too thin for spheres of this size");
  std::shuffle(cells.begin(), cells.end(), gen);
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k)
      p.x[3 * i + k] = cells[i][k] + 0.5 * c * (2.0 * u01(gen) - 1.0);
  if (graded)
  {
    // (the smallest scale a sphere got: below the grid's if the finest
    // part is thinner than the grid's spacing)
    for (std::size_t i = 0; i < n; ++i)
    {
      const double si = checked_scale(o.size_scale, {p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]});
      p.r[i] *= si;
      grade.smallest = std::min(grade.smallest, si);
    }
    fit_radii(p, g, o, grade, rs);
  }
  // memory order along a Morton curve from the start (radii are i.i.d.)
  impl::morton_sort(p, g);
}

/// Relaxation by FIRE (Bitzek et al. 2006) on the overlap energy, with each
/// sphere's Jacobi displacement d (its share of the overlaps it is in,
/// weighted by the other's volume, plus the boundary push) as the force:
/// about 3x fewer sweeps than heavy-ball momentum restarted per sphere.
/// Sums are taken in fixed blocks of spheres, so the run is the same
/// whatever the thread count. The spheres grow from s0 = 0.8 of their
/// radii over the first growth_sweeps sweeps.
class Relaxation
{
public:
  /// jammed when the largest overlap fell by less than 10 % over
  /// check_every sweeps: all radii are then scaled by `backoff` (0.6 % of
  /// the volume)
  static constexpr int check_every = 100;
  static constexpr double backoff = 0.998;

  Relaxation(Packing& p, const Region& g, const PackingOptions& o, double rmin)
      : _p(p), _g(g), _o(o), _n(p.size()), _rmin(rmin), _skin(1.0 * rmin),
        _h(1e-7 * (g.hi[0] - g.lo[0] + g.hi[1] - g.lo[1])), _hug(rmin), _max_step(0.1 * rmin),
        _part((_n + block - 1) / block), _ball(_n), _f(3 * _n), _v(3 * _n, 0.0), _near(_n, 1)
  {
    for (std::size_t i = 0; i < _n; ++i)
      _ball[i] = {p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2], p.r[i]};
  }

  /// Sweeps until the overlaps and penetrations are within the tolerance
  /// (true) or o.max_sweeps (false).
  bool run()
  {
    const double s0 = 0.8, tol = _o.tolerance * _rmin;
    const int grow = _o.growth_sweeps;
    for (int sweep = 0; sweep < _o.max_sweeps; ++sweep)
    {
      const double s = std::min(1.0, s0 + (1.0 - s0) * sweep / grow);
      if (_moved2 > 0.25 * _skin * _skin)
        rebuild();
      const Sums sums = displacements(s);
      fire_control(sums.power);
      move(sums.ff, kick());
      _p.sweeps = sweep + 1;
      if (s >= 1.0 && (sweep - grow) % check_every == check_every - 1)
        back_off_if_jammed(sums.max_ov);
      _p.max_overlap = sums.max_ov / _rmin;
      _p.max_penetration = sums.max_pen / _rmin;
      if (_o.verbose && sweep % 100 == 0)
        std::printf("packing sweep %d: scale %.3f, max overlap %.2e Rmin, penetration %.2e Rmin, "
                    "FIRE step %.2f\n",
                    sweep, s, _p.max_overlap, _p.max_penetration, _dt);
      if (s >= 1.0 && ((sums.max_ov < tol && sums.max_pen < tol)
                       || (sums.max_ov < _o.shrink_below * _rmin && sums.max_pen < _o.shrink_below * _rmin)))
        return true;
    }
    return false;
  }

  /// Removes the overlaps left by shrinking the spheres concerned (each by
  /// half the overlap of a pair, the whole penetration at the boundary).
  void shrink_remaining()
  {
    std::vector<double> cut(_n, 0.0);
    const Csr nb = neighbours(_p.x, _p.r, _skin);
    const Packing& p = _p;
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < _n; ++i)
    {
      for (std::int32_t q2 = nb.start[i]; q2 < nb.start[i + 1]; ++q2)
      {
        const std::int32_t j = nb.items[q2];
        const double dist = std::sqrt(std::pow(p.x[3 * j] - p.x[3 * i], 2) + std::pow(p.x[3 * j + 1] - p.x[3 * i + 1], 2)
                                      + std::pow(p.x[3 * j + 2] - p.x[3 * i + 2], 2));
        cut[i] = std::max(cut[i], 0.5 * (p.r[i] + p.r[j] - dist));
      }
      cut[i] = std::max(cut[i], _g.sdf({p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]}) + p.r[i]);
    }
    for (std::size_t i = 0; i < _n; ++i)
      if (cut[i] > 0.0)
      {
        _p.r[i] -= cut[i] * (1.0 + 1e-9);
        _p.max_shrink = std::max(_p.max_shrink, cut[i] / _rmin);
        ++_p.shrunk;
      }
    _p.max_overlap = _p.max_penetration = 0.0;
  }

  double gradient_step() const { return _h; }

private:
  static constexpr std::size_t block = 1024;
  /// FIRE's constants: Bitzek et al.'s (N_min 5, f_inc 1.1, f_dec 0.5,
  /// f_alpha 0.99) with alpha_0 = 0.2 and the time step of the
  /// preconditioned force kept in [0.7, 1] (1 = a full Jacobi step): the
  /// boundary terms are not the gradient of one energy, so uphill steps are
  /// frequent in small packings, and halving the step down to 0.2 or less
  /// tripled their sweeps.
  static constexpr double dt_max = 1.0, dt_min = 0.7, alpha0 = 0.2;
  static constexpr int n_min = 5;

  struct Sums
  {
    double max_ov, max_pen, power, ff;
  };

  /// The neighbour lists and the spheres near the boundary, again.
  void rebuild()
  {
    _nb = neighbours(_p.x, _p.r, _skin);
    _x_build = _p.x;
    ++_p.rebuilds;
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < _n; ++i)
      _near[i] = _g.sdf({_p.x[3 * i], _p.x[3 * i + 1], _p.x[3 * i + 2]}) > -(_p.r[i] + _hug + _skin);
  }

  /// Each sphere's displacement (the force) at radii scaled by s; the
  /// largest overlap and penetration, the power F.v and |F|^2 per block.
  Sums displacements(double s)
  {
    double max_ov = 0.0, max_pen = 0.0;
    const std::size_t blocks = _part.size();
#pragma omp parallel for schedule(static) reduction(max : max_ov, max_pen)
    for (std::size_t b = 0; b < blocks; ++b)
    {
      double power = 0.0, ff = 0.0;
      for (std::size_t i = b * block; i < std::min(_n, (b + 1) * block); ++i)
      {
        double d[3] = {0.0, 0.0, 0.0};
        const Ball bi = _ball[i];
        const double wi = bi.r * bi.r * bi.r;
        for (std::int32_t q2 = _nb.start[i]; q2 < _nb.start[i + 1]; ++q2)
        {
          const Ball bj = _ball[_nb.items[q2]];
          const double dx = bj.x - bi.x, dy = bj.y - bi.y, dz = bj.z - bi.z;
          const double d2 = dx * dx + dy * dy + dz * dz, reach = s * (bi.r + bj.r);
          if (d2 >= reach * reach || d2 <= 0.0)
            continue;
          const double dist = std::sqrt(d2);
          const double ov = reach - dist;
          max_ov = std::max(max_ov, ov);
          const double wj = bj.r * bj.r * bj.r;
          const double c = ov * wj / ((wi + wj) * dist);
          d[0] -= c * dx;
          d[1] -= c * dy;
          d[2] -= c * dz;
        }
        // Boundary: push back what crosses it; once grown, also pull the
        // outer layer (within hug of the boundary) onto it, so faces are
        // covered.
        if (_near[i])
        {
          const Point c{bi.x + d[0], bi.y + d[1], bi.z + d[2]};
          const double pen = _g.sdf(c) + s * bi.r;
          if (pen > 0.0 || (s >= 1.0 && pen > -_hug))
          {
            max_pen = std::max(max_pen, pen);
            const Point gr = gradient(_g, c, _h);
            const double move = pen > 0.0 ? pen : 0.5 * pen; // gentle pull onto the wall
            for (int k = 0; k < 3; ++k)
              d[k] -= move * gr[k];
          }
        }
        for (int k = 0; k < 3; ++k)
        {
          _f[3 * i + k] = d[k];
          power += d[k] * _v[3 * i + k];
          ff += d[k] * d[k];
        }
      }
      _part[b] = {power, ff, 0.0};
    }
    double power = 0.0, ff = 0.0;
    for (const auto& q2 : _part)
    {
      power += q2[0];
      ff += q2[1];
    }
    return {max_ov, max_pen, power, ff};
  }

  /// FIRE's control: speed up while the motion goes downhill, stop and
  /// restart gently when it goes uphill.
  void fire_control(double power)
  {
    if (power > 0.0)
    {
      if (++_n_pos > n_min)
      {
        _dt = std::min(1.1 * _dt, dt_max);
        _alpha *= 0.99;
      }
    }
    else
    {
      _n_pos = 0;
      _dt = std::max(0.5 * _dt, dt_min);
      _alpha = alpha0;
      std::fill(_v.begin(), _v.end(), 0.0);
    }
  }

  /// v += dt F; returns |v|^2 (summed per block).
  double kick()
  {
    const std::size_t blocks = _part.size();
#pragma omp parallel for schedule(static)
    for (std::size_t b = 0; b < blocks; ++b)
    {
      double vv = 0.0;
      for (std::size_t k = 3 * b * block; k < 3 * std::min(_n, (b + 1) * block); ++k)
      {
        _v[k] += _dt * _f[k];
        vv += _v[k] * _v[k];
      }
      _part[b][2] = vv;
    }
    double vv = 0.0;
    for (const auto& q2 : _part)
      vv += q2[2];
    return vv;
  }

  /// Mixes the velocity towards the force and moves (at most max_step per
  /// sweep: no sphere outruns its neighbour list).
  void move(double ff, double vv)
  {
    const double mix = ff > 0.0 ? _alpha * std::sqrt(vv / ff) : 0.0;
    double moved2 = 0.0;
#pragma omp parallel for schedule(static) reduction(max : moved2)
    for (std::size_t i = 0; i < _n; ++i)
    {
      double* vi = &_v[3 * i];
      double step2 = 0.0;
      for (int k = 0; k < 3; ++k)
      {
        vi[k] = (1.0 - _alpha) * vi[k] + mix * _f[3 * i + k];
        step2 += vi[k] * vi[k];
      }
      const double len = _dt * std::sqrt(step2);
      const double cap = _dt * (len > _max_step ? _max_step / len : 1.0);
      double m2 = 0.0;
      for (int k = 0; k < 3; ++k)
      {
        _p.x[3 * i + k] += cap * vi[k];
        const double dk = _p.x[3 * i + k] - _x_build[3 * i + k];
        m2 += dk * dk;
      }
      _ball[i] = {_p.x[3 * i], _p.x[3 * i + 1], _p.x[3 * i + 2], _p.r[i]};
      moved2 = std::max(moved2, m2);
    }
    _moved2 = moved2;
  }

  /// Jammed (the overlap no longer falls): back off by shrinking all radii.
  void back_off_if_jammed(double max_ov)
  {
    if (max_ov > 0.9 * _last_check && max_ov > _o.shrink_below * _rmin)
    {
      for (std::size_t i = 0; i < _n; ++i)
      {
        _p.r[i] *= backoff;
        _ball[i].r = _p.r[i];
      }
      ++_p.backoffs;
      std::fill(_v.begin(), _v.end(), 0.0);
    }
    _last_check = max_ov;
  }

  Packing& _p;
  const Region& _g;
  const PackingOptions& _o;
  const std::size_t _n;
  const double _rmin, _skin, _h, _hug, _max_step;
  double _dt = dt_min, _alpha = alpha0;
  int _n_pos = 0;
  std::vector<std::array<double, 3>> _part;
  std::vector<Ball> _ball; // what a neighbour read needs, in one cache line
  Csr _nb;
  std::vector<double> _x_build, _f, _v;
  std::vector<std::uint8_t> _near;
  double _last_check = 1e300, _moved2 = 1e300; // largest squared move since the last build
};
} // namespace

Packing generate_packing(const Region& g, const PackingOptions& o)
{
  check_options(o);
  // graded: the region's volume weighted by scale^-3 (what sets the count)
  const bool graded = static_cast<bool>(o.size_scale);
  Graded grade = graded ? graded_volume(g, o.size_scale) : Graded{g.volume, 1.0};
  const std::size_t n = sphere_count(g, o, grade);
  std::mt19937_64 gen(o.seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  Packing p;
  p.r.resize(n);
  const double q = o.radius_ratio;
  for (auto& r : p.r)
    r = 1.0 + (q - 1.0) * u01(gen);
  // the radii scaled to the target fraction (after the start, if graded:
  // each radius times the scale where its sphere starts)
  RadiusScale rs;
  if (!graded)
    fit_radii(p, g, o, grade, rs);
  stratified_start(p, g, o, grade, gen, u01, rs);
  Relaxation relax(p, g, o, rs.rmin);
  if (!relax.run())
  {
    std::ostringstream m;
    m << "packing did not converge in " << o.max_sweeps << " sweeps: overlap " << p.max_overlap
      << " Rmin (tolerance " << o.tolerance << "); lower the target fraction (" << o.target_fraction
      << ") or raise --max-sweeps";
    throw std::runtime_error(m.str());
  }
  relax.shrink_remaining();
  // (graded: the spheres added are those of scale 1, so a face is filled
  // where it is left wider than the largest of them allow)
  const double r_lo = rs.rmin_unit * std::pow(Relaxation::backoff, p.backoffs);
  p.filled = impl::fill_uncovered(p, g, r_lo, q * r_lo, relax.gradient_step());
  impl::morton_sort(p, g);
  return p;
}

} // namespace dembridge::dem
