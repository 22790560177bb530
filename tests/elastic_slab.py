#!/usr/bin/env python3
"""The elastic slab under a short pulse, three ways (docs/impact.md, "Elastic
checks"): `impact elastic-slab` with --model fe, de and coupled. At each
deflection point the peak deflection and the free vibration's period
(summary: deflection_points) of the all-DE and the coupled slab must agree
with the all-shell slab's, and the coupled slab's with the all-DE slab's,
within 5 % and 2 %: the same concrete and the same free span in each model,
so neither the spheres nor the coupling may stiffen or soften the slab by
more than the discretisations' differences (a period error of 2 % is a 4 %
error in stiffness). The all-DE slab holds its spheres in a band inside its
lateral faces, the shells their edges: it is run 20 mm wider with a 10 mm
band, so that all three slabs bend over 0.4 m. No link may break (the load
is elastic) and each energy budget closes to 1e-3 of the pulse's work.

usage: elastic_slab.py IMPACT OUTDIR
"""
import json
import subprocess
import sys
from pathlib import Path


# The all-DE slab's held band (10 mm) lies outside the shells' 0.4 m span.
DE_SPAN = ["--set", "target.size_m=[0.42, 0.42]", "--set", "target.support_width_m=0.01"]


def run(impact, out, model):
    summary = out / f"elastic_{model}.json"
    cmd = [impact, "elastic-slab", "--model", model, "--summary", str(summary), "--plot", "0"]
    if model == "de":
        cmd += DE_SPAN
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"FAIL: {' '.join(cmd)} exited {done.returncode}:\n{done.stderr[-2000:]}")
    return json.loads(summary.read_text())


def main():
    impact, out = sys.argv[1], Path(sys.argv[2])
    out.mkdir(parents=True, exist_ok=True)
    runs = {m: run(impact, out, m) for m in ("fe", "de", "coupled")}
    failures = []
    for model, s in runs.items():
        share = abs(s["energy"]["imbalance_share"])
        print(f"{model}: wall {s['wall_s']:.1f} s, budget {share:.2e} of the pulse's work, "
              f"links broken {s.get('links_broken', 0)}")
        if share > 1e-3:
            failures.append(f"{model}: energy budget off by {share:.2e} of the pulse's work")
        if s.get("links_broken", 0) != 0:
            failures.append(f"{model}: {s['links_broken']} links broke under an elastic load")
    for model, against in (("de", "fe"), ("coupled", "fe"), ("coupled", "de")):
        ref = runs[against]["deflection_points"]
        for q, (p, r) in enumerate(zip(runs[model]["deflection_points"], ref)):
            if p["period_s"] is None or r["period_s"] is None:
                failures.append(f"{model}: point {q}: no period (fewer than 3 zero crossings)")
                continue
            dp = p["period_s"] / r["period_s"] - 1.0
            dw = p["peak_m"] / r["peak_m"] - 1.0
            print(f"{model} point {q} ({p['x_m']}, {p['y_m']}) m: period {p['period_s'] * 1e3:.4f} ms "
                  f"({100 * dp:+.2f} % of {against}'s), peak {p['peak_m'] * 1e6:.3f} um ({100 * dw:+.2f} %)")
            if abs(dp) > 0.02:
                failures.append(f"{model} point {q}: period {100 * dp:+.2f} % off {against}'s (bound 2 %)")
            if abs(dw) > 0.05:
                failures.append(f"{model} point {q}: peak {100 * dw:+.2f} % off {against}'s (bound 5 %)")
    if failures:
        sys.exit("FAIL:\n  " + "\n  ".join(failures))
    print("PASS")


if __name__ == "__main__":
    main()
