#!/usr/bin/python3
"""Plots triaxial tests of dem_sample: the deviator against the axial strain.

Usage: plot_triaxial.py OUT.png DIR [DIR ...] [--fc PA]

Each DIR is the --output of a `dem_sample --test triaxial` run. One curve per
run: the deviator q = |axial stress| - lateral stress [MPa] against the
platen strain [%], labelled by the run's confinement (the largest lateral
stress of its stress_strain.csv). With --fc (the concrete's uniaxial
compressive strength, Pa) each curve's confinement also gets, as a short
dashed line at its height, the peak deviator of the Holmquist-Johnson-Cook
intact failure surface q = f_c (0.79 + 1.6 (p / f_c)^0.61), p = sigma_3 +
q / 3 (the constants published for a 48 MPa concrete; a reference at high
confinement: at sigma_3 = 0 it gives about 2 f_c).
"""
import argparse
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_run(folder):
    """(platen strains, deviators [Pa], confinement [Pa]) of a triaxial run."""
    path = os.path.join(folder, "stress_strain.csv")
    if not os.path.exists(path):
        sys.exit(f"{path}: not found (is {folder} the --output of a dem_sample run?)")
    eps, q, lateral = [], [], []
    with open(path) as f:
        rows = csv.DictReader(f)
        if "lateral_stress_pa" not in (rows.fieldnames or []):
            sys.exit(f"{path}: no lateral_stress_pa column (not a triaxial run of this version)")
        for row in rows:
            s3 = float(row["lateral_stress_pa"])
            eps.append(abs(float(row["strain"])))
            q.append(abs(float(row["stress_pa"])) - s3)
            lateral.append(s3)
    if not lateral or max(lateral) <= 0.0:
        sys.exit(f"{path}: the lateral stress is 0 throughout: not a triaxial run")
    return eps, q, max(lateral)


def hjc_intact(s3, fc):
    """Peak deviator [Pa] of HJC's intact surface at confinement s3 [Pa]:
    the fixed point of q = fc (A + B ((s3 + q / 3) / fc)^N), a contraction
    (its slope in q is below 0.2 for these constants)."""
    q = fc
    for _ in range(200):
        q = fc * (0.79 + 1.6 * ((s3 + q / 3.0) / fc) ** 0.61)
    return q


def main(argv):
    ap = argparse.ArgumentParser(description="dem_sample triaxial tests: deviator against axial strain")
    ap.add_argument("png", help="output PNG file")
    ap.add_argument("runs", nargs="+", help="dem_sample --output folders of triaxial runs")
    ap.add_argument("--fc", type=float, default=0.0, help="uniaxial compressive strength [Pa] for HJC's peaks (0: none)")
    a = ap.parse_args(argv)
    if not a.fc >= 0.0:
        sys.exit(f"--fc {a.fc}: must be >= 0 (0: no reference)")
    runs = sorted((read_run(d) for d in a.runs), key=lambda r: r[2])
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for eps, q, s3 in runs:
        line, = ax.plot([100 * e for e in eps], [v / 1e6 for v in q], lw=1.4,
                        label=f"$\\sigma_3$ = {s3 / 1e6:g} MPa")
        if a.fc > 0.0:
            ax.hlines(hjc_intact(s3, a.fc) / 1e6, 0, 100 * max(eps) * 0.15, colors=line.get_color(),
                      linestyles="dashed", lw=1.2)
    ax.set_xlabel("axial strain [%]")
    ax.set_ylabel("deviator $\\sigma_1 - \\sigma_3$ [MPa]")
    title = "Triaxial compression, DE sample"
    if a.fc > 0.0:
        title += "\n(dashed: HJC intact surface's peak at each $\\sigma_3$)"
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.png, dpi=120)
    print(f"wrote {a.png}")


if __name__ == "__main__":
    main(sys.argv[1:])
