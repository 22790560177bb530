#!/usr/bin/python3
"""Penetration depths of a rigid projectile into a thick concrete block, run
at several striking speeds, against two published formulas for rigid
ogive-nose projectiles into semi-infinite concrete:

- Forrestal et al. (1994, 1996): a crater of depth 2 d, then the tunnel's
  resistance (pi d^2 / 4) (S f_c + N* rho V^2), S = 82.6 f_c^-0.544 (f_c in MPa):
      X = 2 M / (pi d^2 N* rho) ln(1 + N* rho V1^2 / (S f_c)) + 2 d,
      V1^2 = (M V^2 - (pi/2) d^3 S f_c) / (M + (pi/2) d^3 N* rho);
- Li and Chen (2003): the same resistance with S = 72 f_c^-0.5 and a crater
  of depth k d, k = 0.707 + h/d (h the nose length), in the dimensionless
  form X/d = (2 N / pi) ln((1 + I / N) / (1 + pi k / (4 N))) + k, with
  I = M V^2 / (S f_c d^3) and N = M / (N* rho d^3), or, for X/d <= k,
  X/d = sqrt((4 k I / pi) (1 + pi k / (4 N)) / (1 + I / N)).
N* = (8 psi - 1) / (24 psi^2) for an ogive of CRH psi. These are fits to test
series with 10-30 % scatter: envelopes, not exact values.

Runs build/bin/impact SCENARIO --set projectile.velocity_m_s=V for each V
into OUT/v<V>/ (a run already complete is not redone), and writes
OUT/penetration.json and OUT/penetration.csv: the depth run and the two
formulas' at each speed, and how far the projectile left its path (the tip's
distance from it at the end, `off_path_m`, and the largest speed across it,
`across_path_max_m_s`: the formulas are for a projectile that keeps to its
path). A block thinner than 3 x the depth (the run's or the formulas') is
flagged (`thin_block`). f_c is the material file's measured compressive
strength (its "macroscopic" block), or --fc.

Usage: /usr/bin/python3 scripts/penetration.py SCENARIO OUT V1 V2 ... [--set KEY=VALUE ...]
       [--fc PA] [--impact build/bin/impact]
"""
import argparse
import csv
import json
import math
import os
import sys

from ballistic import run_at


def nose_factor(psi):
    return (8.0 * psi - 1.0) / (24.0 * psi * psi)


def forrestal(M, d, psi, rho, fc, V):
    S = 82.6 * (fc / 1e6) ** -0.544
    N = nose_factor(psi)
    v1sq = (M * V * V - math.pi / 2 * d ** 3 * S * fc) / (M + math.pi / 2 * d ** 3 * N * rho)
    if v1sq <= 0:  # stops in the crater: x = 2d sqrt(M V^2 / (pi/2 d^3 S fc)) (force linear in depth)
        return 2 * d * math.sqrt(M * V * V / (math.pi / 2 * d ** 3 * S * fc))
    return 2 * M / (math.pi * d * d * N * rho) * math.log(1 + N * rho * v1sq / (S * fc)) + 2 * d


def li_chen(M, d, psi, rho, fc, V):
    S = 72.0 * (fc / 1e6) ** -0.5
    Ns = nose_factor(psi)
    h = d * math.sqrt(psi - 0.25)
    k = 0.707 + h / d
    I = M * V * V / (S * fc * d ** 3)
    N = M / (Ns * rho * d ** 3)
    deep = 2 * N / math.pi * math.log((1 + I / N) / (1 + math.pi * k / (4 * N))) + k
    if deep > k:
        return d * deep
    return d * math.sqrt(4 * k * I / math.pi * (1 + math.pi * k / (4 * N)) / (1 + I / N))


def off_path(history_csv, aim, obliquity_deg):
    """The tip's distance from the intended path (the line through (aim, 0)
    along (sin th, 0, -cos th)) at the last row of a history, and the
    largest speed across that path over the run [m, m/s]."""
    th = math.radians(obliquity_deg)
    u = (math.sin(th), 0.0, -math.cos(th))

    def across_u(w):  # the length of w's part across u
        along = sum(a * b for a, b in zip(w, u))
        return math.sqrt(sum((c - along * e) ** 2 for c, e in zip(w, u)))

    speed, tip = 0.0, None
    with open(history_csv) as f:
        for row in csv.DictReader(f):
            speed = max(speed, across_u([float(row[f"velocity_{c}_m_s"]) for c in "xyz"]))
            tip = [float(row["tip_x_m"]) - aim[0], float(row["tip_y_m"]) - aim[1], float(row["tip_z_m"])]
    if tip is None:
        raise ValueError(f"{history_csv}: no rows")
    return across_u(tip), speed


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenario")
    ap.add_argument("out")
    ap.add_argument("velocities", type=float, nargs="+")
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--fc", type=float, default=0.0)
    ap.add_argument("--impact", default=os.path.join(os.path.dirname(__file__), "..", "build", "bin", "impact"))
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for V in args.velocities:
        s = run_at(args.impact, args.scenario, args.out, V, args.set)
        d = os.path.join(args.out, f"v{V:g}")
        with open(os.path.join(d, "scenario.json")) as f:
            sc = json.load(f)
        fc = args.fc
        if fc <= 0:
            with open(sc["material.file"]) as f:
                fc = json.load(f)["macroscopic"]["compressive_strength_pa"]
        M, dia, psi = s["projectile_mass_kg"], sc["projectile.diameter_m"], sc["projectile.crh"]
        rho = sc["material.density_kg_m3"]
        xf, xl = forrestal(M, dia, psi, rho, fc, V), li_chen(M, dia, psi, rho, fc, V)
        rows.append({"striking_m_s": V, "depth_m": s["penetration_depth_m"], "forrestal_m": xf, "li_chen_m": xl,
                     "to_forrestal": s["penetration_depth_m"] / xf - 1, "to_li_chen": s["penetration_depth_m"] / xl - 1,
                     "perforated": s["perforated"], "outcome": s["outcome"], "thickness_m": sc["target.thickness_m"],
                     "particles": s["particles"], "imbalance_share": s["energy"]["imbalance_share"],
                     "wall_s": s["wall_s"], "fc_pa": fc})
        r = rows[-1]
        r["off_path_m"], r["across_path_max_m_s"] = off_path(os.path.join(d, "history.csv"), sc["projectile.aim_m"],
                                                             sc["projectile.obliquity_deg"])
        # the formulas are for a semi-infinite target: the rule, thickness >= 3 x the depth
        thin = r["thin_block"] = sc["target.thickness_m"] < 3 * max(r["depth_m"], xf, xl)
        print(f"{V:7.1f} m/s: depth {1e3 * r['depth_m']:6.1f} mm, Forrestal {1e3 * xf:6.1f} mm "
              f"({100 * r['to_forrestal']:+.0f} %), Li-Chen {1e3 * xl:6.1f} mm ({100 * r['to_li_chen']:+.0f} %); "
              f"tip {1e3 * r['off_path_m']:.1f} mm off the path, at most {r['across_path_max_m_s']:.1f} m/s across it"
              + ("  PERFORATED: the block is too thin" if s["perforated"] else "")
              + (f"  (the block, {sc['target.thickness_m']:g} m, is thinner than 3 x the depth)" if thin else ""))
    with open(os.path.join(args.out, "penetration.json"), "w") as f:
        json.dump(rows, f, indent=2)
    with open(os.path.join(args.out, "penetration.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
