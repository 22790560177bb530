#!/usr/bin/python3
"""A run on 1 and on 2 threads gives the same result, bit for bit.

Runs EXE ARGS --output DIR --summary DIR.json with OMP_NUM_THREADS=1, then
=2, and compares the summaries (every key but the wall-clock times), every
CSV and XDMF file byte for byte and every HDF5 dataset bit for bit (the
comparisons of tests/restart.py).

Usage: threads.py EXE ARGS...
"""
import glob
import json
import os
import subprocess
import sys
import tempfile

from restart import compare_h5, compare_json


def main(argv):
    if not argv:
        raise SystemExit(__doc__)
    problems = []
    with tempfile.TemporaryDirectory() as tmp:
        dirs = {}
        for n in (1, 2):
            d = os.path.join(tmp, f"t{n}")
            env = dict(os.environ, OMP_NUM_THREADS=str(n))
            r = subprocess.run(argv + ["--output", d, "--summary", d + ".json"], env=env, text=True,
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
            if r.returncode != 0:
                raise SystemExit(f"{n} thread(s): exit {r.returncode}: {r.stderr[-500:]}")
            dirs[n] = d
        with open(dirs[1] + ".json") as f1, open(dirs[2] + ".json") as f2:
            compare_json(json.load(f1), json.load(f2), "", problems)
        files = sorted(os.path.relpath(p, dirs[1]) for p in glob.glob(os.path.join(dirs[1], "*")))
        for name in files:
            a, b = os.path.join(dirs[1], name), os.path.join(dirs[2], name)
            if name.endswith((".csv", ".xdmf")):
                with open(a, "rb") as fa, open(b, "rb") as fb:
                    if fa.read() != fb.read():
                        problems.append(f"{name}: differs")
            elif name.endswith(".h5"):
                compare_h5(a, b, problems)
    for p in problems:
        print(p)
    print(f"{os.path.basename(argv[0])}: 1 and 2 threads, {len(files)} output files and the summary compared; "
          f"{len(problems)} differences")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
