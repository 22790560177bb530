#!/usr/bin/python3
"""A ballistic-limit study: an impact scenario at several striking speeds,
the residual velocities fitted with the Lambert-Jonas form
    V_r = a (V_s^p - V_bl^p)^(1/p)   for V_s > V_bl, 0 below,
and compared with measured values if given.

Runs build/bin/impact SCENARIO --set projectile.velocity_m_s=V (plus any
--set given here) for each V, into OUT/v<V>/, and writes:
- OUT/ballistic.csv: striking, residual, measured (if any) and the fit;
- OUT/ballistic.json: the fit (a, p, V_bl, rms) and every run's key figures;
- OUT/ballistic.png: residual against striking velocity, runs, fit and data.
A run already done (OUT/v<V>/summary.json complete) is not run again.

The fit: for each p in [1.5, 4] and V_bl below the lowest perforating speed
(and above the highest non-perforating one), a is the least-squares value
(closed form), capped at 1; the (p, V_bl) of least squares is kept. With
fewer than three perforations p is held at 2.

Usage: /usr/bin/python3 scripts/ballistic.py SCENARIO OUT V1 V2 ... [--set KEY=VALUE ...]
       [--measured VS:VR,VS:VR,...] [--impact build/bin/impact]
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys


def fit_lambert_jonas(runs):
    """runs: [(striking, residual)]; residual 0 for no perforation."""
    perf = [(v, r) for v, r in runs if r > 0.0]
    stopped = [v for v, r in runs if r <= 0.0]
    if not perf:
        return None
    lo = max(stopped) if stopped else 0.0
    hi = min(v for v, _ in perf)
    best = None
    ps = [1.5 + 0.05 * k for k in range(51)] if len(perf) >= 3 else [2.0]
    for p in ps:
        for k in range(400):
            vbl = lo + (hi - lo) * k / 400.0
            g = [(v ** p - vbl ** p) ** (1.0 / p) for v, _ in perf]
            den = sum(x * x for x in g)
            a = min(1.0, sum(x * r for x, (_, r) in zip(g, perf)) / den) if den > 0 else 1.0
            err = sum((a * x - r) ** 2 for x, (_, r) in zip(g, perf))
            if best is None or err < best[0]:
                best = (err, a, p, vbl)
    err, a, p, vbl = best
    return {"a": a, "p": p, "v_bl_m_s": vbl, "rms_m_s": math.sqrt(err / len(perf)),
            "v_bl_bounds_m_s": [lo, hi]}


def run_at(impact, scenario, out, v, sets):
    """Runs the scenario at striking speed v into OUT/v<V>/ unless a complete
    run is there already; returns its summary."""
    d = os.path.join(out, f"v{v:g}")
    summary = os.path.join(d, "summary.json")
    done = False
    if os.path.exists(summary):
        with open(summary) as f:
            done = json.load(f).get("completed", False)
    if not done:
        cmd = [impact, scenario, "--set", f"projectile.velocity_m_s={v}", "--plot", "0", "--output", d,
               "--summary", summary]
        for s in sets:
            cmd += ["--set", s]
        print("running:", " ".join(cmd), flush=True)
        with open(os.path.join(out, f"v{v:g}.log"), "w") as log:
            if subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT).returncode != 0:
                raise SystemExit(f"the run at {v} m/s failed: see {log.name}")
    with open(summary) as f:
        return json.load(f)


def residual(fit, v):
    if fit is None or v <= fit["v_bl_m_s"]:
        return 0.0
    return fit["a"] * (v ** fit["p"] - fit["v_bl_m_s"] ** fit["p"]) ** (1.0 / fit["p"])


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenario")
    ap.add_argument("out")
    ap.add_argument("velocities", type=float, nargs="+")
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--measured", default="")
    ap.add_argument("--impact", default=os.path.join(os.path.dirname(__file__), "..", "build", "bin", "impact"))
    args = ap.parse_args(argv)
    measured = {}
    for pair in filter(None, args.measured.split(",")):
        vs, vr = pair.split(":")
        measured[float(vs)] = float(vr)
    os.makedirs(args.out, exist_ok=True)
    runs, table = [], []
    for v in args.velocities:
        s = run_at(args.impact, args.scenario, args.out, v, args.set)
        runs.append((v, s["residual_velocity_m_s"] if s["perforated"] else 0.0))
        table.append({"striking_m_s": v, "residual_m_s": runs[-1][1], "perforated": s["perforated"],
                      "penetration_depth_m": s["penetration_depth_m"],
                      "front_crater_diameter_m": s["front_crater_diameter_m"],
                      "rear_scab_diameter_m": s["rear_scab_diameter_m"],
                      "imbalance_share": s["energy"]["imbalance_share"], "particles": s["particles"],
                      "wall_s": s["wall_s"]})
    fit = fit_lambert_jonas(runs)
    fit_measured = fit_lambert_jonas(sorted(measured.items())) if measured else None
    with open(os.path.join(args.out, "ballistic.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["striking_m_s", "residual_m_s", "fit_m_s", "measured_m_s", "difference_share"])
        for v, r in runs:
            m = measured.get(v)
            w.writerow([v, r, residual(fit, v), "" if m is None else m,
                        "" if not m else (r - m) / m])
    with open(os.path.join(args.out, "ballistic.json"), "w") as f:
        json.dump({"fit": fit, "fit_of_measured": fit_measured, "runs": table, "measured": measured}, f, indent=2)
    for row in table:
        m = measured.get(row["striking_m_s"])
        print(f"{row['striking_m_s']:8.1f} m/s -> {row['residual_m_s']:8.1f} m/s"
              + (f"   measured {m:6.1f} ({100 * (row['residual_m_s'] - m) / m:+.1f} %)" if m else ""))
    if fit:
        print(f"Lambert-Jonas: a {fit['a']:.3f}, p {fit['p']:.2f}, V_bl {fit['v_bl_m_s']:.1f} m/s "
              f"(rms {fit['rms_m_s']:.1f} m/s)")
    if fit_measured:
        print(f"  of the measured values: a {fit_measured['a']:.3f}, p {fit_measured['p']:.2f}, "
              f"V_bl {fit_measured['v_bl_m_s']:.1f} m/s")
    plot(args.out, runs, fit, measured)
    return 0


def plot(out, runs, fit, measured):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.5))
    top = max([v for v, _ in runs] + list(measured)) * 1.05
    if fit:
        xs = [fit["v_bl_m_s"] + (top - fit["v_bl_m_s"]) * k / 200 for k in range(201)]
        ax.plot(xs, [residual(fit, x) for x in xs], color="tab:red", lw=1,
                label=f"Lambert-Jonas fit, V_bl = {fit['v_bl_m_s']:.0f} m/s")
    ax.plot([v for v, _ in runs], [r for _, r in runs], "o", color="tab:red", label="dembridge")
    if measured:
        ax.plot(list(measured), list(measured.values()), "s", color="k", mfc="none", label="measured")
    ax.plot([0, top], [0, top], color="grey", lw=0.6, ls="--")
    ax.set_xlim(0, top)
    ax.set_ylim(0, top)
    ax.set_xlabel("striking velocity [m/s]")
    ax.set_ylabel("residual velocity [m/s]")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "ballistic.png"), dpi=110)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
