#!/usr/bin/python3
"""A run interrupted and restarted from its checkpoint equals the uninterrupted run.

Runs EXE ARGS --output A --summary A.json to the end. Then runs the same
with --output B --checkpoint-every N, waits for its first checkpoint,
interrupts it (SIGINT: the run writes a checkpoint at the end of that step
and exits 130), and restarts it with --restart B/checkpoint.h5. Checks:
- the interrupted run's summary names its checkpoint;
- the restarted run's summary equals the whole run's, every key, bit for bit
  (but the wall-clock times and restarted_from_step, which says where it
  continued);
- every CSV and XDMF file of B equals A's byte for byte, and every HDF5
  dataset of B equals A's, bit for bit (same datasets, same values);
- a restart with another value of a set-up option (--bad OPTION VALUE) is
  refused with exit code 1 and a message naming the option (or, for --set
  KEY=VALUE, the scenario key); with --before TEXT, before the run printed
  TEXT (a message of its set-up, e.g. the packing's: refused before any
  set-up is spent on it).

With --kill, the run is killed (SIGKILL, no checkpoint of its own) a moment
after its first periodic checkpoint instead: the restart then continues from
that older checkpoint, dropping the frames and CSV rows written after it.

Usage: restart.py --every N [--kill] [--bad OPTION VALUE [--before TEXT]] EXE ARGS...
"""
import glob
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

SKIP = {"wall_s", "restarted_from_step", "step_time_s", "de_step_split_s", "shell_setup_s", "shells_and_bridge_share",
        "peak_memory_mb"}


def run(cmd):
    return subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                          stdin=subprocess.DEVNULL)


def timing(key):
    return key in SKIP or key.endswith("_wall_s") or "seconds" in key or key.startswith("time_per")


def compare_json(a, b, where, problems):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if timing(k):
                continue
            if k not in a or k not in b:
                problems.append(f"summary {where}{k}: only in {'the whole run' if k in a else 'the restarted run'}")
            else:
                compare_json(a[k], b[k], f"{where}{k}.", problems)
    elif a != b:
        problems.append(f"summary {where[:-1]}: {a!r} (whole run) against {b!r} (restarted)")


def compare_h5(fa, fb, problems):
    with h5py.File(fa, "r") as a, h5py.File(fb, "r") as b:
        names = {}
        for f, key in ((a, "a"), (b, "b")):
            def visit(name, obj, key=key):
                if isinstance(obj, h5py.Dataset):
                    names.setdefault(name, set()).add(key)
            f.visititems(visit)
        for name, where in sorted(names.items()):
            if where != {"a", "b"}:
                problems.append(f"{os.path.basename(fa)}:{name}: only in {'A' if 'a' in where else 'B'}")
                continue
            x, y = a[name][()], b[name][()]
            if x.shape != y.shape or x.dtype != y.dtype or not np.array_equal(x.view(np.uint8), y.view(np.uint8)):
                problems.append(f"{os.path.basename(fa)}:{name}: differs")
        return len(names)


def main(argv):
    every, bad, kill, before = None, None, False, None
    while argv and argv[0].startswith("--"):
        if argv[0] == "--kill":
            kill, argv = True, argv[1:]
        elif argv[0] == "--every":
            every, argv = argv[1], argv[2:]
        elif argv[0] == "--bad":
            bad, argv = argv[1:3], argv[3:]
        elif argv[0] == "--before":
            before, argv = argv[1], argv[2:]
        else:
            raise SystemExit(__doc__)
    if not argv or every is None:
        raise SystemExit(__doc__)
    problems = []
    with tempfile.TemporaryDirectory() as tmp:
        A, B = os.path.join(tmp, "A"), os.path.join(tmp, "B")
        r = run(argv + ["--output", A, "--summary", A + ".json"])
        if r.returncode != 0:
            print(f"the whole run failed (exit {r.returncode}): {r.stderr[-400:]}")
            return 1
        ckpt = os.path.join(B, "checkpoint.h5")
        p = subprocess.Popen(argv + ["--output", B, "--summary", B + ".json", "--checkpoint-every", every],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
        start = time.time()
        while not os.path.exists(ckpt) and p.poll() is None and time.time() - start < 300:
            time.sleep(0.02)
        if kill:
            time.sleep(0.3)  # outputs written after the checkpoint, to be dropped
        p.send_signal(signal.SIGKILL if kill else signal.SIGINT)
        _, err = p.communicate(timeout=120)
        if p.returncode != (-9 if kill else 130):
            print(f"the run was not interrupted (exit {p.returncode}; make it longer or --every smaller): {err[-300:]}")
            return 1
        s = {} if kill else json.load(open(B + ".json"))
        if not kill and (s.get("completed") is not False or s.get("checkpoint") != ckpt):
            problems.append(f"interrupted summary: {s}")
        if bad:
            r = subprocess.run(argv + [bad[0], bad[1], "--output", B, "--restart", ckpt], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
            # the option named, or the scenario key a --set changed
            named = bad[0] in r.stderr or bad[1].split("=")[0] in r.stderr
            if r.returncode != 1 or not named or "differs from the checkpointed run" not in r.stderr:
                problems.append(f"restart with {bad[0]} {bad[1]}: exit {r.returncode}, {r.stderr.strip()[-300:]!r}")
            if before and before in r.stdout:
                problems.append(f"restart with {bad[0]} {bad[1]}: refused only after the set-up printed {before!r}")
        r = run(argv + ["--output", B, "--summary", B + ".json", "--restart", ckpt])
        if r.returncode != 0:
            print(f"the restart failed (exit {r.returncode}): {r.stderr[-400:]}")
            return 1
        b = json.load(open(B + ".json"))
        a = json.load(open(A + ".json"))
        if "restarted_from_step" not in b:
            problems.append("the restarted summary has no restarted_from_step")
        compare_json(a, b, "", problems)
        files = 0
        for fa in sorted(glob.glob(os.path.join(A, "**", "*"), recursive=True)):
            rel = os.path.relpath(fa, A)
            fb = os.path.join(B, rel)
            if os.path.isdir(fa) or rel.endswith(".png"):
                continue
            if not os.path.exists(fb):
                problems.append(f"{rel}: not in the restarted run's output")
                continue
            files += 1
            if rel.endswith(".h5"):
                compare_h5(fa, fb, problems)
            elif open(fa, "rb").read() != open(fb, "rb").read():
                problems.append(f"{rel}: differs")
        print(f"{os.path.basename(argv[0])}: {'killed' if kill else 'interrupted'} after {s.get('time_reached_s', '?')} s of simulated time, "
              f"restarted from step {b.get('restarted_from_step')}; {files} output files and the summary compared")
    for pr in problems:
        print(pr)
    print(f"{len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
