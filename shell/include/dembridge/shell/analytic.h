#pragma once
/// @file analytic.h
/// Closed-form and semi-analytical references for beams (SI units). Used by
/// the tests and demos to judge the shell and solid models. No DOLFINx here.

namespace dembridge::shell::analytic
{

/// Rectangular cross-section of a beam bending about the axis parallel to
/// `width`: area A = width * depth, I = width * depth^3 / 12.
struct BeamSection
{
  double width;  ///< [m], along the bending axis
  double depth;  ///< [m], in the bending direction
  double area() const { return width * depth; }
  double second_moment() const { return width * depth * depth * depth / 12.0; }
};

/// First axial frequency of a clamped-free bar: c / (4 L), c = sqrt(E / rho) [Hz].
double axial_clamped_free_frequency(double E, double rho, double L);

/// Tip deflection of an Euler-Bernoulli cantilever under a tip load P [m]:
/// P L^3 / (3 E I).
double euler_bernoulli_tip_deflection(double P, double E, const BeamSection& s,
                                      double L);

/// Tip deflection of a Timoshenko cantilever under a tip load P [m]:
/// P L^3 / (3 E I) + P L / (k G A), G = E / (2 (1 + nu)).
double timoshenko_tip_deflection(double P, double E, double nu,
                                 const BeamSection& s, double L, double k);

/// First bending frequency of a clamped-free Euler-Bernoulli beam [Hz]:
/// (1.87510407)^2 / (2 pi L^2) sqrt(E I / (rho A)).
double euler_bernoulli_cantilever_frequency(double E, double rho,
                                            const BeamSection& s, double L);

/// First bending frequency of a clamped-free Timoshenko beam with shear
/// factor k and rotary inertia [Hz]. Solves the frequency equation by
/// shooting: for trial omega, the two solutions of
///   E I psi'' + k G A (w' - psi) + rho I omega^2 psi = 0,
///   k G A (w'' - psi') + rho A omega^2 w = 0
/// with w = psi = 0 at the clamp are integrated (RK4) to the free end, and
/// omega is a root of det[[M, V]] (moment E I psi' and shear k G A (w' - psi)
/// both zero). The first root is bracketed from below the Euler-Bernoulli
/// value and refined by bisection to 1e-12 relative.
double timoshenko_cantilever_frequency(double E, double nu, double rho,
                                       const BeamSection& s, double L,
                                       double k);

/// Mode shape of the first Euler-Bernoulli cantilever mode at x in [0, L],
/// normalised to 1 at the tip; `slope` returns dw/dx.
double cantilever_mode_shape(double x, double L);
double cantilever_mode_slope(double x, double L);

} // namespace dembridge::shell::analytic
