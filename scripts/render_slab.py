#!/usr/bin/python3
"""Renders a coupled slab's impact run (impact --model coupled): the DE
core's damage and the shells' deflection in one picture.

Top row: a cut along the projectile's path (the x-z plane, y = 0) at three
moments, the spheres within one mean radius of the plane drawn as discs
coloured by their damage (broken / initial links), the projectile's outline,
and the shells' section (grey) from the core's edge outwards, overlapping
the spheres of the band. Bottom: the whole slab seen from above at the last
of them, the shells coloured by their deflection u_z and the spheres of the
struck face by their damage; and the shells' deflection along y = 0 at the
three moments.

Reads DIR/particles.h5, DIR/shell.h5, DIR/scenario.json and
DIR/summary.json of `build/bin/impact SCENARIO --output DIR --summary
DIR/summary.json` (a coupled run). The three moments are the frames after a
quarter and after half of the run, and the last.

Writes OUT.png and, beside it, OUT.json: the figures the picture shows
(scenario, spheres, striking and residual velocity, outcome).

Usage: /usr/bin/python3 scripts/render_slab.py DIR OUT.png
"""
import json
import sys
from pathlib import Path

import h5py
import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PatchCollection, PolyCollection  # noqa: E402
from matplotlib.patches import Circle, Polygon  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
from render_impact import hull, write_figures  # noqa: E402


def frame_times(xdmf: Path):
    return [float(t.split('"')[1]) for t in xdmf.read_text().split("<Time Value=")[1:]]


def by_number(names):
    return sorted((k for k in names if k.startswith("frame_")), key=lambda k: int(k.split("_")[1]))


