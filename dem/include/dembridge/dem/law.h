#pragma once
/// @file law.h
/// The concrete interaction law of the DE model (docs/method.md sections 1.5-1.8, after
/// Hentz, Donze & Daudeville 2004) as pure functions: no state of their own,
/// the history passed in and out. Forces in N, lengths in m. Sign convention:
/// normal force F_n > 0 in tension; the compression force is F_c = -F_n.

#include <algorithm>
#include <array>
#include <cmath>

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
  /// Tresca limit of the contacts' friction: |fs| <= S_int shear_limit
  /// beside F_c tan(phi_c) [Pa]; 0 = none (Material::contact_shear_limit)
  double shear_limit = 0.0;
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
/// softened state follows the secant to the origin (a choice of the project: docs/method.md section 1.6).
/// Compression is elastic and never breaks the link.
/// @param delta_max largest elongation reached so far (history; start at 0)
NormalForce link_normal_force(double delta, double delta_max, const LinkLaw& p);

/// Compaction of a link in compression (docs/method.md section 1.6c): the
/// pores of concrete collapse under high confinement. In terms of the
/// link's compressive strain e = -delta / D_init, the compression force
/// follows the envelope
///   f(e) = K_n D_init e                                   e <= onset
///   f(e) = K_n D_init (onset + stiffness (e - onset))     onset < e <= lock
///   f(e) = K_n D_init (onset + stiffness (lock - onset) + e - lock)   e > lock
/// (pores collapsing at `stiffness` x K_n, then closed: K_n again); below
/// the largest strain reached, e_max, the link unloads and reloads
/// elastically (K_n) from the permanent set it left. The set shifts the
/// rest of the law: elongation, softening and rupture count from it.
struct CompactionLaw
{
  double onset = 0.0;     ///< compressive strain where pores start to collapse [-]; 0 = no compaction
  double stiffness = 1.0; ///< tangent stiffness while compacting / K_n, in (0, 1] [-]
  double lock = 0.0;      ///< compressive strain where the pores are closed, > onset [-]
  /// Pressure gate [Pa]; 0 = none. With a gate a link starts compacting
  /// only while the mean pressure of its two spheres is at least this: until
  /// then its onset follows its compressive strain (Links::compaction_onset),
  /// so that compaction starts, without a jump of the force, from the strain
  /// the link has when the gate first opens; its lock strain moves with it.
  double pressure = 0.0;
  bool on() const { return onset > 0.0; }
  bool gated() const { return on() && pressure > 0.0; }
  /// The same law from another onset [-], its lock strain moved as much.
  CompactionLaw from(double new_onset) const
  {
    return {new_onset, stiffness, lock + (new_onset - onset), pressure};
  }
};

/// The envelope's compression force over K_n D_init [-] (a strain).
inline double compaction_envelope(double e, const CompactionLaw& c)
{
  if (e <= c.onset)
    return e;
  if (e <= c.lock)
    return c.onset + c.stiffness * (e - c.onset);
  return c.onset + c.stiffness * (c.lock - c.onset) + (e - c.lock);
}

/// The permanent set (<= 0) [m] the largest compressive strain e_max leaves:
/// the elongation where the elastic unloading from the envelope at e_max
/// reaches zero force, -D_init (e_max - envelope(e_max)).
inline double compaction_set(double e_max, double d_init, const CompactionLaw& c)
{
  return e_max > c.onset ? -d_init * (e_max - compaction_envelope(e_max, c)) : 0.0;
}

/// Energy dissipated by compaction once the largest compressive strain is
/// e_max [J]: the work along the envelope, K_n D_init^2 times its integral
/// up to e_max, less what the elastic unloading gives back, f^2 / (2 K_n).
double compaction_dissipation(double e_max, double kn, double d_init, const CompactionLaw& c);

