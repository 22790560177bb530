"""Checks an impact run's summary against its own history (history.csv).

    check_outcome.py SUMMARY.json HISTORY.csv THICKNESS_M OUTCOME

OUTCOME is what the run must report (perforated or stopped). The summary's
outcome and penetration depth are recomputed from the rows:
- perforated: some row has a contact (contacts > 0, contact force > 0), and
  the last row's tip lies deeper than the rear face; the depth is the
  thickness; the residual velocity is the last row's speed.
- stopped: some row has a contact; the last row's path velocity is at most
  2 % of the striking speed (the run's stop rule); the depth lies between
  the deepest tip in the rows and that plus the distance the projectile can
  cover between two rows at the striking speed (the summary tracks the
  depth at every step, the rows every few steps).
A run that never touched the slab must not be reported as either.
"""
import csv
import json
import sys


def main():
    summary_file, history_file, thickness, expect = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4]
    s = json.load(open(summary_file))
    rows = list(csv.DictReader(open(history_file)))
    if len(rows) < 2:
        sys.exit(f"{history_file}: {len(rows)} rows")
    touched = [r for r in rows if int(r["contacts"]) > 0 and float(r["contact_force_n"]) > 0.0]
    depth = [float(r["depth_m"]) for r in rows]
    times = [float(r["time_s"]) for r in rows]
    last = rows[-1]
    v0 = s["striking_velocity_m_s"]
    failures = []

    def check(ok, what):
        print(("ok   " if ok else "FAIL ") + what)
        if not ok:
            failures.append(what)

    check(s["outcome"] == expect, f"outcome {s['outcome']!r}, expected {expect!r}")
    check(bool(touched), f"{len(touched)} rows with a contact")
    check(s["touched"] == bool(touched), f"summary touched {s['touched']} against the rows")
    check(s["peak_contact_force_n"] >= max(float(r["contact_force_n"]) for r in rows),
          f"peak contact force {s['peak_contact_force_n']:.4g} N at least the rows' largest")
    if expect == "perforated":
        check(s["perforated"], "perforated flag")
        check(float(last["depth_m"]) > thickness, f"last tip depth {float(last['depth_m']):.4g} m past the rear "
              f"face {thickness} m")
        check(abs(s["penetration_depth_m"] - thickness) < 1e-12, f"depth {s['penetration_depth_m']} m = thickness")
        speed = float(last["speed_m_s"])
        check(abs(s["residual_velocity_m_s"] - speed) <= 1e-6 * v0,
              f"residual velocity {s['residual_velocity_m_s']:.6g} m/s = last row's speed {speed:.6g}")
    else:
        check(not s["perforated"], "not perforated")
        check(float(last["path_velocity_m_s"]) <= 0.02 * v0 + 1e-9,
              f"last path velocity {float(last['path_velocity_m_s']):.4g} m/s <= 2 % of {v0} m/s")
        gap = max(b - a for a, b in zip(times, times[1:])) * v0
        d = s["penetration_depth_m"]
        check(max(depth) - 1e-12 <= d <= max(depth) + gap,
              f"depth {d:.5g} m within [{max(depth):.5g}, {max(depth) + gap:.5g}] m of the rows' deepest tip")
        check(0.0 < d < thickness, f"depth {d:.5g} m inside the slab")
    if failures:
        sys.exit(f"{len(failures)} check(s) failed")


if __name__ == "__main__":
    main()
