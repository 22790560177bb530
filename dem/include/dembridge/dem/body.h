#pragma once
/// @file body.h
/// Rigid bodies that the spheres touch: a projectile (6 degrees of freedom,
/// a solid of revolution: cylinder shank with a flat, hemispherical, conical
/// or tangent-ogive nose) and fixed bodies (planes, boxes) for supports and
/// walls. Each shape is a signed distance (negative inside) with its
/// gradient, exact near the surface. A sphere overlapping a body feels a
/// normal penalty and Coulomb friction (docs/method.md,
/// section 1.7b); the forces and torques are summed on the body, which DemSolver
/// integrates with the spheres' velocity-Verlet step.

#include "dembridge/dem/forces.h"
#include "dembridge/dem/neighbours.h"

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace dembridge::dem
{

enum class Nose
{
  flat,
  hemispherical,
  conical,
  ogive ///< tangent ogive of caliber-radius-head psi: arc radius psi d
};

/// What a body is made of, in its own frame. A projectile's axis is the
/// body's x axis, the nose pointing to +x, the tip at x = 0 (the shank
/// behind it, at x < 0); planes and boxes are given in the world frame
/// directly (they do not move).
struct Shape
{
  enum class Kind
  {
    projectile,
    plane, ///< the half space n . (x - point) < 0 is solid
    box    ///< axis-aligned, [lo, hi]
  };
  Kind kind = Kind::projectile;
  // projectile
  double diameter = 0.0;     ///< shank diameter d [m], > 0
  double length = 0.0;       ///< overall length, tip to tail [m], > nose length
  Nose nose = Nose::ogive;
  double crh = 3.0;          ///< ogive: caliber-radius-head psi, >= 0.5 (0.5: hemisphere-like tip)
  double cone_angle_deg = 30.0; ///< conical: half-angle at the tip [degree], in (0, 90)
  // plane and box
  std::array<double, 3> point{0, 0, 0}, normal{0, 0, 1};
  std::array<double, 3> lo{0, 0, 0}, hi{0, 0, 0};

  /// Length of the nose along the axis [m] (0 for a flat nose): d/2 for a
  /// hemisphere, (d/2) / tan(half-angle) for a cone, d sqrt(psi - 1/4) for
  /// a tangent ogive.
  double nose_length() const;
  /// Solid volume [m^3] (projectile).
  double volume() const;
  /// @throws std::runtime_error naming the value and what is allowed. A
  /// projectile must be at least as long as the rear half of its nose's
  /// shape reaches (2 x the nose length for an ogive, the diameter for a
  /// hemispherical nose), which lies inside the shank.
  void validate() const;
};

/// Signed distance of a point to a shape in the shape's own frame [m]
/// (negative inside) and its gradient (the unit outward normal at the
/// nearest surface point).
struct Distance
{
  double d;
  std::array<double, 3> n;
};
Distance signed_distance(const Shape& s, const std::array<double, 3>& x);

/// A rigid body: its shape, mass and inertia (principal, in the body frame),
/// and its state in the world frame.
struct RigidBody
{
  std::string name;
  Shape shape;
  bool fixed = false;             ///< fixed bodies do not move (planes and boxes always are)
  double mass = 0.0;              ///< [kg] (moving bodies)
  std::array<double, 3> inertia{0, 0, 0}; ///< principal moments about the body axes at the centre of mass [kg m^2]
  std::array<double, 3> centre{0, 0, 0};  ///< centre of mass in the body frame [m]
  std::array<double, 3> x{0, 0, 0};       ///< world position of the centre of mass [m]
  std::array<double, 9> R{1, 0, 0, 0, 1, 0, 0, 0, 1}; ///< rotation body -> world (row-major)
  std::array<double, 3> v{0, 0, 0};       ///< velocity of the centre of mass [m/s]
  std::array<double, 3> L{0, 0, 0};       ///< angular momentum about the centre of mass, world frame [kg m^2/s]
  std::array<double, 3> f{0, 0, 0}, t{0, 0, 0}; ///< force and torque of the contacts [N, N m]
  double friction = 0.0;          ///< Coulomb coefficient between the body and the spheres [-]

  /// Angular velocity, world frame [rad/s]: R I^-1 R^T L.
  std::array<double, 3> omega() const;
  double kinetic_energy() const;
  /// A point of the body frame in the world frame.
  std::array<double, 3> to_world(const std::array<double, 3>& q) const;
  /// A world point in the body frame.
  std::array<double, 3> to_body(const std::array<double, 3>& w) const;
};

/// A projectile of solid density `density` [kg/m^3]: mass, centre of mass
/// and inertia from its shape (by quadrature along the axis), the tip at
/// `tip` pointing along `direction`, moving at `velocity` [m/s].
RigidBody make_projectile(const std::string& name, const Shape& shape, double density,
                          const std::array<double, 3>& tip, const std::array<double, 3>& direction,
                          const std::array<double, 3>& velocity);

/// A fixed plane or box.
RigidBody make_wall(const std::string& name, const Shape& shape, double friction = 0.0);

/// Normal stiffness of a sphere of radius r on a rigid body [N/m]: twice a
/// link's K_n for two spheres of radius r (a sphere on a rigid wall is half
/// of the symmetric contact of the sphere and its mirror image), that is
/// cn E pi r with cn the contacts' factor of equation [1]; the tangential
/// stiffness is cs times it.
double body_contact_stiffness(const Material& m, double r);

/// The contacts of spheres with one body: the spheres in contact (sorted)
/// and their shear force on the sphere (3 per contact), and the spheres
/// close enough to be examined.
struct BodyContacts
{
  std::vector<std::int32_t> ids;
  std::vector<double> fs;
  std::vector<std::int32_t> near;           ///< spheres that may touch before the next refresh
  std::array<double, 3> x_refresh{0, 0, 0}; ///< body position at the last refresh
  std::array<double, 9> R_refresh{1, 0, 0, 0, 1, 0, 0, 0, 1}; ///< its orientation then
  std::size_t version = 0;                  ///< neighbour-list version at the last refresh
  bool refreshed = false;
  double friction_work = 0.0;               ///< energy dissipated by sliding [J]
};

/// A closed triangulated surface (for output): vertices (n, 3) and
/// triangles (m, 3) of vertex indices, outward-oriented.
struct SurfaceMesh
{
  std::vector<double> x;
  std::vector<std::int32_t> triangles;
  std::size_t vertices() const { return x.size() / 3; }
};

/// The surface of a projectile in its own frame: `rings` sections along the
/// nose (and the shank's two ends), each of `segments` points round the axis
/// on the exact section radius; closed at the tip (a point, or the flat
/// face) and at the tail. @throws unless the shape is a projectile.
SurfaceMesh body_surface(const Shape& s, int rings = 24, int segments = 32);

/// World bounding box of a body (planes: unbounded but along an axis normal).
std::pair<std::array<double, 3>, std::array<double, 3>> bounding_box(const RigidBody& b);

/// Refreshes c.near, the spheres within r_max + 2 skin of the body's
/// bounding box, when the neighbour list has changed or any point of the
/// body may have moved more than skin/2 since the last refresh (its centre's
/// move plus its turn times its length). Between two changes of the list a
/// sphere moves less than nl.drift() (0.6 skin), hence less than a skin from
/// where it was at the refresh: no other sphere can reach the body before
/// the next refresh.
void refresh_candidates(const Particles& p, const RigidBody& b, BodyContacts& c, const NeighbourList& nl);

/// Adds the contact forces of body b on the spheres (p.f, p.t) and sets the
/// body's (b.f, b.t), updating the shear history over the step dt. Normal
/// force K_n delta along the body's outward normal at the sphere's centre
/// (delta = r - distance), the contact point midway in the overlap; shear
/// force incremental (K_s times the tangential slip of the sphere's surface
/// over the body's), turned with the normal, capped at friction x K_n delta.
void body_forces(Particles& p, RigidBody& b, BodyContacts& c, const NeighbourList& nl, const Material& m,
                 double dt);

/// Elastic energy stored in the contacts of body b [J].
double body_contact_energy(const Particles& p, const RigidBody& b, const BodyContacts& c, const Material& m);

} // namespace dembridge::dem