/// Dynamic increase factor of concrete's tensile strength at the strain rate
/// `rate` [1/s], Malvar and Ross (1998), for a compressive strength fc [Pa]:
///   DIF = (rate / rate_s)^delta            rate_s < rate <= 1 /s
///   DIF = beta (rate / rate_s)^(1/3)       rate > 1 /s
/// with rate_s = 1e-6 /s, delta = 1 / (1 + 8 fc / fc0), fc0 = 10 MPa,
/// log10 beta = 6 delta - 2 (continuous at 1 /s); 1 at and below rate_s
/// (and for compression, rate < 0). docs/method.md section 1.6b.
double malvar_ross_dif(double rate, double fc);

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
/// R - I for the same rotation, without forming R: exactly zero for
/// theta = 0, and accurate to round-off relative to |theta| for small ones.
Mat3 rotation_minus_identity(const Vec3& theta);

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

/// A rotation over a step in four numbers (what the force loop keeps per
/// sphere, beside its centre and radius, in one 64-byte record):
/// u = (sin a / a) theta and k = 1 / (1 + cos a), a = |theta| < pi. Then
///   R - I = [u]x + k (u u^T - |u|^2 I),
/// Rodrigues' formula with (1 - cos a) / a^2 = k (sin a / a)^2. Zero rotation
/// gives u = 0 exactly, hence R - I = 0 exactly.
struct StepRotation
{
  Vec3 u;   ///< (sin a / a) theta [-]
  double k; ///< 1 / (1 + cos a) [-]
};
/// @param theta rotation vector, |theta| < pi (the force loop asks < 1 rad)
StepRotation step_rotation(const Vec3& theta);
/// (R - I) v for the rotation q, without forming R.
Vec3 rotation_minus_identity_times(const StepRotation& q, const Vec3& v);
/// R - I of the rotation q as a matrix (worth forming for a sphere's links
/// together: 15 operations per product instead of 27).
Mat3 rotation_minus_identity(const StepRotation& q);

/// Trial shear force of the step, before any cap, in one product:
///   fs_trial = P (Rp (fs_old + K_s D n_old)),
/// with Rp = f_a R_a + f_b R_b the pair's rotation and P the projection on
/// the tangent plane of n_new. Both rotate_shear and shear_increment are Rp
/// then P, and linear, so this equals rotate_shear(fs_old) - K_s
/// shear_increment(n_old) to round-off, at a third of the cost (what the
/// force loop uses). It evaluates, with Qp = Rp - I and since P n_new = 0,
///   fs_trial = P (fs_old + K_s D (n_old - n_new) + Qp (fs_old + K_s D n_old)),
/// so that no term of size K_s D cancels another: the round-off is relative
/// to the shear force and its increment, and a link that neither turns nor
/// spins (n_new == n_old, Qp = 0) keeps its force exactly. (P Rp (fs_old +
/// K_s D n_old) as written leaves K_s D eps, ~1e-11 N for concrete links, on
/// a link at rest, every step.)
/// @param qa R_a - I, sphere a's rotation over the step (a matrix: the force
/// loop forms it once for all links of a); @param qb sphere b's rotation
/// @param fa = R_a / (R_a + R_b); @param ks_d K_s times the branch length D [N]
Vec3 trial_shear(const Vec3& fs_old, const Vec3& n_old, const Vec3& n_new, const Mat3& qa,
                 const StepRotation& qb, double fa, double ks_d);


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
/// The same cap applied to a trial force already computed (trial_shear).
ShearForce link_shear_cap(const Vec3& fs_trial, double fn, const LinkLaw& p);

/// Normal force of a contact (no link): compression only,
/// F_n = -K_n (R_a + R_b - D) when D < R_a + R_b, else 0.
double contact_normal_force(double distance, double radius_sum, double kn);

