#pragma once
/// @file beam.h
/// A reinforced-concrete beam of DE concrete with steel bars in quasi-static
/// three-point bending (docs/validation.md section 2.10): the load against
/// the midspan deflection, the cracking load, the cracked stiffness and the
/// first yield of the bars, beside the values of reinforced-concrete section
/// theory.

#include "dembridge/dem/assembly.h"
#include "dembridge/dem/bars.h"

#include <nlohmann/json.hpp>

#include <array>
#include <span>
#include <string>

namespace dembridge::demo
{

struct BeamConfig
{
  double span = 0.6;          ///< between the supports [m]
  double overhang = 0.025;    ///< beyond each support [m]
  double height = 0.1;        ///< [m]
  double width = 0.1;         ///< [m]
  int bars = 2;               ///< bars at the bottom, along the beam
  double bar_diameter = 6e-3; ///< [m]
  double cover = 0.02;        ///< bottom face to the bars' axes [m]
  bool skin_compensation = true; ///< stiffen the links of the spheres near the faces (dem/skin.h)
  bool hinged_supports = true; ///< the supports turn about their lines (false: held bands)
  dem::Steel steel;
  dem::BondLaw bond;
  dem::Material material;
  double links_per_sphere = 12.0;
  double tensile_strength = 0.0; ///< the concrete's macroscopic sigma_t for the theory [Pa] (the material file's)
  double concrete_modulus = 0.0; ///< its macroscopic E for the theory [Pa] (the material file's)
  double concrete_poisson = 0.2; ///< its macroscopic nu for the theory's shear deflection (the material file's)
  double mean_radius = 5e-3;  ///< [m]
  double radius_ratio = 2.0;
  unsigned seed = 1;
  double deflection = 0.0;    ///< midspan deflection to reach [m]; 0 = 2 x the theory's at first yield
  double speed = 0.04;        ///< the loading plate's speed [m/s] (reached over ramp_time)
  double ramp_time = 0.0;     ///< [s]; 0 = 4 periods of the first bending mode
  double damping = 0.0;       ///< [1/s]; 0 = 0.1 x the first bending mode's circular frequency
  double safety = 0.5;        ///< fraction of the critical time step
  int frames = 20;
  std::string output_dir;     ///< "" = no files
  bool quiet = false;
};

/// Section theory of the beam (transformed sections, n = E_s / E):
/// uncracked (bars as n - 1 times their area) and fully cracked (concrete
/// in tension ignored) second moments, the cracking moment f_ct,fl I / y_t
/// (the flexural tensile strength of fib MC2010, (1 + 0.06 h^0.7) / (0.06 h^0.7)
/// sigma_t with h in mm; Eurocode 2's max(1.6 - h[m], 1) sigma_t beside it),
/// the first-yield moment A_s f_y (d - c / 3), and the deflection at a
/// midspan load P, integrating the curvature M / (E I) with I uncracked
/// where |M| < M_cr and cracked elsewhere, plus the shear deflection
/// P L / (4 kappa G A). With tension stiffening (Eurocode 2, 7.4.3, eq.
/// 7.18-7.19, a single short-term load: beta = 1) the cracked part's
/// curvature is zeta M / (E I_cr) + (1 - zeta) M / (E I), zeta = 1 - (M_t / M)^2,
/// M_t the moment at which the uncracked section reaches sigma_t (f_ctm, as
/// Eurocode 2 7.1(2) asks for tension stiffening): the concrete between the
/// cracks still carries tension.
struct BeamTheory
{
  double n = 0.0, d = 0.0;                 ///< modular ratio; depth of the bars [m]
  double i_uncracked = 0.0, y_uncracked = 0.0; ///< [m^4]; neutral axis from the top [m]
  double i_cracked = 0.0, c_cracked = 0.0;   ///< [m^4]; neutral axis from the top [m]
  double f_ct_fl = 0.0;                      ///< flexural tensile strength (MC2010) [Pa]
  double f_ct_fl_ec2 = 0.0;                  ///< the same of Eurocode 2 [Pa]
  double m_cracking = 0.0, p_cracking = 0.0; ///< [N m], [N]
  double m_yield = 0.0, p_yield = 0.0;       ///< [N m], [N]
  double deflection(const BeamConfig& c, double load, bool tension_stiffening = false) const; ///< [m]
};
BeamTheory beam_theory(const BeamConfig& c);

/// The change of slope of a curve y(x) that starts at the origin (a load
/// against a deflection): the breakpoint xb of the continuous two-line
/// least-squares fit y = a min(x, xb) + b max(x - xb, 0) over the points
/// with 0 < x <= x_end, xb searched over 5-90 % of x_end in steps of 0.25 %.
/// Returns {xb, a xb}; {0, 0} with fewer than 4 such points or where every
/// breakpoint leaves the fit singular.
std::array<double, 2> change_of_slope(std::span<const double> x, std::span<const double> y, double x_end);

/// Runs the beam; returns the summary (docs/demos.md, rc_beam).
nlohmann::json run_beam(const BeamConfig& c);

/// Least-squares line y = a x + b through the points added.
struct LineFit
{
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  void add(double x, double y)
  {
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    ++n;
  }
  double det() const { return n * sxx - sx * sx; }
  double slope() const { return (n * sxy - sx * sy) / det(); }
  double intercept() const { return (sy - slope() * sx) / n; }
};

/// Least-squares slope of y against x over the points with lo <= y <= hi
/// before y first exceeds hi (the loading branch, not the points where the
/// load falls back into the window after a crack).
double slope(const std::vector<double>& x, const std::vector<double>& y, double lo, double hi);

} // namespace dembridge::demo
