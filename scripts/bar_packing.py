#!/usr/bin/python3
"""The solid fraction of a packing against the distance from the nearest bar
axis: how densely the spheres pack round the bars (docs/validation.md 7b.2).

Points are drawn uniformly in a box (the slab less a margin at its lateral
faces); each counts as solid if it lies inside a sphere. The fraction in each
band of distance from the nearest bar element's axis is printed, with its
number of points (the fraction's standard error is about 0.5 / sqrt(count)).

Usage: bar_packing.py PACKING BARS_H5 [--box X0 X1 Y0 Y1 Z0 Z1] [--points N]
         [--edges MM ...] [--seed S]
PACKING: an `impact --output` run's packing.txt (x y z r per line, metres);
BARS_H5: the same run's bars.h5 (its first frame's positions and elements).
"""
import argparse

import numpy as np
from scipy.spatial import cKDTree


def axis_distance(points, a, b):
    """Distance of each point (n, 3) from the nearest segment [a[k], b[k]]."""
    best = np.full(len(points), np.inf)
    for p, q in zip(a, b):
        ab = q - p
        t = np.clip(((points - p) @ ab) / (ab @ ab), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(points - (p + t[:, None] * ab), axis=1))
    return best


def solid(points, centres, radii):
    """1 for each point inside some sphere, else 0."""
    tree = cKDTree(centres)
    inside = np.zeros(len(points), bool)
    for i, near in enumerate(tree.query_ball_point(points, radii.max())):
        if near:
            near = np.asarray(near)
            inside[i] = np.any(np.linalg.norm(centres[near] - points[i], axis=1) < radii[near])
    return inside


def fractions(points, inside, distance, edges):
    """(lo, hi, solid fraction, count) for each band [lo, hi) of distance."""
    out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (distance >= lo) & (distance < hi)
        out.append((lo, hi, inside[m].mean() if m.any() else float("nan"), int(m.sum())))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("packing")
    ap.add_argument("bars")
    ap.add_argument("--box", type=float, nargs=6, default=[-0.2, 0.2, -0.2, 0.2, -0.178, 0.0],
                    help="where the points are drawn: x0 x1 y0 y1 z0 z1 [m] (default: Hanchak's slab less 0.105 m at its sides)")
    ap.add_argument("--points", type=int, default=200000)
    ap.add_argument("--edges", type=float, nargs="+", default=[0, 2.845, 5, 7.5, 10, 12.5, 15, 20, 30, 100],
                    help="band edges, distance from the nearest axis [mm]")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    import h5py

    with h5py.File(a.bars) as f:
        x, e = f["frame_0/position"][:], f["elements"][:]
    d = np.loadtxt(a.packing)
    rng = np.random.default_rng(a.seed)
    lo, hi = np.array(a.box[0::2]), np.array(a.box[1::2])
    points = lo + rng.random((a.points, 3)) * (hi - lo)
    dist = axis_distance(points, x[e[:, 0]], x[e[:, 1]])
    inside = solid(points, d[:, :3], d[:, 3])
    for lo_, hi_, f, n in fractions(points, inside, dist, np.array(a.edges) * 1e-3):
        print(f"{lo_ * 1e3:6.2f}-{hi_ * 1e3:6.2f} mm from an axis: solid fraction {f:.3f} ({n} points)")


if __name__ == "__main__":
    main()