/// Incremental Coulomb friction of a contact: fs_trial = fs - K_s du_s,
/// |fs| <= F_c tan(phi_c); on sliding fs is scaled back to the cap and the
/// energy dissipated over the increment is returned: the work of the mean
/// shear force over the increment, (fs + fs_new) . du / 2, less the change
/// of the spring's energy, that is (fs + fs_new) . (fs_trial - fs_new) /
/// (2 K_s) -- cap x slip when sliding goes on at the cap, half that in the
/// step where sliding starts from rest, 0 without a cap (phi_c = 0).
ShearForce contact_shear_force(const Vec3& fs, const Vec3& du_s, double fn, const LinkLaw& p);
/// The same cap applied to a trial force already computed (trial_shear);
/// fs_prev: the force of the previous step (for the dissipated energy).
ShearForce contact_shear_cap(const Vec3& fs_trial, double fn, const LinkLaw& p, const Vec3& fs_prev);

/// Rolling resistance of a contact (docs/method.md section 1.7d; the
/// elastic-plastic spring of Iwashita and Oda 1998, as in Ai et al. 2011's
/// "type C" models): a moment M on b (and -M on a) in the tangent plane.
/// Trial moment of the step, before the cap:
///   M_trial = P (Rp M_old - k_r dtheta),
/// with Rp = f_a R_a + f_b R_b the pair's rotation (as trial_shear carries
/// the shear force), dtheta = (w_b - w_a) dt b's rotation relative to a
/// over the step and P the projection on the tangent plane of n_new (the
/// twist about the normal is not resisted). A rigid rotation of the pair
/// (w_a = w_b) carries the moment with it and adds none.
/// @param qa R_a - I; @param qb sphere b's rotation; @param fa = R_a / (R_a + R_b);
/// @param kr rolling stiffness [N m / rad]
Vec3 trial_rolling(const Vec3& m_old, const Vec3& n_new, const Mat3& qa, const StepRotation& qb,
                   double fa, const Vec3& dtheta, double kr);
/// The rolling moment's cap |M| <= mu_r R* F_c (F_c = -fn, the contact's
/// compression; arm = mu_r R*, R* = R_a R_b / (R_a + R_b)), applied as
/// contact_shear_cap applies Coulomb's to the shear force, with the same
/// energy: (M_prev + M_new) . (M_trial - M_new) / (2 k_r) dissipated by
/// rolling in the step where the cap holds. Returns the moment in `fs`.
ShearForce contact_rolling_cap(const Vec3& m_trial, double fn, double kr, double arm, const Vec3& m_prev);

/// Torques from a shear force fs acting on b (and -fs on a) at the contact
/// point, which lies at l_a n from a's centre and -l_b n from b's (n the unit
/// normal from a to b): t_a = (l_a n) x (-fs) = -l_a n x fs,
/// t_b = (-l_b n) x fs = -l_b n x fs. Returns {t_a, t_b}. With
/// l_a + l_b = D (lever arms in proportion to the radii) a rigid rotation of
/// the pair gives no relative motion at that point (objectivity).
std::array<Vec3, 2> shear_torques(const Vec3& n, const Vec3& fs, double l_a, double l_b);

// ---------------------------------------------------------------------------
// Definitions, inline so that the force loop compiles them into its sweep
// (the common cases avoid divisions and square roots).
namespace detail
{
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b)
{
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline Vec3 mul(const Mat3& r, const Vec3& v)
{
  return {r[0] * v[0] + r[1] * v[1] + r[2] * v[2], r[3] * v[0] + r[4] * v[1] + r[5] * v[2],
          r[6] * v[0] + r[7] * v[1] + r[8] * v[2]};
}
/// sin(a)/a and (1 - cos a)/a^2 for a^2 = a2 (series for small angles:
/// next terms below 1e-19 for a < 1e-2).
inline void rodrigues_factors(double a2, double& sa, double& ca)
{
  if (a2 < 1e-4)
  {
    sa = 1.0 - a2 / 6.0 + a2 * a2 / 120.0 - a2 * a2 * a2 / 5040.0;
    ca = 0.5 - a2 / 24.0 + a2 * a2 / 720.0 - a2 * a2 * a2 / 40320.0;
  }
  else
  {
    const double a = std::sqrt(a2);
    sa = std::sin(a) / a;
    ca = (1.0 - std::cos(a)) / a2;
  }
}
} // namespace detail

