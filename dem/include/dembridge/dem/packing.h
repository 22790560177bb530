#pragma once
/// @file packing.h
/// Dense, polydisperse, isotropic sphere packings filling a region given by a
/// signed-distance function (box, cylinder, or any), and plain `x y z r`
/// packing files.
///
/// Method (a collective-rearrangement generator; any method that meets
/// the figures below would do): radii are drawn from the distribution, their
/// number set by the target packing fraction and the region's volume;
/// centres start one per cell of a grid (cells picked at random, centres
/// jittered within them) with radii scaled down to 0.8; then sweeps push every
/// overlapping pair apart (each sphere by its share of the overlap, weighted
/// by the other's volume) and push spheres that cross the boundary back
/// inside, while the radii grow to full size; these displacements drive a
/// FIRE minimiser (Bitzek et al. 2006), about 3x fewer sweeps than plain
/// momentum. Once grown, spheres within Rmin of the boundary are also pulled
/// onto it, so faces are covered. If the overlap stops falling (jammed: the
/// target was too dense for the region), all radii are scaled by 0.998 and
/// the sweeps go on, so the target fraction is an upper bound; `backoffs`
/// counts these steps. It stops when no overlap or boundary penetration
/// exceeds the tolerance, or, once they are below `shrink_below` Rmin,
/// shrinks the spheres still overlapping by what is left (reported: count
/// and largest reduction). Last, wherever a point of the boundary is left
/// farther than 0.75 Rmax from every sphere, the largest sphere in [Rmin,
/// Rmax] tangent to the boundary there that overlaps nothing is added
/// (`filled`): no gap at a flat face is wider than Rmax. The result is
/// renumbered along a Morton curve (memory order follows space).
/// Deterministic for a seed, whatever the thread count.

