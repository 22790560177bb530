#include "dembridge/dem/law.h"

#include <algorithm>
#include <cmath>

namespace dembridge::dem
{
namespace
{
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b)
{
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
/// Rodrigues rotation of v about unit axis k by the angle with cos c, sin s.
inline Vec3 rotate(const Vec3& v, const Vec3& k, double c, double s)
{
  const Vec3 kxv = cross(k, v);
  const double kv = dot(k, v);
  Vec3 r;
  for (int i = 0; i < 3; ++i)
    r[i] = v[i] * c + kxv[i] * s + k[i] * kv * (1.0 - c);
  return r;
}
} // namespace

double link_envelope(double d, const LinkLaw& p)
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

NormalForce link_normal_force(double delta, double delta_max, const LinkLaw& p)
{
  const double f_peak = p.s_int * p.tensile;
  const double de = f_peak / p.kn;
  const double dr = (1.0 + p.zeta) * de;
  if (delta <= 0.0)
    return {p.kn * delta, delta_max, delta_max > de ? NormalState::softening : NormalState::elastic};
  if (delta >= dr || delta_max >= dr)
    return {0.0, std::max(delta, delta_max), NormalState::broken};
  const double dm = std::max(delta, delta_max);
  if (dm <= de)
    return {p.kn * delta, dm, NormalState::elastic};
  // softened: on the envelope at dm, on the secant below it
  const double f_dm = f_peak - p.kn / p.zeta * (dm - de);
  return {f_dm / dm * delta, dm, NormalState::softening};
}

double softening_dissipation(double delta_max, const LinkLaw& p)
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

Vec3 rotate_shear(const Vec3& fs, const Vec3& n_old, const Vec3& n_new, double twist)
{
  Vec3 r = fs;
  Vec3 axis = cross(n_old, n_new);
  const double s = norm(axis);
  if (s > 1e-300)
  {
    for (auto& a : axis)
      a /= s;
    const double c = dot(n_old, n_new);
    r = rotate(r, axis, c, s);
  }
  if (twist != 0.0)
    r = rotate(r, n_new, std::cos(twist), std::sin(twist));
  return r;
}

namespace
{
using Quat = std::array<double, 4>;
inline Quat qmul(const Quat& a, const Quat& b)
{
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}
inline Quat from_rotvec(const Vec3& v)
{
  const double a = norm(v);
  if (a < 1e-30)
    return {1.0, 0.5 * v[0], 0.5 * v[1], 0.5 * v[2]};
  const double s = std::sin(0.5 * a) / a;
  return {std::cos(0.5 * a), s * v[0], s * v[1], s * v[2]};
}
inline Vec3 to_rotvec(const Quat& q)
{
  const double s = std::sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (s < 1e-30)
    return {2.0 * q[1], 2.0 * q[2], 2.0 * q[3]};
  const double a = 2.0 * std::atan2(s, q[0]) / s;
  return {a * q[1], a * q[2], a * q[3]};
}
/// Minimal rotation taking unit a to unit b (half-angle form).
inline Quat between(const Vec3& a, const Vec3& b)
{
  const Vec3 c = cross(a, b);
  Quat q{1.0 + dot(a, b), c[0], c[1], c[2]};
  const double l = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (l < 1e-150) // antiparallel: any perpendicular axis
    return {0.0, 1.0, 0.0, 0.0};
  for (auto& x : q)
    x /= l;
  return q;
}
} // namespace

Vec3 rotate(const std::array<double, 4>& q, const Vec3& v)
{
  // v' = v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z)
  const Vec3 u{q[1], q[2], q[3]};
  const Vec3 t = cross(u, v);
  const Vec3 t2 = cross(u, t);
  return {v[0] + 2.0 * (q[0] * t[0] + t2[0]), v[1] + 2.0 * (q[0] * t[1] + t2[1]),
          v[2] + 2.0 * (q[0] * t[2] + t2[2])};
}

ShearKinematics shear_kinematics(const Vec3& n_old, const Vec3& n_new, const Vec3& dtheta_a,
                                 const Vec3& dtheta_b, double d, double fa)
{
  const Quat qm = between(n_old, n_new);
  const Quat qmc{qm[0], -qm[1], -qm[2], -qm[3]};
  const Vec3 ra = to_rotvec(qmul(qmc, from_rotvec(dtheta_a)));
  const Vec3 rb = to_rotvec(qmul(qmc, from_rotvec(dtheta_b)));
  const double ta = dot(ra, n_old), tb = dot(rb, n_old);
  Vec3 tilt;
  for (int k = 0; k < 3; ++k)
    tilt[k] = fa * (ra[k] - ta * n_old[k]) + (1.0 - fa) * (rb[k] - tb * n_old[k]);
  const Vec3 c = cross(tilt, n_old);
  const Vec3 du_old{-d * c[0], -d * c[1], -d * c[2]};
  ShearKinematics out;
  out.du_s = rotate(qm, du_old);
  // project away round-off normal components
  const double dn = dot(out.du_s, n_new);
  for (int k = 0; k < 3; ++k)
    out.du_s[k] -= dn * n_new[k];
  const double tw = fa * ta + (1.0 - fa) * tb;
  const Quat qt = from_rotvec({tw * n_new[0], tw * n_new[1], tw * n_new[2]});
  out.q = qmul(qt, qm);
  return out;
}

ShearForce link_shear_force(const Vec3& fs, const Vec3& du_s, double fn, const LinkLaw& p)
{
  ShearForce out{{fs[0] - p.ks * du_s[0], fs[1] - p.ks * du_s[1], fs[2] - p.ks * du_s[2]},
                 false, 0.0};
  const double fc = -fn; // compression positive
  const double cap = p.s_int * p.cohesion + fc * p.tan_phi_i;
  out.exceeded = norm(out.fs) > std::max(cap, 0.0);
  return out;
}

double contact_normal_force(double distance, double radius_sum, double kn)
{
  return distance < radius_sum ? -kn * (radius_sum - distance) : 0.0;
}

ShearForce contact_shear_force(const Vec3& fs, const Vec3& du_s, double fn, const LinkLaw& p)
{
  ShearForce out{{fs[0] - p.ks * du_s[0], fs[1] - p.ks * du_s[1], fs[2] - p.ks * du_s[2]},
                 false, 0.0};
  const double cap = std::max(-fn, 0.0) * p.tan_phi_c;
  const double mag = norm(out.fs);
  if (mag > cap)
  {
    out.exceeded = true;
    const double scale = mag > 0.0 ? cap / mag : 0.0;
    // slip = (mag - cap) / ks against the capped force
    out.slip_energy = cap * (mag - cap) / p.ks;
    for (auto& f : out.fs)
      f *= scale;
  }
  return out;
}

std::array<Vec3, 2> shear_torques(const Vec3& n, const Vec3& fs, double l_a, double l_b)
{
  const Vec3 nxf = cross(n, fs);
  return {Vec3{-l_a * nxf[0], -l_a * nxf[1], -l_a * nxf[2]},
          Vec3{-l_b * nxf[0], -l_b * nxf[1], -l_b * nxf[2]}};
}

} // namespace dembridge::dem