inline double link_envelope(double d, const LinkLaw& p)
{
  const double f_peak = p.s_int * p.tensile;
  const double de = f_peak / p.kn;
  if (d <= de)
    return p.kn * d;
  const double dr = (1.0 + p.zeta) * de;
  if (d >= dr)
    return 0.0;
  return f_peak - p.kn / p.zeta * (d - de);
}

inline NormalForce link_normal_force(double delta, double delta_max, const LinkLaw& p)
{
  const double f_peak = p.s_int * p.tensile;
  const double dm = std::max(delta, delta_max);
  // never beyond the elastic limit (K_n dm <= S_int T): elastic
  if (p.kn * dm <= f_peak)
    return {p.kn * delta, delta > 0.0 ? dm : delta_max, NormalState::elastic};
  const double de = f_peak / p.kn;
  const double dr = (1.0 + p.zeta) * de;
  if (delta <= 0.0)
    return {p.kn * delta, delta_max, NormalState::softening}; // compression: elastic
  if (dm >= dr)
    return {0.0, dm, NormalState::broken};
  // softened: on the envelope at dm, on the secant below it
  const double f_dm = f_peak - p.kn / p.zeta * (dm - de);
  return {f_dm / dm * delta, dm, NormalState::softening};
}

inline double compaction_dissipation(double e_max, double kn, double d_init, const CompactionLaw& c)
{
  if (!(e_max > c.onset))
    return 0.0;
  // the envelope's integral over [0, e_max], piece by piece (trapezoids of
  // straight pieces: exact)
  auto area = [&](double a, double b) { return 0.5 * (compaction_envelope(a, c) + compaction_envelope(b, c)) * (b - a); };
  double integral = area(0.0, c.onset);
  integral += area(c.onset, std::min(e_max, c.lock));
  if (e_max > c.lock)
    integral += area(c.lock, e_max);
  const double f = compaction_envelope(e_max, c);
  return kn * d_init * d_init * (integral - 0.5 * f * f);
}

inline double malvar_ross_dif(double rate, double fc)
{
  constexpr double rate_s = 1e-6, fc0 = 10e6;
  if (!(rate > rate_s))
    return 1.0;
  const double delta = 1.0 / (1.0 + 8.0 * fc / fc0);
  const double ratio = rate / rate_s;
  if (rate <= 1.0)
    return std::pow(ratio, delta);
  const double beta = std::pow(10.0, 6.0 * delta - 2.0);
  return beta * std::cbrt(ratio);
}

inline double softening_dissipation(double delta_max, const LinkLaw& p)
{
  const double f_peak = p.s_int * p.tensile;
  const double de = f_peak / p.kn;
  if (delta_max <= de)
    return 0.0;
  const double dr = (1.0 + p.zeta) * de;
  const double dm = std::min(delta_max, dr);
  const double f_dm = link_envelope(dm, p);
  const double work = 0.5 * f_peak * de + 0.5 * (f_peak + f_dm) * (dm - de);
  return work - 0.5 * f_dm * dm;
}

inline Vec3 rotate(const Vec3& th, const Vec3& v)
{
  double sa, ca;
  detail::rodrigues_factors(detail::dot(th, th), sa, ca);
  const Vec3 t = detail::cross(th, v);
  const Vec3 tt = detail::cross(th, t);
  return {v[0] + sa * t[0] + ca * tt[0], v[1] + sa * t[1] + ca * tt[1],
          v[2] + sa * t[2] + ca * tt[2]};
}