#include <array>
#include <filesystem>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace dembridge::dem
{

using Point = std::array<double, 3>;

/// A region: sdf(x) < 0 inside, > 0 outside, |grad sdf| = 1 near the boundary.
struct Region
{
  std::string name;
  std::function<double(const Point&)> sdf;
  Point lo, hi;       ///< bounding box [m]
  double volume;      ///< [m^3]
};

/// Axis-aligned box [lo, hi]. @throws if any hi <= lo.
Region box_region(const Point& lo, const Point& hi);
/// Cylinder of the given radius and height, axis along z from `base`.
Region cylinder_region(const Point& base, double radius, double height);
/// Any region from its signed distance and bounding box; the volume is
/// measured on a grid of 100^3 points (1e-2 relative for smooth shapes).
Region sdf_region(const std::string& name, std::function<double(const Point&)> sdf,
                  const Point& lo, const Point& hi);

struct PackingOptions
{
  double mean_radius = 0.0;     ///< mean radius [m] (used if count == 0)
  std::size_t count = 0;        ///< number of spheres (0: from mean_radius), before the boundary is filled
  double radius_ratio = 2.0;    ///< Rmax / Rmin, in [1, 3]; radii uniform in [Rmin, Rmax]
  double target_fraction = 0.60;///< solid fraction of the whole region (the bulk gets ~0.62)
  double tolerance = 1e-3;      ///< allowed overlap and penetration, fraction of Rmin
  unsigned seed = 1;
  int max_sweeps = 20000;
  /// sweeps over which the radii grow from 0.8 to 1 (300: the same bulk
  /// fraction as 1000; 200 or fewer jam the packing, then the backoffs cost
  /// more sweeps than they saved)
  int growth_sweeps = 300;
  /// Once overlaps and penetrations are below this fraction of Rmin, the
  /// spheres still overlapping are shrunk to remove them (0: never).
  /// 0.05: the slow end of the settling saved, radii of the spheres
  /// concerned reduced by at most ~3 % of Rmin.
  double shrink_below = 0.05;
  /// Graded packings: the radius scale at a point, in (0, 1]. A sphere's
  /// radius is its draw from [Rmin, Rmax] times the scale where it starts,
  /// and the spheres start with a density proportional to scale^-3, so the
  /// solid fraction is the same everywhere. mean_radius is the mean where the
  /// scale is 1. Empty: 1 everywhere (a uniform packing).
  std::function<double(const Point&)> size_scale;
  bool verbose = false;
};

struct Packing
{
  std::vector<double> x;  ///< centres (n, 3) [m]
  std::vector<double> r;  ///< radii [m]
  int sweeps = 0;
  double max_overlap = 0.0;     ///< largest pair overlap / Rmin
  double max_penetration = 0.0; ///< largest boundary penetration / Rmin
  std::size_t shrunk = 0;       ///< spheres shrunk by the final step
  std::size_t filled = 0;       ///< spheres added where the boundary was left uncovered
  int backoffs = 0;             ///< times all radii were scaled by 0.998 to unjam
  int rebuilds = 0;             ///< neighbour-list rebuilds
  double max_shrink = 0.0;      ///< largest radius reduction / Rmin
  std::size_t size() const { return r.size(); }
};

/// The fill step of generate_packing on its own: wherever the boundary of
/// `region` is left uncovered (a point of it farther than 0.75 rmax from
/// every sphere), adds the largest sphere of radius in [rmin, rmax] tangent
/// to it there that overlaps nothing, then renumbers the packing along its
/// Morton curve. For a packing whose region gained holes after it was made
/// (bars: the spheres on them removed, bars.h): the spheres added line the
/// holes. Returns the number added (also added to p.filled).
std::size_t fill_boundary(Packing& p, const Region& region, double rmin, double rmax);

/// Generates a packing. @throws std::runtime_error on bad options (radius
/// ratio outside [1, 3], radius <= 0, fraction outside (0, 0.74), a size
/// scale outside (0, 1]) or if it does not converge in max_sweeps (the
/// message gives the overlap reached).
Packing generate_packing(const Region& region, const PackingOptions& opt);

/// Solid fraction inside the region shrunk by `margin` [m] (sdf < -margin),
/// measured on a regular grid of about `samples` points.
double packing_fraction(const Packing& p, const Region& region, double margin,
                        std::size_t samples = 2000000);

/// Largest distance from a point of the face sdf = 0 to the nearest sphere
/// surface, sampled on a grid over the given flat face {x : x[axis] = value}
/// within the region and at least Rmax from the face's edges [m]: the widest
/// gap at that face.
double face_gap(const Packing& p, const Region& region, int axis, double value,
                int samples_per_side = 200);

/// One flag per sphere: 1 if its centre lies at least `margin` inside the
/// region (sdf < -margin), e.g. the bulk for dem::lambda_for_mean_links.
std::vector<std::uint8_t> inside(const Region& region, std::span<const double> x, double margin);
/// The bulk of a packing: 1 for the spheres whose centre lies 2 Rmax or more
/// inside the region (their neighbourhood within lambda (Ra + Rb) is whole
/// for lambda up to ~1.5). @throws if there is none (region too small).
std::vector<std::uint8_t> bulk_spheres(const Region& region, std::span<const double> x,
                                       std::span<const double> r);
/// Interaction range lambda giving `links_per_sphere` links per sphere on
/// average in the bulk: over the bulk_spheres
/// (their links to any sphere counted). The spheres at a face miss
/// neighbours; counting them would raise lambda, the more so the smaller the
/// sample, and make the bulk of a small sample stiffer than that of a
/// large one (measured: E 27.4 GPa on 400 spheres, 23.8 GPa on 3,200, with
/// the same parameters). @throws if no sphere is that far inside.
double lambda_for_bulk_links(const Region& region, std::span<const double> x, std::span<const double> r,
                             double links_per_sphere);
/// Writes `x y z r` lines (full precision).
void write_packing(const std::filesystem::path& file, const Packing& p);
/// Reads `x y z r` lines ('#' starts a comment). @throws std::runtime_error
/// naming the file and line for a malformed line or a radius <= 0.
Packing read_packing(const std::filesystem::path& file);
/// The packing's largest protrusion out of `region`: the largest
/// (sdf(centre) + r) / r over its spheres, with the sphere's index. A
/// generated packing keeps every sphere inside (0 or below, to round-off);
/// a file of another region's spheres, or one with a radius out of scale,
/// gives far more.
std::pair<double, std::size_t> largest_protrusion(const Region& region, const Packing& p);
/// Checks that a packing read from a file fits `region`: every centre inside
/// it, and no sphere out of it by more than half its radius.
/// @throws std::runtime_error starting with `what` (the option or key and
///   the file), naming the sphere, its radius and the region.
void check_packing_fits(const Region& region, const Packing& p, const std::string& what);

} // namespace dembridge::dem
