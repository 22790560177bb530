#!/usr/bin/python3
"""The history of an impact run: the projectile's speed along its path, tip
depth and contact force against time, with the slab's faces marked; or,
under a prescribed pulse (any model), the load and the deflection at each
of shells.deflection_points_m.
Writes DIR/history.png from DIR/history.csv and DIR/scenario.json.
Usage: /usr/bin/python3 scripts/plot_impact.py DIR"""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(root):
    with open(os.path.join(root, "history.csv")) as f:
        rows = list(csv.DictReader(f))
    col = {k: [float(r[k]) for r in rows] for k in rows[0]}
    with open(os.path.join(root, "scenario.json")) as f:
        sc = json.load(f)
    t = [1e3 * v for v in col["time_s"]]
    if "load_n" in col:
        return pulse(root, sc, t, col)
    fig, ax = plt.subplots(3, 1, figsize=(7, 8), sharex=True)
    ax[0].plot(t, col["path_velocity_m_s"], color="tab:red")
    ax[0].set_ylabel("velocity along the path [m/s]")
    ax[0].set_title(f"{sc['scenario.name']}: {sc['projectile.velocity_m_s']:g} m/s, "
                    f"{sc['target.thickness_m'] * 1e3:g} mm slab")
    ax[1].plot(t, [1e3 * v for v in col["depth_m"]], color="tab:blue")
    thick = 1e3 * sc["target.thickness_m"]
    ax[1].axhline(0.0, color="grey", lw=0.8, ls="--")
    ax[1].axhline(thick, color="grey", lw=0.8, ls="--")
    ax[1].text(t[0], thick, " rear face", va="bottom", color="grey")
    ax[1].set_ylabel("tip depth [mm]")
    ax[2].plot(t, [1e-3 * v for v in col["contact_force_n"]], color="tab:green")
    ax[2].set_ylabel("contact force [kN]")
    ax[2].set_xlabel("time [ms]")
    for a in ax:
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(root, "history.png"), dpi=110)


def pulse(root, sc, t, col):
    """The load and the deflections of a run under a pulse."""
    fig, ax = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    ax[0].plot(t, [1e-3 * v for v in col["load_n"]], color="tab:green")
    ax[0].set_ylabel("load [kN]")
    ax[0].set_title(f"{sc['scenario.name']} ({sc['shells.model']}): a {sc['pulse.peak_force_n'] * 1e-3:g} kN pulse "
                    f"over {sc['pulse.duration_s'] * 1e3:g} ms")
    points = sc["shells.deflection_points_m"]
    for q, p in enumerate(points):
        ax[1].plot(t, [1e6 * v for v in col[f"deflection_{q}_m"]], label=f"({p[0]:g}, {p[1]:g}) m")
    if points:
        ax[1].legend()
    axis = "u_x" if sc["pulse.direction"] == "x" else "u_z"
    ax[1].set_ylabel(f"{axis} at the points [um]")
    ax[1].set_xlabel("time [ms]")
    for a in ax:
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(root, "history.png"), dpi=110)


if __name__ == "__main__":
    main(sys.argv[1])