inline Mat3 rotation_minus_identity(const Vec3& th)
{
  // R - I = sa [th]x + ca (th th^T - |th|^2 I)
  const double a2 = detail::dot(th, th);
  double sa, ca;
  detail::rodrigues_factors(a2, sa, ca);
  const double d = -ca * a2;
  return {d + ca * th[0] * th[0],       ca * th[0] * th[1] - sa * th[2], ca * th[0] * th[2] + sa * th[1],
          ca * th[1] * th[0] + sa * th[2], d + ca * th[1] * th[1],       ca * th[1] * th[2] - sa * th[0],
          ca * th[2] * th[0] - sa * th[1], ca * th[2] * th[1] + sa * th[0], d + ca * th[2] * th[2]};
}

inline Mat3 rotation_matrix(const Vec3& th)
{
  Mat3 r = rotation_minus_identity(th);
  r[0] += 1.0;
  r[4] += 1.0;
  r[8] += 1.0;
  return r;
}

inline Vec3 shear_increment(const Vec3& n_old, const Vec3& n_new, const Mat3& ra, const Mat3& rb,
                            double d, double fa)
{
  const Vec3 ma = detail::mul(ra, n_old), mb = detail::mul(rb, n_old);
  const double fb = 1.0 - fa;
  const double pa = detail::dot(ma, n_new), pb = detail::dot(mb, n_new);
  Vec3 du;
  for (int k = 0; k < 3; ++k)
    du[k] = -d * (fa * (ma[k] - pa * n_new[k]) + fb * (mb[k] - pb * n_new[k]));
  return du;
}

inline Vec3 rotate_shear(const Vec3& fs, const Mat3& ra, const Mat3& rb, double fa,
                         const Vec3& n_new)
{
  const Vec3 a = detail::mul(ra, fs), b = detail::mul(rb, fs);
  const double fb = 1.0 - fa;
  Vec3 r{fa * a[0] + fb * b[0], fa * a[1] + fb * b[1], fa * a[2] + fb * b[2]};
  const double rn = detail::dot(r, n_new);
  for (int k = 0; k < 3; ++k)
    r[k] -= rn * n_new[k];
  return r;
}

inline StepRotation step_rotation(const Vec3& th)
{
  double sa, ca;
  detail::rodrigues_factors(detail::dot(th, th), sa, ca);
  return {{sa * th[0], sa * th[1], sa * th[2]}, ca / (sa * sa)};
}

inline Vec3 rotation_minus_identity_times(const StepRotation& q, const Vec3& v)
{
  const Vec3 c = detail::cross(q.u, v);
  const double uv = detail::dot(q.u, v), uu = detail::dot(q.u, q.u);
  return {c[0] + q.k * (q.u[0] * uv - uu * v[0]), c[1] + q.k * (q.u[1] * uv - uu * v[1]),
          c[2] + q.k * (q.u[2] * uv - uu * v[2])};
}

inline Mat3 rotation_minus_identity(const StepRotation& q)
{
  const Vec3& u = q.u;
  const double k = q.k, uu = detail::dot(u, u);
  return {k * (u[0] * u[0] - uu), k * u[0] * u[1] - u[2],  k * u[0] * u[2] + u[1],
          k * u[1] * u[0] + u[2], k * (u[1] * u[1] - uu),  k * u[1] * u[2] - u[0],
          k * u[2] * u[0] - u[1], k * u[2] * u[1] + u[0],  k * (u[2] * u[2] - uu)};
}

inline Vec3 trial_shear(const Vec3& fs_old, const Vec3& n_old, const Vec3& n_new, const Mat3& qa,
                        const StepRotation& qb, double fa, double ks_d)
{
  const Vec3 v{fs_old[0] + ks_d * n_old[0], fs_old[1] + ks_d * n_old[1],
               fs_old[2] + ks_d * n_old[2]};
  const Vec3 qva = detail::mul(qa, v), qvb = rotation_minus_identity_times(qb, v);
  const double fb = 1.0 - fa;
  Vec3 r;
  for (int k = 0; k < 3; ++k)
    r[k] = fs_old[k] + ks_d * (n_old[k] - n_new[k]) + (fa * qva[k] + fb * qvb[k]);
  const double rn = detail::dot(r, n_new);
  for (int k = 0; k < 3; ++k)
    r[k] -= rn * n_new[k];
  return r;
}

