#!/usr/bin/python3
"""The validation scripts' own arithmetic (no simulation):
- scripts/penetration.py: Forrestal's and Li and Chen's depths for shot 14
  of Forrestal et al. 1994 (0.906 kg, 26.9 mm, CRH 2.0, 277 m/s into 35.2 MPa
  concrete of 2370 kg/m^3; measured 173 mm; Li and Chen's 2003 paper gives
  167 mm for its model) within 5 % of the measured depth, and the two
  formulas continuous where the crater phase ends;
- scripts/ballistic.py: the Lambert-Jonas fit recovers a, p and V_bl of
  residual velocities made from known values (a = 0.9, p = 2.12,
  V_bl = 333 m/s) to the fit's grid: p to 3 % (steps of 0.05), a to 2 %,
  V_bl to 1 %;
- scripts/resistance.py: R and N of F = A (R + N rho v^2) fitted to two
  projectile histories made from the closed-form solution of that force
  law (R = 500 MPa, N = 0.106; 0.5 kg, 25.4 mm, 1000 and 700 m/s, sampled
  every 0.1 mm) within 1 % (the central differences of the energy on that
  grid err by about 1e-5), and its --bands resistance over 10 mm bands
  of the 1000 m/s history within 1 % of R + N rho v^2 at the band's rms
  speed (the force varies by a few % across a band; the energy drop over
  the band is the force's mean, the rms speed's square its speed term's);
- scripts/penetration.py's off_path: a history whose tip moves along an
  oblique path (30 degrees, aimed off the origin) plus a known drift across
  it, in both directions across and largest before the end, gives that
  drift's final distance and its largest speed, to 1e-12;
- scripts/bar_packing.py: a bar along x and one huge sphere that fills the
  half-space z < -c: in each band of distance d from the axis the solid
  fraction is the mean of arccos(c / d) / pi over the band (points uniform
  in the cross-section, so weighted by d), within 5 standard errors of the
  points' count;
- scripts/damage_map.py: spheres damaged exactly where depth < 60 mm and
  distance from the path < 40 mm give shares 1 and 0 in the bands that
  split there, and none in an empty band.
Usage: check_scripts.py SOURCE_DIR"""
import math
import os
import sys

sys.path.insert(0, os.path.join(sys.argv[1], "scripts"))
import ballistic  # noqa: E402
import bar_packing  # noqa: E402
import damage_map  # noqa: E402
import numpy as np  # noqa: E402
import penetration  # noqa: E402
import resistance  # noqa: E402

