#!/usr/bin/python3
"""Renders the coupled bar of a `bar` run, seen from the side (x-z plane).

Reads what `build/bin/bar --model coupled --load bending --regime static
--output DIR` writes: DIR/particles.h5 (the spheres' last frame: position,
radius, displacement), DIR/shape.csv (the shell's displacement along the bar)
and DIR/summary.json. Draws the shell part as a grey band (its thickness, on
the deformed mid-surface), the spheres as discs coloured by their vertical
displacement, the overlap shaded, displacements magnified so that the
largest shows as `--shown` metres.

Usage: /usr/bin/python3 scripts/render_picture.py DIR OUT.png [--thickness H]
       [--overlap X0 X1] [--shown S]
"""
import argparse
import csv
import json
import sys
from pathlib import Path

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PatchCollection  # noqa: E402
from matplotlib.patches import Circle, Polygon  # noqa: E402


def last_frame(h5_path):
    """Position (n, 3), radius (n), displacement (n, 3) of the last frame."""
    with h5py.File(h5_path, "r") as f:
        frames = sorted((k for k in f.keys() if k.startswith("frame_")), key=lambda k: int(k[6:]))
        if not frames:
            raise SystemExit(f"error: {h5_path} holds no frame")
        g = f[frames[-1]]
        return g["position"][()], g["radius"][()], g["displacement"][()]


def shell_line(shape_csv):
    """(x, w) of the shell's columns, from shape.csv's rows with source fe."""
    xs, ws = [], []
    with open(shape_csv, newline="") as f:
        for row in csv.DictReader(f):
            if row["source"] == "fe":
                xs.append(float(row["x_m"]))
                ws.append(float(row["displacement_m"]))
    if not xs:
        raise SystemExit(f"error: {shape_csv} has no shell (fe) rows: is it a coupled or fe run?")
    return xs, ws


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", type=Path, help="the bar run's output folder")
    ap.add_argument("png", type=Path, help="the picture to write")
    ap.add_argument("--thickness", type=float, default=0.25, help="shell thickness [m]")
    ap.add_argument("--overlap", type=float, nargs=2, default=[0.40, 0.55],
                    help="overlap from x0 to x1 [m]")
    ap.add_argument("--shown", type=float, default=0.06,
                    help="the largest displacement as drawn [m]")
    a = ap.parse_args(argv)
    for name in ("particles.h5", "shape.csv", "summary.json"):
        if not (a.dir / name).is_file():
            raise SystemExit(f"error: {a.dir / name} not found: run build/bin/bar --model coupled "
                             f"--load bending --regime static --output {a.dir} first")
    summary = json.loads((a.dir / "summary.json").read_text())
    x, r, u = last_frame(a.dir / "particles.h5")
    xs, ws = shell_line(a.dir / "shape.csv")
    umax = max(max(abs(v) for v in ws), float(abs(u[:, 2]).max()))
    if not umax > 0.0:
        raise SystemExit("error: the bar did not move (all displacements are 0)")
    s = a.shown / umax
    h = a.thickness

    fig, ax = plt.subplots(figsize=(10, 3.6), dpi=120)
    ax.axvspan(a.overlap[0], a.overlap[1], color="#f3d9a4", alpha=0.6, lw=0, zorder=0)
    # the shell: its sections (normal to the mid-surface, Reissner-Mindlin)
    # turned with the slope of the magnified deflection
    slope = [(ws[min(k + 1, len(xs) - 1)] - ws[max(k - 1, 0)])
             / (xs[min(k + 1, len(xs) - 1)] - xs[max(k - 1, 0)]) for k in range(len(xs))]
    top = [(xi - 0.5 * h * s * gi, 0.5 * h + s * wi) for xi, wi, gi in zip(xs, ws, slope)]
    bottom = [(xi + 0.5 * h * s * gi, -0.5 * h + s * wi) for xi, wi, gi in zip(xs, ws, slope)]
    # spheres at their magnified displacement (x holds the deformed centres),
    # the near side (small y) drawn last
    order = sorted(range(len(r)), key=lambda i: -x[i, 1])
    discs = [Circle((x[i, 0] - u[i, 0] + s * u[i, 0], x[i, 2] - u[i, 2] + s * u[i, 2]), r[i])
             for i in order]
    pc = PatchCollection(discs, cmap="viridis", edgecolor="#1d1d1d", linewidth=0.15, zorder=1)
    pc.set_array([1e6 * u[i, 2] for i in order])
    ax.add_collection(pc)
    # the shell over them, see-through where the two overlap
    ax.add_patch(Polygon(top + bottom[::-1], closed=True, facecolor="#b8bcc2", edgecolor="#3c4046",
                         lw=1.0, alpha=0.55, zorder=2))
    for (xt, zt), (xb, zb) in zip(top, bottom):  # the shell's element edges
        ax.plot([xb, xt], [zb, zt], color="#3c4046", lw=0.6, zorder=2)
    cb = fig.colorbar(pc, ax=ax, fraction=0.03, pad=0.01)
    cb.set_label("vertical displacement [µm]")
    ax.set_aspect("equal")
    ax.set_xlim(-0.02, 0.87)
    ax.set_ylim(-0.5 * h - 0.03, 0.5 * h + a.shown + 0.03)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.set_title(f"Coupled bar in static bending: shells (grey), {summary['particles']} spheres, "
                 f"overlap shaded; displacements x {s:.0f}", fontsize=10)
    fig.tight_layout()
    a.png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(a.png)
    print(f"wrote {a.png}")


if __name__ == "__main__":
    main(sys.argv[1:])
