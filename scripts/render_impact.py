#!/usr/bin/python3
"""Renders an impact run as a cut through the slab along the projectile's
path (the x-z plane, y = 0) at three moments: the spheres whose centre lies
within one mean radius of the plane, drawn as discs coloured by their damage
(broken / initial links), and the projectile's outline.

Reads DIR/particles.h5 and DIR/summary.json of `build/bin/impact ...
--output DIR --summary DIR/summary.json`. The three frames are the first
one after a quarter and after half of the run, and the last.

Writes OUT.png and, beside it, OUT.json: the figures the picture shows
(scenario, spheres, striking and residual velocity, outcome).

Usage: /usr/bin/python3 scripts/render_impact.py DIR OUT.png
"""
import json
import sys
from pathlib import Path

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PatchCollection  # noqa: E402
from matplotlib.patches import Circle, Polygon  # noqa: E402


def hull(points):
    """Convex hull of 2D points (monotone chain), counter-clockwise."""
    pts = sorted(set(points))
    if len(pts) < 3:
        return pts

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def write_figures(summary, out_png):
    """The figures the picture shows, beside it as OUT.json
    (tests/check_picture.py compares them with a fresh run and with
    README.md's caption)."""
    figures = {k: summary[k] for k in ("scenario", "particles", "striking_velocity_m_s", "outcome")}
    figures["residual_velocity_m_s"] = round(summary["residual_velocity_m_s"])
    Path(out_png).with_suffix(".json").write_text(json.dumps(figures, indent=2) + "\n")


def main(run_dir, out_png):
    run = Path(run_dir)
    summary = json.loads((run / "summary.json").read_text())
    with h5py.File(run / "particles.h5", "r") as f:
        frames = sorted((k for k in f if k.startswith("frame_")), key=lambda k: int(k.split("_")[1]))
        picks = [frames[len(frames) // 4], frames[len(frames) // 2], frames[-1]]
        xdmf = (run / "particles.xdmf").read_text()
        times = [float(t.split('"')[1]) for t in xdmf.split("<Time Value=")[1:]]
        n_frames = len(frames)
        data = []
        for k in picks:
            g = f[k]
            data.append((g["position"][()], g["radius"][()], g["damage"][()], g["projectile_position"][()],
                         times[int(k.split("_")[1]) % n_frames]))
    r_mean = float(summary["mean_radius_m"])
    fig, axes = plt.subplots(1, 3, figsize=(12, 4.2), sharey=True)
    for ax, (x, r, damage, proj, t) in zip(axes, data):
        keep = abs(x[:, 1]) < r_mean
        discs = [Circle((1e3 * p[0], 1e3 * p[2]), 1e3 * q) for p, q in zip(x[keep], r[keep])]
        pc = PatchCollection(discs, cmap="inferno_r", edgecolor="none")
        pc.set_array(damage[keep])
        pc.set_clim(0.0, 1.0)
        ax.add_collection(pc)
        outline = hull([(1e3 * p[0], 1e3 * p[2]) for p in proj])
        ax.add_patch(Polygon(outline, closed=True, facecolor="#7a8ea8", edgecolor="k", lw=0.8))
        ax.set_title(f"t = {1e6 * t:.0f} us")
        ax.set_aspect("equal")
        ax.set_xlabel("x [mm]")
    thick = 1e3 * float(json.loads((run / "scenario.json").read_text())["target.thickness_m"])
    for ax in axes:
        ax.set_ylim(-thick - 3 * thick / 2, thick)
        ax.autoscale(enable=True, axis="x", tight=True)
    axes[0].set_ylabel("z [mm]")
    fig.colorbar(pc, ax=axes, shrink=0.8, label="damage (broken / initial links)")
    fig.suptitle(f"{summary['scenario']}: {summary['striking_velocity_m_s']:g} m/s, residual "
                 f"{summary['residual_velocity_m_s']:.0f} m/s, {summary['particles']} spheres (cut at y = 0)")
    fig.savefig(out_png, dpi=110, bbox_inches="tight")
    write_figures(summary, out_png)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    main(sys.argv[1], sys.argv[2])