inline ShearForce link_shear_force(const Vec3& fs, const Vec3& du_s, double fn, const LinkLaw& p)
{
  return link_shear_cap({fs[0] - p.ks * du_s[0], fs[1] - p.ks * du_s[1], fs[2] - p.ks * du_s[2]},
                        fn, p);
}

inline ShearForce link_shear_cap(const Vec3& fs_trial, double fn, const LinkLaw& p)
{
  ShearForce out{fs_trial, false, 0.0};
  const double fc = -fn; // compression positive
  const double cap = std::max(p.s_int * p.cohesion + fc * p.tan_phi_i, 0.0);
  out.exceeded = detail::dot(out.fs, out.fs) > cap * cap;
  return out;
}

inline double contact_normal_force(double distance, double radius_sum, double kn)
{
  return distance < radius_sum ? -kn * (radius_sum - distance) : 0.0;
}

inline ShearForce contact_shear_force(const Vec3& fs, const Vec3& du_s, double fn, const LinkLaw& p)
{
  return contact_shear_cap({fs[0] - p.ks * du_s[0], fs[1] - p.ks * du_s[1], fs[2] - p.ks * du_s[2]},
                           fn, p, fs);
}

inline ShearForce contact_shear_cap(const Vec3& fs_trial, double fn, const LinkLaw& p, const Vec3& fs_prev)
{
  ShearForce out{fs_trial, false, 0.0};
  double cap = std::max(-fn, 0.0) * p.tan_phi_c;
  if (p.shear_limit > 0.0)
    cap = std::min(cap, p.s_int * p.shear_limit);
  const double mag2 = detail::dot(out.fs, out.fs);
  if (mag2 > cap * cap)
  {
    const double mag = std::sqrt(mag2);
    out.exceeded = true;
    const double scale = mag > 0.0 ? cap / mag : 0.0;
    for (auto& f : out.fs)
      f *= scale;
    // the mean force's work over the increment less the spring's gain
    double e = 0.0;
    for (int k = 0; k < 3; ++k)
      e += (fs_prev[k] + out.fs[k]) * (fs_trial[k] - out.fs[k]);
    out.slip_energy = 0.5 * e / p.ks;
  }
  return out;
}

inline Vec3 trial_rolling(const Vec3& m_old, const Vec3& n_new, const Mat3& qa, const StepRotation& qb,
                          double fa, const Vec3& dtheta, double kr)
{
  const Vec3 qva = detail::mul(qa, m_old), qvb = rotation_minus_identity_times(qb, m_old);
  const double fb = 1.0 - fa;
  Vec3 r;
  for (int k = 0; k < 3; ++k)
    r[k] = m_old[k] + (fa * qva[k] + fb * qvb[k]) - kr * dtheta[k];
  const double rn = detail::dot(r, n_new);
  for (int k = 0; k < 3; ++k)
    r[k] -= rn * n_new[k];
  return r;
}

inline ShearForce contact_rolling_cap(const Vec3& m_trial, double fn, double kr, double arm, const Vec3& m_prev)
{
  LinkLaw law{};
  law.ks = kr;
  law.tan_phi_c = arm;
  return contact_shear_cap(m_trial, fn, law, m_prev);
}

inline std::array<Vec3, 2> shear_torques(const Vec3& n, const Vec3& fs, double l_a, double l_b)
{
  const Vec3 nxf = detail::cross(n, fs);
  return {Vec3{-l_a * nxf[0], -l_a * nxf[1], -l_a * nxf[2]},
          Vec3{-l_b * nxf[0], -l_b * nxf[1], -l_b * nxf[2]}};
}

} // namespace dembridge::dem
