#pragma once
/// @file conditions.h
/// Boundary conditions of the DEM on sets of spheres: kinematic conditions
/// (fixed, prescribed velocity or displacement, optionally hinged) and
/// external forces (optionally through a rigid, possibly rotating, loading
/// plate). DemSolver (solver.h) applies them.

#include "dembridge/core/stepping.h"

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace dembridge::dem
{

/// (core/stepping.h) On spheres: fixed holds translations and rotations at
/// zero velocity; velocity, the chosen components follow value(t) [m/s];
/// displacement, they follow x0 + value(t) [m].
using core::History;
using core::MotionKind;

/// A kinematic condition on a set of particles.
struct ParticleMotion
{
  std::string name;
  std::vector<std::int32_t> ids;
  MotionKind kind = MotionKind::fixed;
  std::array<bool, 3> components{true, true, true}; ///< for velocity/displacement
  History value;
  /// For velocity/displacement: the set follows value(t) as a plate hinged
  /// at its centroid: for each chosen component, the set's mass-weighted mean
  /// follows value(t) and its rotations normal to that component stay free
  /// (the component is an affine function of position, its slopes fitted to
  /// the spheres' own velocities as for ParticleForce::plate_rotates).
  /// Its spheres are kicked by their forces like free ones, then moved as
  /// the plate; its reaction is the force on the plate's mean motion. It
  /// shares no sphere with another condition or a loading plate. Without it
  /// each sphere follows value(t): the set cannot rotate.
  bool rotates = false;
  /// With `rotates`: a non-zero axis [any length] makes the set a hinge
  /// about that axis through its centroid: component k becomes affine
  /// along e_k x axis only (the one direction a rotation about the axis
  /// moves it along), so a support line hinged about y lets a beam along x
  /// turn in its plane of bending and holds its roll and its twist. Each
  /// component's slope is fitted on its own, as for `rotates` alone, so
  /// with two components chosen the set may also shear in the plane
  /// normal to the axis. Zero: both rotations normal to each component are
  /// free.
  std::array<double, 3> axis{0.0, 0.0, 0.0};
  /// A hinged set: it rotates and moves (a fixed set holds everything).
  bool hinged() const { return rotates && kind != MotionKind::fixed; }
};

/// External force on each particle of a set: direction * value(t) [N].
struct ParticleForce
{
  std::string name;
  std::vector<std::int32_t> ids;
  std::array<double, 3> direction{1.0, 0.0, 0.0};
  History value;
  /// Load through a rigid plate: the spheres' velocity components along
  /// `direction` are made equal (their mass-weighted mean, so momentum is
  /// kept) after every kick, so the set moves as one along the load and the
  /// total force spreads as a stiff loading plate spreads it, whatever each
  /// sphere's bonds (an equal share per sphere would push a loosely bonded
  /// surface sphere far out). Other components stay free. No kinematic
  /// condition may hold its spheres along `direction` (one holding other
  /// components, e.g. a platen held axially under a side plate, may).
  bool plate = false;
  /// With `plate`: the plate may also rotate, as one loaded through a ball
  /// joint: the velocity components along `direction` are made an affine
  /// function of position, v_d = V + g . (x - c) with g normal to the load
  /// (the rigid rotations' share of v_d), fitted by mass-weighted least
  /// squares (so momentum and the moments about the centroid c are kept).
  /// The plate then carries the load and no moment. Without it, the plate
  /// only translates: it holds its own rotation, and so the end of a bent
  /// bar (a plate of end spheres a centimetre deep in x clamps that layer's
  /// rotation and takes ~2 % of the moment).
  bool plate_rotates = false;
};

} // namespace dembridge::dem
