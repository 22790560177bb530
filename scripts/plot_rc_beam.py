#!/usr/bin/python3
"""The load against the midspan deflection of an rc_beam run, beside the
section theory's curves (smeared cracks, and Eurocode 2's tension
stiffening), with the cracking point and the first yield marked.

Usage: /usr/bin/python3 scripts/plot_rc_beam.py DIR
Reads DIR/load_deflection.csv, DIR/theory_curve.csv and DIR/summary.json;
writes DIR/load_deflection.png.
"""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def columns(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def main(root):
    run = columns(os.path.join(root, "load_deflection.csv"))
    theory = columns(os.path.join(root, "theory_curve.csv"))
    with open(os.path.join(root, "summary.json")) as f:
        s = json.load(f)
    mm = lambda v: [1e3 * x for x in v]  # noqa: E731
    kn = lambda v: [1e-3 * x for x in v]  # noqa: E731
    fig, ax = plt.subplots(figsize=(7, 4.8))
    ax.plot(mm(run["deflection_m"]), kn(run["load_n"]), color="tab:blue", lw=0.7, label="DE beam")
    ax.plot(mm(theory["deflection_m"]), kn(theory["load_n"]), color="k", ls="--", label="section theory")
    ax.plot(mm(theory["deflection_tension_stiffening_m"]), kn(theory["load_n"]), color="grey", ls=":",
            label="with tension stiffening (EC2)")
    t = s["theory"]
    d_cr = t["cracking_load_n"] / s["initial_stiffness_theory_n_m"]
    ax.plot(1e3 * d_cr, 1e-3 * t["cracking_load_n"], "o", mfc="none", color="k", label="theory: cracking")
    if s.get("cracking_load_n") is not None:
        ax.plot(1e3 * s["cracking_deflection_m"], 1e-3 * s["cracking_load_n"], "o", color="tab:red",
                label=f"cracking ({s['cracking_read_at']})")
    if s.get("yield_load_n") is not None:
        ax.plot(1e3 * s["yield_deflection_m"], 1e-3 * s["yield_load_n"], "s", color="tab:green",
                label="bars' first yield")
    ax.plot(1e3 * theory["deflection_m"][-1], 1e-3 * theory["load_n"][-1], "s", mfc="none", color="k",
            label="theory: first yield")
    ax.set_xlabel("midspan deflection [mm]")
    ax.set_ylabel("load [kN]")
    ax.set_title(f"rc_beam: {s['particles']} spheres, {s['bar_elements']} bar elements")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(root, "load_deflection.png"), dpi=110)


if __name__ == "__main__":
    main(sys.argv[1])
