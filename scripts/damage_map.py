#!/usr/bin/python3
"""Where a slab cracked: the share of spheres whose damage (their broken
links over their initial ones) exceeds a threshold, in bands of depth and of
distance from the projectile's path, at one frame of an `impact --output`
run (docs/validation.md 7b.2 compares slabs with and without bars this way).

The bands are taken on the spheres' initial positions (frame 0), so that a
band holds the same spheres at every frame. Depth is measured from the
slab's front face (z = 0) into it, the distance from the path from the aim
point along z: a normal impact (an oblique one is refused). A band with no
sphere prints '-'.

Usage: damage_map.py RUN_DIR [--frame K] [--threshold D]
         [--depths MM ...] [--radii MM ...]
RUN_DIR: the run's --output folder (its particles.h5); K: the frame (-1, the
last, by default); D: 0.3 by default.
"""
import argparse
import json
import pathlib
import sys

import numpy as np


def band_shares(damaged, depth, dist, depths, radii):
    """Share of damaged spheres in each (depth band, radius band); None where empty."""
    rows = []
    for d0, d1 in zip(depths[:-1], depths[1:]):
        row = []
        for r0, r1 in zip(radii[:-1], radii[1:]):
            s = (depth >= d0) & (depth < d1) & (dist >= r0) & (dist < r1)
            row.append(float(damaged[s].mean()) if s.any() else None)
        rows.append(row)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", type=pathlib.Path)
    ap.add_argument("--frame", type=int, default=-1)
    ap.add_argument("--threshold", type=float, default=0.3)
    ap.add_argument("--depths", type=float, nargs="+", default=[0, 20, 40, 60, 80, 100, 120, 140, 160, 180])
    ap.add_argument("--radii", type=float, nargs="+", default=[0, 20, 40, 60, 80, 100, 120, 150, 200, 300])
    a = ap.parse_args()
    if not 0.0 < a.threshold <= 1.0:
        sys.exit(f"--threshold {a.threshold}: allowed in (0, 1]")
    for name, edges in (("--depths", a.depths), ("--radii", a.radii)):
        if len(edges) < 2 or any(e1 <= e0 for e0, e1 in zip(edges[:-1], edges[1:])):
            sys.exit(f"{name} {edges}: give at least two edges, increasing")
    h5 = a.run / "particles.h5"
    if not h5.is_file():
        sys.exit(f"{h5}: not found (run impact with --output)")
    aim = [0.0, 0.0]
    scenario = a.run / "scenario.json"
    if scenario.is_file():
        resolved = json.loads(scenario.read_text())
        aim = resolved.get("projectile.aim_m", aim)
        obliquity = resolved.get("projectile.obliquity_deg", 0.0)
        if obliquity != 0.0:
            sys.exit(f"{a.run}: projectile.obliquity_deg = {obliquity}: the bands are about a path along z; "
                     "allowed 0 (a normal impact)")
    import h5py  # here, so that the band arithmetic can be imported without it
    try:
        f = h5py.File(h5, "r")
    except OSError as e:
        sys.exit(f"{h5}: cannot be read ({e}; is the run still writing it?)")
    with f:
        frames = sorted(int(k.split("_")[1]) for k in f if k.startswith("frame_"))
        if not frames:
            sys.exit(f"{h5}: no frame written")
        frame = frames[a.frame] if -len(frames) <= a.frame < len(frames) else None
        if frame is None:
            sys.exit(f"--frame {a.frame}: allowed -{len(frames)} to {len(frames) - 1} ({len(frames)} frames)")
        x0 = f["frame_0/position"][:]
        damage = f[f"frame_{frame}/damage"][:]
    depth = -x0[:, 2] * 1e3
    dist = np.hypot(x0[:, 0] - aim[0], x0[:, 1] - aim[1]) * 1e3
    rows = band_shares(damage > a.threshold, depth, dist, a.depths, a.radii)
    print(f"{a.run}: frame {frame}, share of spheres with damage > {a.threshold}")
    print("rows: depth [mm]; columns: distance from the path [mm]")
    print(f"{'':>11s}" + "".join(f"{f'{r0:g}-{r1:g}':>9s}" for r0, r1 in zip(a.radii[:-1], a.radii[1:])))
    for (d0, d1), row in zip(zip(a.depths[:-1], a.depths[1:]), rows):
        cells = "".join(f"{v:9.2f}" if v is not None else f"{'-':>9s}" for v in row)
        print(f"{f'{d0:g}-{d1:g}':>11s}{cells}")


if __name__ == "__main__":
    main()