def read(run: Path):
    """The three moments: spheres, projectile, shells' displacement, time."""
    with h5py.File(run / "particles.h5", "r") as f, h5py.File(run / "shell.h5", "r") as s:
        frames = by_number(f)
        times = frame_times(run / "particles.xdmf")
        picks = [frames[len(frames) // 4], frames[len(frames) // 2], frames[-1]]
        mesh = (s["mesh/geometry"][()], s["mesh/topology"][()])
        data = []
        for k in picks:
            g = f[k]
            data.append({"x": g["position"][()], "r": g["radius"][()], "damage": g["damage"][()],
                         "proj": g["projectile_position"][()], "u": s[k]["displacement"][()],
                         "t": times[int(k.split("_")[1])]})
    return mesh, data


def section(mesh, u, h):
    """The shells' mid-surface along y = 0, each side of the core: (x, z +
    u_z) in mm, the nodes within h / 2 of y = 0 averaged over bins h wide
    along x (h: the element size; the mesh has no row of nodes on y = 0)."""
    geo = mesh[0]
    near = np.abs(geo[:, 1]) < 0.5 * h
    sides = []
    for side in (-1, 1):
        m = near & (side * geo[:, 0] > 0)
        x, z = geo[m, 0], geo[m, 2] + u[m, 2]
        bins = np.round(x / h).astype(int)
        keys = np.unique(bins)
        sides.append((1e3 * np.array([x[bins == k].mean() for k in keys]),
                      1e3 * np.array([z[bins == k].mean() for k in keys])))
    return sides


def profile(ax, mesh, data, thick, h):
    """The shells' deflection u_z along y = 0 at each moment [mm]."""
    for d, colour in zip(data, ("#9ecae1", "#4292c6", "#08306b")):
        for k, (xs, zs) in enumerate(section(mesh, d["u"], h)):
            ax.plot(xs, zs + thick / 2, color=colour, label=f"t = {1e6 * d['t']:.0f} us" if k else None)
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("x [mm]")
    ax.yaxis.tick_right()
    ax.yaxis.set_label_position("right")
    ax.set_ylabel("shells' deflection u_z at y = 0 [mm]")
    ax.legend()


def cut(ax, d, mesh, r_mean, thick, h):
    """The x-z cut at y = 0: spheres by damage, projectile, shells' section."""
    x = d["x"]
    keep = abs(x[:, 1]) < r_mean
    discs = [Circle((1e3 * p[0], 1e3 * p[2]), 1e3 * q) for p, q in zip(x[keep], d["r"][keep])]
    pc = PatchCollection(discs, cmap="inferno_r", edgecolor="none")
    pc.set_array(d["damage"][keep])
    pc.set_clim(0.0, 1.0)
    ax.add_collection(pc)
    ax.add_patch(Polygon(hull([(1e3 * p[0], 1e3 * p[2]) for p in d["proj"]]), closed=True,
                         facecolor="#7a8ea8", edgecolor="k", lw=0.8))
    for xs, zs in section(mesh, d["u"], h):
        ax.fill_between(xs, zs - thick / 2, zs + thick / 2, color="#b9c3cc", alpha=0.6, lw=0, zorder=0)
        ax.plot(xs, zs, color="#42505c", lw=0.6, zorder=0)
    ax.set_title(f"t = {1e6 * d['t']:.0f} us")
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    return pc


def plan(ax, d, mesh, r_mean):
    """The slab from above: shells by u_z [mm], spheres by damage."""
    geo, cells = mesh
    uz = 1e3 * d["u"][:, 2]
    polys = [1e3 * geo[c][:, :2] for c in cells]
    shells = PolyCollection(polys, cmap="coolwarm", edgecolor="none")
    shells.set_array(uz[cells].mean(axis=1))
    lim = max(abs(uz).max(), 1e-9)
    shells.set_clim(-lim, lim)
    ax.add_collection(shells)
    x = d["x"]
    top = x[:, 2] > -2 * r_mean  # the struck face's layer
    ax.scatter(1e3 * x[top, 0], 1e3 * x[top, 1], c=d["damage"][top], cmap="inferno_r", vmin=0, vmax=1, s=1.5,
               lw=0)
    ax.set_aspect("equal")
    ax.autoscale()
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title(f"from above, t = {1e6 * d['t']:.0f} us")
    return shells


def main(run_dir, out_png):
    run = Path(run_dir)
    summary = json.loads((run / "summary.json").read_text())
    scenario = json.loads((run / "scenario.json").read_text())
    thick = 1e3 * float(scenario["target.thickness_m"])
    r_mean = float(summary["mean_radius_m"])
    mesh, data = read(run)
    reach = 1e3 * abs(data[0]["x"][:, 0]).max()  # the DE region's half width along x
    h = float(summary["coupling"]["element_size_m"])
    fig = plt.figure(figsize=(12, 7.8))
    grid = fig.add_gridspec(2, 6, height_ratios=[1, 1.5])
    axes = [fig.add_subplot(grid[0, 2 * k:2 * k + 2]) for k in range(3)]
    for ax, d in zip(axes, data):
        pc = cut(ax, d, mesh, r_mean, thick, h)
        ax.set_xlim(-reach - 40, reach + 40)
        ax.set_ylim(-thick - 1.5 * thick, thick)
    axes[0].set_ylabel("z [mm]")
    fig.colorbar(pc, ax=axes, shrink=0.8, label="damage (broken / initial links)")
    below = fig.add_subplot(grid[1, :3])
    shells = plan(below, data[-1], mesh, r_mean)
    fig.colorbar(shells, ax=below, shrink=0.8, label="shells' deflection u_z [mm]")
    profile(fig.add_subplot(grid[1, 3:]), mesh, data, thick, h)
    fig.suptitle(f"{summary['scenario']}: {summary['striking_velocity_m_s']:g} m/s, residual "
                 f"{summary['residual_velocity_m_s']:.0f} m/s; {summary['particles']} spheres in the core and "
                 f"band, {summary['coupling']['shell_nodes']} shell nodes", y=0.95)
    fig.savefig(out_png, dpi=100, bbox_inches="tight")
    write_figures(summary, out_png)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    main(sys.argv[1], sys.argv[2])
