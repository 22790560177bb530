#pragma once
/// @file law.h
/// The concrete interaction law of the DE model (METHOD.md section 1, after
/// Hentz, Donze & Daudeville 2004) as pure functions: no state of their own,
/// the history passed in and out. Forces in N, lengths in m. Sign convention:
/// normal force F_n > 0 in tension; the compression force is F_c = -F_n.

#include <array>

namespace dembridge::dem
{

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<double, 9>; ///< row-major 3 x 3

/// Parameters of one cohesive link (or contact), from equation [1] and the
/// local strengths.
struct LinkLaw
{
  double kn;          ///< normal stiffness K_n [N/m]
  double ks;          ///< tangential stiffness K_s [N/m]
  double s_int;       ///< interaction surface S_int [m^2]
  double tensile;     ///< local tensile strength T [Pa]
  double cohesion;    ///< cohesion C0 [Pa]
  double tan_phi_i;   ///< tan of the internal friction angle [-]
  double tan_phi_c;   ///< tan of the contact friction angle [-]
  double zeta;        ///< softening factor [-] (rupture at (1 + zeta) x elastic limit)
};

/// State of a link after the normal law.
enum class NormalState
{
  elastic,
  softening,
  broken
};

/// Result of the normal law for a cohesive link.
struct NormalForce
{
  double fn;          ///< normal force, tension > 0 [N]
  double delta_max;   ///< updated largest elongation reached [m]
  NormalState state;
};

/// Normal force of a cohesive link at elongation delta = D - D_init [m].
/// Elastic (K_n delta) up to the peak S_int T at delta_e = S_int T / K_n;
/// then linear softening with slope -K_n / zeta to zero at
/// delta_r = (1 + zeta) delta_e, where the link breaks. Unloading from a
/// softened state follows the secant to the origin (METHOD.md choice).
/// Compression is elastic and never breaks the link.
/// @param delta_max largest elongation reached so far (history; start at 0)
NormalForce link_normal_force(double delta, double delta_max, const LinkLaw& p);

/// Softening envelope: the force on the loading path at elongation d >= 0.
double link_envelope(double d, const LinkLaw& p);

/// Energy dissipated by softening once the largest elongation is delta_max:
/// area under the loading path up to delta_max minus the energy the secant
/// still stores, 0 while elastic, S_int T delta_r / 2 at rupture [J].
double softening_dissipation(double delta_max, const LinkLaw& p);

/// Rotation of v by the rotation vector theta (Rodrigues, exact; series for
/// small angles, accurate to round-off).
Vec3 rotate(const Vec3& theta, const Vec3& v);

/// The rotation matrix of the rotation vector theta (same formula).
Mat3 rotation_matrix(const Vec3& theta);

/// Each sphere carries the old contact normal with its own rotation over
/// the step, m = R n_old; the material points of the contact then sit at
/// l_a m_a and -l_b m_b, while the branch says l_a n_new and -l_b n_new. The
/// tangential (w.r.t. n_new) mismatch is the shear increment of b w.r.t. a:
///   du_s = -D (f_a (m_a)_t + (1 - f_a) (m_b)_t),  l_a = f_a D.
/// For any rigid motion (same rotation for both spheres and the branch)
/// m_a = m_b = n_new and du_s = 0 to round-off (objectivity); for small
/// rotations it is the classical relative velocity at the contact point
/// times dt. @param ra, rb rotations of a and b over the step;
/// @param d branch length [m]; @param fa = R_a / (R_a + R_b)
Vec3 shear_increment(const Vec3& n_old, const Vec3& n_new, const Mat3& ra, const Mat3& rb,
                     double d, double fa);

/// Carries a stored shear force over the step: turned by f_a R_a + f_b R_b
/// (the pair's rotation), then projected on the tangent plane of n_new; a
/// rigid motion turns it exactly with the pair.
Vec3 rotate_shear(const Vec3& fs, const Mat3& ra, const Mat3& rb, double fa, const Vec3& n_new);

/// Result of the shear law.
struct ShearForce
{
  Vec3 fs;            ///< shear force on b (the force on a is -fs) [N]
  bool exceeded;      ///< the cap was reached (link: breaks; contact: slides)
  double slip_energy; ///< energy dissipated by sliding in this increment [J]
};

/// Incremental shear force of a link: fs_trial = fs - K_s du_s, capped by the
/// Mohr-Coulomb criterion |fs| <= S_int C0 + F_c tan(phi_i). If exceeded the
/// link breaks (caller turns it into a contact); fs is returned unchanged
/// (trial value) with exceeded = true.
/// @param du_s tangential relative displacement increment of b w.r.t. a [m]
/// @param fn normal force (tension > 0) [N]
ShearForce link_shear_force(const Vec3& fs, const Vec3& du_s, double fn, const LinkLaw& p);

/// Normal force of a contact (no link): compression only,
/// F_n = -K_n (R_a + R_b - D) when D < R_a + R_b, else 0.
double contact_normal_force(double distance, double radius_sum, double kn);

/// Incremental Coulomb friction of a contact: fs_trial = fs - K_s du_s,
/// |fs| <= F_c tan(phi_c); on sliding fs is scaled back to the cap and the
/// dissipated energy (cap x slip) is returned.
ShearForce contact_shear_force(const Vec3& fs, const Vec3& du_s, double fn, const LinkLaw& p);

/// Torques from a shear force fs acting on b (and -fs on a) at the contact
/// point, which lies at l_a n from a's centre and -l_b n from b's (n the unit
/// normal from a to b): t_a = (l_a n) x (-fs) = -l_a n x fs,
/// t_b = (-l_b n) x fs = -l_b n x fs. Returns {t_a, t_b}. With
/// l_a + l_b = D (lever arms in proportion to the radii) a rigid rotation of
/// the pair gives no relative motion at that point (objectivity).
std::array<Vec3, 2> shear_torques(const Vec3& n, const Vec3& fs, double l_a, double l_b);

} // namespace dembridge::dem
