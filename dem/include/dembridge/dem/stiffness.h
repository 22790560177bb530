#pragma once
/// @file stiffness.h
/// Micro-macro relations of the DE model (paper's equation [1], after Hentz,
/// Donze & Daudeville 2004). Pure functions; no DOLFINx in dem/.

namespace dembridge::dem
{

/// Packing-dependent coefficients of equation [1], identified on the
/// assembly (docs/method.md section 1.4).
struct MicroMacro
{
  double alpha;
  double beta;
  double gamma;
};

/// Normal and tangential stiffness of one link [N/m].
struct LinkStiffness
{
  double kn;
  double ks;
};

/// Interaction surface S_int = pi min(Ra, Rb)^2 [m^2] (a choice of the project: docs/method.md section 1.4).
/// @throws std::runtime_error if a radius is not > 0.
double interaction_surface(double ra, double rb);

/// Equation [1]:
///   K_n = E S_int / D_init (1 + alpha) / (beta (1 + nu) + gamma (1 - alpha nu))
///   K_s = K_n (1 - alpha nu) / (1 + nu)
/// @param E Young's modulus [Pa], > 0; @param nu Poisson's ratio in (-1, 0.5)
/// @param s_int interaction surface [m^2]; @param d_init initial distance [m]
/// @throws std::runtime_error naming the value if an input is out of range or
///   the denominator is not positive.
LinkStiffness link_stiffness(double E, double nu, double s_int, double d_init,
                             const MicroMacro& c);

} // namespace dembridge::dem
