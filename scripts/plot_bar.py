#!/usr/bin/python3
"""Plots of `bar --compare DIR`: the probe histories of the three models
(like the paper's Figures 12 and 13) and the static shapes against beam
theory (Figures 9 and 10). Writes DIR/dynamic_<load>.png, DIR/static_<load>.png.
Usage: /usr/bin/python3 scripts/plot_bar.py DIR"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) if k != "source" else r[k] for r in rows] for k in rows[0]}


def main(root):
    styles = {"fe": ("FE (shells)", "tab:blue", "-"), "coupled": ("coupled", "tab:red", "--"),
              "de": ("DE", "tab:green", ":")}
    for load in ("tension", "bending"):
        fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
        for model, (label, color, ls) in styles.items():
            path = os.path.join(root, f"{model}_{load}_dynamic", "history.csv")
            if not os.path.exists(path):
                continue
            h = read(path)
            axes[0].plot(h["t_s"], h["probe_0_75_m"], ls, color=color, label=label)
            axes[1].plot(h["t_s"], h["probe_0_4351_m"], ls, color=color, label=label)
        comp = "axial" if load == "tension" else "transverse"
        axes[0].set_ylabel(f"{comp} displacement [m]\nat x = 0.75 m")
        axes[1].set_ylabel(f"{comp} displacement [m]\nat x = 0.4351 m (FE: 0.45)")
        axes[1].set_xlabel("time [s]")
        axes[0].legend()
        axes[0].set_title(f"Bar, dynamic {load}: end displacement ramped, then released")
        fig.tight_layout()
        fig.savefig(os.path.join(root, f"dynamic_{load}.png"), dpi=120)
        plt.close(fig)

        fig, ax = plt.subplots(figsize=(8, 4))
        theory_done = False
        for model, (label, color, ls) in styles.items():
            path = os.path.join(root, f"{model}_{load}_static", "shape.csv")
            if not os.path.exists(path):
                continue
            s = read(path)
            pts = sorted(zip(s["x_m"], s["displacement_m"], s["beam_theory_m"]))
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o", ms=3, color=color, label=label)
            if not theory_done:
                ax.plot([p[0] for p in pts], [p[2] for p in pts], "k-", lw=1, label="beam theory")
                theory_done = True
        ax.set_xlabel("x [m]")
        ax.set_ylabel(("axial" if load == "tension" else "transverse") + " displacement [m]")
        ax.set_title(f"Bar, static {load}: final shape")
        ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(root, f"static_{load}.png"), dpi=120)
        plt.close(fig)
    print(f"plots written to {root}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
