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

Vec3 rotate(const Vec3& th, const Vec3& v)
{
  const double a2 = dot(th, th);
  double sa, ca; // sin(a)/a and (1 - cos a)/a^2
  if (a2 < 1e-4)
  {
    // series: next terms below 1e-19 for a < 1e-2
    sa = 1.0 - a2 / 6.0 + a2 * a2 / 120.0 - a2 * a2 * a2 / 5040.0;
    ca = 0.5 - a2 / 24.0 + a2 * a2 / 720.0 - a2 * a2 * a2 / 40320.0;
  }
  else
  {
    const double a = std::sqrt(a2);
    sa = std::sin(a) / a;
    ca = (1.0 - std::cos(a)) / a2;
  }
  const Vec3 t = cross(th, v);
  const Vec3 tt = cross(th, t);
  return {v[0] + sa * t[0] + ca * tt[0], v[1] + sa * t[1] + ca * tt[1],
          v[2] + sa * t[2] + ca * tt[2]};
}

Mat3 rotation_matrix(const Vec3& th)
{
  const Vec3 ex = rotate(th, {1.0, 0.0, 0.0}), ey = rotate(th, {0.0, 1.0, 0.0}),
             ez = rotate(th, {0.0, 0.0, 1.0});
  return {ex[0], ey[0], ez[0], ex[1], ey[1], ez[1], ex[2], ey[2], ez[2]};
}

namespace
{
inline Vec3 mul(const Mat3& r, const Vec3& v)
{
  return {r[0] * v[0] + r[1] * v[1] + r[2] * v[2], r[3] * v[0] + r[4] * v[1] + r[5] * v[2],
          r[6] * v[0] + r[7] * v[1] + r[8] * v[2]};
}
} // namespace

Vec3 shear_increment(const Vec3& n_old, const Vec3& n_new, const Mat3& ra, const Mat3& rb,
                     double d, double fa)
{
  const Vec3 ma = mul(ra, n_old), mb = mul(rb, n_old);
  const double fb = 1.0 - fa;
  const double pa = dot(ma, n_new), pb = dot(mb, n_new);
  Vec3 du;
  for (int k = 0; k < 3; ++k)
    du[k] = -d * (fa * (ma[k] - pa * n_new[k]) + fb * (mb[k] - pb * n_new[k]));
  return du;
}

Vec3 rotate_shear(const Vec3& fs, const Mat3& ra, const Mat3& rb, double fa, const Vec3& n_new)
{
  const Vec3 a = mul(ra, fs), b = mul(rb, fs);
  const double fb = 1.0 - fa;
  Vec3 r{fa * a[0] + fb * b[0], fa * a[1] + fb * b[1], fa * a[2] + fb * b[2]};
  const double rn = dot(r, n_new);
  for (int k = 0; k < 3; ++k)
    r[k] -= rn * n_new[k];
  return r;
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
