#!/usr/bin/python3
"""Plots the stress-strain curves of a calibration (or of dem_sample runs).

Usage: plot_stress_strain.py DIR
Reads DIR/tension/stress_strain.csv and DIR/compression/stress_strain.csv
(whichever exist) and writes DIR/tension.png and DIR/compression.png, like
the paper's Figures 3 and 4 (stress in MPa against strain).
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def curve(path):
    eps, sig = [], []
    with open(path) as f:
        for row in csv.DictReader(f):
            eps.append(abs(float(row["strain"])))
            sig.append(abs(float(row["stress_pa"])) / 1e6)
    return eps, sig


def main(folder):
    made = 0
    for test in ("tension", "compression"):
        path = os.path.join(folder, test, "stress_strain.csv")
        if not os.path.exists(path):
            continue
        eps, sig = curve(path)
        fig, ax = plt.subplots(figsize=(5, 3.6))
        ax.plot([e * 1e3 for e in eps], sig, "-", lw=1.5, label="DE sample")
        ax.set_xlabel("strain [10$^{-3}$]")
        ax.set_ylabel(("tensile" if test == "tension" else "compressive") + " stress [MPa]")
        ax.set_title("Uniaxial " + test)
        ax.grid(alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(folder, test + ".png"), dpi=120)
        plt.close(fig)
        made += 1
    if made == 0:
        sys.exit("no stress_strain.csv under " + folder)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
