#!/usr/bin/python3
"""Plots the stress-strain curves of a calibration (or of dem_sample runs).

Usage: plot_stress_strain.py DIR
Reads DIR/tension/stress_strain.csv, DIR/compression/stress_strain.csv and
DIR/fracture/stress_strain.csv (whichever exist) and writes DIR/tension.png,
DIR/compression.png (like the paper's Figures 3 and 4: stress in MPa against
strain) and DIR/fracture.png (the notched test to separation: stress on the
ligament).
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
    titles = {"tension": "Uniaxial tension", "compression": "Uniaxial compression",
              "fracture": "Notched tension to separation"}
    for test in ("tension", "compression", "fracture"):
        path = os.path.join(folder, test, "stress_strain.csv")
        if not os.path.exists(path):
            continue
        eps, sig = curve(path)
        fig, ax = plt.subplots(figsize=(5, 3.6))
        ax.plot([e * 1e3 for e in eps], sig, "-", lw=1.5, label="DE sample")
        ax.set_xlabel("strain [10$^{-3}$]")
        ax.set_ylabel({"tension": "tensile stress [MPa]", "compression": "compressive stress [MPa]",
                       "fracture": "stress on the ligament [MPa]"}[test])
        ax.set_title(titles[test])
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
