#!/usr/bin/python3
"""The target's resistance to a penetrating projectile, from impact runs.

Cavity-expansion models of penetration (Forrestal et al.) write the axial
force on a rigid projectile in the tunnelling phase as

    F = A (R + N rho v^2),   A = pi d^2 / 4,

with R the target's static resistance, rho its density and N the nose
factor: for an ogive of calibre-radius-head psi, N* = (8 psi - 1) / (24 psi^2)
(0.106 at CRH 3), and about 1 for a flat nose. This script takes the
`history.csv` of one or more `impact` runs, keeps the samples where the tip
lies between --from and --to [m] deep (clear of the front crater and the rear
scab), takes F = -dE/dx from the projectile's kinetic energy against its depth,
and fits R and N by least squares over every run together (the runs at
different striking speeds are what separate R from N).

    /usr/bin/python3 scripts/resistance.py out/h1058 out/h749 out/h606 \
        --diameter 0.0254 --density 2400 --crh 3 --from 0.07 --to 0.10

prints R, N, the nose's N* and each run's fitted and measured mean force.
With --bands W [m] it also prints, for each run, the mean resistance F / A
over successive depth bands W wide within the window (the drop of the
projectile's kinetic energy between the band's first and last samples over
their depth apart) and the band's rms speed: how the resistance follows the
speed and the depth, whatever the two-term form.
"""
import argparse
import csv
import math
import sys
from pathlib import Path

import numpy as np


def read_history(folder):
    """depth [m], speed [m/s] and kinetic energy [J] of a run's history.csv."""
    rows = list(csv.DictReader(open(Path(folder) / "history.csv")))
    return (np.array([float(r[k]) for r in rows]) for k in ("depth_m", "speed_m_s", "projectile_kinetic_j"))


def window(x, v, e, lo, hi):
    """(speed, axial force) where the tip is between lo and hi deep; the
    force is -dE/dx, central differences over the samples."""
    f = -np.gradient(e, x)
    keep = np.nonzero((x >= lo) & (x <= hi))[0]
    keep = keep[(keep > 0) & (keep < len(x) - 1) & np.isfinite(f[keep])]
    return v[keep], f[keep]


def bands(x, v, e, lo, hi, width, area):
    """[(band start, band end, rms speed, mean resistance [Pa])] over the
    bands [lo + k width, lo + (k + 1) width) within [lo, hi] that hold at
    least 3 samples: the energy drop between the band's first and last
    samples over their depth apart, per unit of the shank's area."""
    out = []
    start = lo
    while start < hi - 1e-12:
        end = min(start + width, hi)
        keep = np.nonzero((x >= start) & (x < end))[0]
        if len(keep) >= 3 and x[keep[-1]] > x[keep[0]]:
            f = (e[keep[0]] - e[keep[-1]]) / (x[keep[-1]] - x[keep[0]])
            out.append((start, end, float(np.sqrt(np.mean(v[keep] ** 2))), f / area))
        start = end
    return out


def fit(data, area, density):
    """R [Pa] and N of F = A (R + N rho v^2), least squares over the
    (speed, force) arrays of every run together."""
    v2 = np.concatenate([v ** 2 for v, _ in data])
    p = np.concatenate([f for _, f in data]) / area
    if np.ptp(v2) < 0.05 * np.mean(v2):
        print("warning: the speeds barely differ across the samples; R and N are ill separated: give runs at "
              "other striking speeds", file=sys.stderr)
    (r, n), *_ = np.linalg.lstsq(np.column_stack([np.ones_like(v2), density * v2]), p, rcond=None)
    return r, n


def main():
    a = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("runs", nargs="+", help="impact output folders (each with history.csv)")
    a.add_argument("--diameter", type=float, required=True, help="projectile diameter [m]")
    a.add_argument("--density", type=float, required=True, help="target density [kg/m^3]")
    a.add_argument("--crh", type=float, default=0.0, help="ogive calibre-radius-head, for N* (0: not printed)")
    a.add_argument("--from", dest="lo", type=float, required=True, help="window start: tip depth [m]")
    a.add_argument("--to", dest="hi", type=float, required=True, help="window end: tip depth [m]")
    a.add_argument("--bands", type=float, default=0.0,
                   help="also print each run's mean resistance over depth bands this wide [m] (0: not)")
    o = a.parse_args()
    for name, value in (("--diameter", o.diameter), ("--density", o.density)):
        if not value > 0.0:
            sys.exit(f"{name} = {value}: must be > 0")
    if not 0.0 <= o.lo < o.hi:
        sys.exit(f"--from {o.lo}, --to {o.hi}: need 0 <= from < to")
    if not 0.0 <= o.bands:
        sys.exit(f"--bands {o.bands}: must be >= 0 (0: no bands)")
    area = math.pi * o.diameter ** 2 / 4.0
    data = []
    for run in o.runs:
        v, f = window(*read_history(run), o.lo, o.hi)
        if len(v) < 3:
            sys.exit(f"{run}: fewer than 3 samples with the tip between {o.lo} and {o.hi} m deep")
        data.append((v, f))
    if len(o.runs) == 1:
        print("warning: one run: R and N are separated only by its slowing down within the window; give a "
              "second run at another striking speed", file=sys.stderr)
    r, n = fit(data, area, o.density)
    print(f"window: tip {o.lo * 1e3:.0f}-{o.hi * 1e3:.0f} mm deep, {sum(len(v) for v, _ in data)} samples "
          f"from {len(o.runs)} runs")
    print(f"R (static resistance) = {r / 1e6:.0f} MPa")
    print(f"N (nose factor)       = {n:.3f}")
    if o.crh > 0.0:
        psi = o.crh
        print(f"N* of a CRH {psi:g} ogive = {(8.0 * psi - 1.0) / (24.0 * psi * psi):.3f}; a flat nose: about 1")
    for run, (v, f) in zip(o.runs, data):
        model = area * (r + n * o.density * np.mean(v ** 2))
        print(f"  {run}: speed {v.max():.0f}-{v.min():.0f} m/s, mean force {np.mean(f) / 1e3:.0f} kN "
              f"(fit {model / 1e3:.0f} kN)")
    if o.bands > 0.0:
        print(f"mean resistance over {o.bands * 1e3:g} mm bands (rms speed; the fit's R + N rho v^2):")
        for run in o.runs:
            for b0, b1, vb, pb in bands(*read_history(run), o.lo, o.hi, o.bands, area):
                print(f"  {run}: {b0 * 1e3:.0f}-{b1 * 1e3:.0f} mm: {vb:.0f} m/s, {pb / 1e6:.0f} MPa "
                      f"({(r + n * o.density * vb * vb) / 1e6:.0f} MPa)")

if __name__ == "__main__":
    main()