problems = []
for name, f in (("Forrestal", penetration.forrestal), ("Li-Chen", penetration.li_chen)):
    x = f(0.906, 0.0269, 2.0, 2370.0, 35.2e6, 277.0)
    print(f"{name}: {1e3 * x:.1f} mm for shot 14 (measured 173 mm)")
    if abs(x / 0.173 - 1) > 0.05:
        problems.append(f"{name}: {x} m, not within 5 % of 0.173 m")
    # no jump where the tunnel phase begins: depths at nearby speeds differ little
    xs = [f(0.5, 0.0254, 3.0, 2400.0, 48e6, v) for v in range(50, 400, 5)]
    jumps = [b - a for a, b in zip(xs, xs[1:])]
    if min(jumps) <= 0 or max(jumps) > 3 * sorted(jumps)[len(jumps) // 2]:
        problems.append(f"{name}: depth against speed not smooth and increasing: steps {jumps}")
a, p, vbl = 0.9, 2.12, 333.0
runs = [(v, a * (v ** p - vbl ** p) ** (1 / p)) for v in (400.0, 500.0, 650.0, 800.0, 1000.0)] + [(300.0, 0.0)]
fit = ballistic.fit_lambert_jonas(runs)
print("fit of synthetic data:", fit)
for key, want, tol in (("a", a, 0.02), ("p", p, 0.03), ("v_bl_m_s", vbl, 0.01)):
    if abs(fit[key] / want - 1) > tol:
        problems.append(f"Lambert-Jonas fit: {key} {fit[key]} instead of {want}")
# m v dv/dx = -A (R + N rho v^2): v^2 = (V0^2 + R/(N rho)) exp(-2 A N rho x / m) - R/(N rho)
mass, area, rho, r_true, n_true = 0.5, math.pi * 0.0254 ** 2 / 4, 2400.0, 500e6, 0.106
x = np.arange(0.0, 0.15, 1e-4)
data = []
for v0 in (1000.0, 700.0):
    c = r_true / (n_true * rho)
    v = np.sqrt((v0 ** 2 + c) * np.exp(-2 * area * n_true * rho * x / mass) - c)
    data.append(resistance.window(x, v, 0.5 * mass * v ** 2, 0.05, 0.12))
r_fit, n_fit = resistance.fit(data, area, rho)
print(f"resistance fit of synthetic histories: R {r_fit / 1e6:.2f} MPa, N {n_fit:.4f}")
for key, got, want in (("R", r_fit, r_true), ("N", n_fit, n_true)):
    if abs(got / want - 1) > 0.01:
        problems.append(f"resistance fit: {key} {got} instead of {want}")
v0 = 1000.0
v = np.sqrt((v0 ** 2 + c) * np.exp(-2 * area * n_true * rho * x / mass) - c)
rows = resistance.bands(x, v, 0.5 * mass * v ** 2, 0.05, 0.12, 0.01, area)
if len(rows) != 7:
    problems.append(f"resistance bands: {len(rows)} bands of 10 mm over 50-120 mm instead of 7")
for b0, b1, vb, pb in rows:
    want = r_true + n_true * rho * vb * vb
    print(f"band {1e3 * b0:.0f}-{1e3 * b1:.0f} mm: {vb:.0f} m/s, {pb / 1e6:.1f} MPa (law {want / 1e6:.1f})")
    if abs(pb / want - 1) > 0.01:
        problems.append(f"resistance band {b0}-{b1}: {pb} Pa instead of {want}")
# off_path: the tip at (aim, 0) + s u + e1 w1 + e2 w2, the velocity 400 u + c1 w1
# + c2 w2, with w1 = (0, 1, 0) and w2 = (cos th, 0, sin th) across the path u;
# the drift peaks before the last row, so the final distance (2 mm) and the
# largest speed across (10 m/s) are each told apart from the other readings
import csv  # noqa: E402
import tempfile  # noqa: E402
th = math.radians(30.0)
u, w2, aim = (math.sin(th), 0.0, -math.cos(th)), (math.cos(th), 0.0, math.sin(th)), (0.01, -0.02)
with tempfile.TemporaryDirectory() as tmp:
    hist = os.path.join(tmp, "history.csv")
    with open(hist, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time_s", "tip_x_m", "tip_y_m", "tip_z_m", "velocity_x_m_s", "velocity_y_m_s", "velocity_z_m_s"])
        rows_ = ((0.0, 0.0, 0.0, 0.0, 0.0), (0.05, 0.003, 0.004, 6.0, 8.0), (0.1, 0.0012, 0.0016, -1.8, 2.4))
        for k, (s_, e1, e2, c1, c2) in enumerate(rows_):
            w.writerow([1e-4 * k] + [aim[0] + s_ * u[0] + e2 * w2[0], aim[1] + e1, s_ * u[2] + e2 * w2[2]]
                       + [400 * u[0] + c2 * w2[0], c1, 400 * u[2] + c2 * w2[2]])
    off, across = penetration.off_path(hist, aim, 30.0)
print(f"off_path of a synthetic history: {1e3 * off:.6f} mm off, {across:.6f} m/s across")
if abs(off - 0.002) > 1e-12 or abs(across - 10.0) > 1e-12:
    problems.append(f"off_path: {off} m and {across} m/s instead of 0.002 m and 10 m/s")
# bar_packing: the half-space z < -c filled by one huge sphere, a bar along x
c, big = 0.002, 1e4
rng = np.random.default_rng(3)
pts = np.column_stack([rng.uniform(-0.05, 0.05, 40000), rng.uniform(-0.01, 0.01, (40000, 2))])
dist = bar_packing.axis_distance(pts, np.array([[-1.0, 0.0, 0.0]]), np.array([[1.0, 0.0, 0.0]]))
inside = bar_packing.solid(pts, np.array([[0.0, 0.0, -c - big]]), np.array([big]))
for lo, hi, f, n in bar_packing.fractions(pts, inside, dist, np.array([0.0, 0.001, 0.003, 0.006, 0.01])):
    d = np.linspace(max(lo, c), hi, 2001)[1:]
    expected = np.trapz(d * np.arccos(np.minimum(c / d, 1.0)) / math.pi, d) / (0.5 * (hi * hi - lo * lo)) if hi > c else 0.0
    err = 5.0 * math.sqrt(max(expected * (1 - expected), 1.0 / max(n, 1)) / max(n, 1))
    print(f"bar_packing: {1e3 * lo:.0f}-{1e3 * hi:.0f} mm: {f:.4f} against {expected:.4f} ({n} points)")
    if n < 100 or not abs(f - expected) <= err:
        problems.append(f"bar_packing: band {lo}-{hi} m: {f} instead of {expected} (+-{err})")
# damage_map: damaged where depth < 60 mm and within 40 mm of the path;
# no sphere beyond 300 mm from it
depth = rng.uniform(0.0, 200.0, 20000)
dist = rng.uniform(0.0, 300.0, 20000)
damaged = (depth < 60.0) & (dist < 40.0)
shares = damage_map.band_shares(damaged, depth, dist, [0.0, 60.0, 200.0], [0.0, 40.0, 300.0, 400.0])
want = [[1.0, 0.0, None], [0.0, 0.0, None]]
print(f"damage_map: {shares} (expected {want})")
if shares != want:
    problems.append(f"damage_map: shares {shares} instead of {want}")
for q in problems:
    print(q)
sys.exit(1 if problems else 0)
