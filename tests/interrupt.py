#!/usr/bin/python3
"""Interrupts a run and checks that nothing written is lost.

Starts EXE ARGS --output DIR --summary DIR/summary.json, waits until the run
has written its first output file (an .xdmf, .csv or .h5 in DIR) and `delay`
seconds more, sends the signal, and checks:
- the exit code is 128 + the signal's number (130 for SIGINT, 143 for SIGTERM);
- the summary says "completed": false, with the time reached > 0;
- every HDF5 file in DIR opens and every dataset reads back in full;
- every XDMF file parses (XML) and names only datasets that exist;
- every CSV file has whole rows only (each with the header's field count);
- no temporary packing file of the run is left in the temporary folder.

With --signal KILL the run is killed outright (no handler, no summary, its
HDF5 files perhaps mid-write): then only its CSV files are checked, for
whole rows, and for a first column (the time) that reaches the last frame
of its particles.xdmf, less the rows' own spacing (rows are flushed as they
are written, so nothing written before the kill is missing from them).

With --wait-output 0 it sends the signal `delay` seconds after the start
(for a program that writes its files only at the end).

With --expect-temp 1, a temporary file of the run must exist when the
signal is sent (so that its removal is what is checked).

Usage: interrupt.py [--signal TERM] [--delay S] [--wait-output 0] [--expect-temp 1] EXE ARGS...
"""
import glob
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

import h5py


def check_csv(out_dir, problems):
    for c in glob.glob(os.path.join(out_dir, "**", "*.csv"), recursive=True):
        with open(c) as f:
            text = f.read()
        if text and not text.endswith("\n"):
            problems.append(f"{c}: ends in the middle of a row")
        rows = text.split("\n")
        if rows and rows[-1] == "":
            rows.pop()
        if not rows:
            continue
        n = rows[0].count(",")
        bad = [i for i, r in enumerate(rows) if r.count(",") != n]
        if bad:
            problems.append(f"{c}: rows {bad[:5]} do not have the header's {n + 1} fields")


def check_killed(out_dir, problems):
    """A killed run: whole CSV rows, reaching the last XDMF frame."""
    check_csv(out_dir, problems)
    xdmf = os.path.join(out_dir, "particles.xdmf")
    csv = os.path.join(out_dir, "history.csv")
    if not (os.path.exists(xdmf) and os.path.exists(csv)):
        problems.append(f"killed before it wrote {csv} and {xdmf}: nothing checked (give a longer --delay)")
        return
    frames = [float(t.get("Value")) for t in ET.parse(xdmf).getroot().iter("Time")]
    times = [float(r.split(",")[0]) for r in open(csv).read().split("\n")[1:] if r]
    if not frames or len(times) < 2:
        problems.append(f"killed after {len(frames)} frames and {len(times)} rows: too early to check "
                        "(give a longer --delay)")
    else:
        spacing = max(b - a for a, b in zip(times, times[1:]))
        if times[-1] < frames[-1] - spacing * (1 + 1e-9):
            problems.append(f"{csv}: its last row (t = {times[-1]:.6g} s) lags the last frame of {xdmf} "
                            f"(t = {frames[-1]:.6g} s) by more than the rows' spacing {spacing:.3g} s")
        print(f"killed: {len(times)} rows to t = {times[-1]:.6g} s, {len(frames)} frames to t = {frames[-1]:.6g} s")


def check_outputs(out_dir, problems):
    for h5 in glob.glob(os.path.join(out_dir, "**", "*.h5"), recursive=True):
        try:
            with h5py.File(h5, "r") as f:
                def visit(name, obj):
                    if isinstance(obj, h5py.Dataset):
                        obj[()]  # reads it all
                f.visititems(visit)
        except Exception as e:  # noqa: BLE001 -- any failure to read is the finding
            problems.append(f"{h5}: cannot be read back: {e}")
    for x in glob.glob(os.path.join(out_dir, "**", "*.xdmf"), recursive=True):
        try:
            root = ET.parse(x).getroot()
        except ET.ParseError as e:
            problems.append(f"{x}: not valid XML: {e}")
            continue
        for item in root.iter("DataItem"):
            ref = (item.text or "").strip()
            if ":" in ref and item.get("Format") == "HDF":
                fname, path = ref.split(":", 1)
                fpath = os.path.join(os.path.dirname(x), fname)
                try:
                    with h5py.File(fpath, "r") as f:
                        f[path][()]
                except Exception as e:  # noqa: BLE001
                    problems.append(f"{x}: names {ref}, which cannot be read: {e}")
    check_csv(out_dir, problems)


def main(argv):
    sig, delay, wait_output, expect_temp = signal.SIGINT, 1.0, True, False
    while argv and argv[0].startswith("--"):
        if argv[0] == "--signal":
            sig = getattr(signal, "SIG" + argv[1])
        elif argv[0] == "--delay":
            delay = float(argv[1])
        elif argv[0] == "--expect-temp":
            expect_temp = argv[1] != "0"
        elif argv[0] == "--wait-output":
            wait_output = argv[1] != "0"
        argv = argv[2:]
    if not argv:
        raise SystemExit(__doc__)
    problems = []
    with tempfile.TemporaryDirectory() as out_dir:
        summary = os.path.join(out_dir, "summary.json")
        cmd = argv + ["--output", out_dir, "--summary", summary]
        p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                             stdin=subprocess.DEVNULL)
        start = time.time()
        while wait_output and time.time() - start < 300 and p.poll() is None:
            if any(glob.glob(os.path.join(out_dir, "**", "*." + e), recursive=True) for e in ("xdmf", "csv", "h5")):
                break
            time.sleep(0.1)
        time.sleep(delay)
        if p.poll() is not None:
            print(f"the run ended (exit {p.returncode}) before it could be interrupted: make it longer")
            return 1
        before = glob.glob(os.path.join(tempfile.gettempdir(), f"dembridge_*_{p.pid}_*"))
        if expect_temp and not before:
            problems.append("no temporary file of the run existed when the signal was sent")
        p.send_signal(sig)
        try:
            _, err = p.communicate(timeout=120)
        except subprocess.TimeoutExpired:
            p.kill()
            print("the run did not stop within 120 s of the signal")
            return 1
        if sig == signal.SIGKILL:
            if p.returncode != -signal.SIGKILL:
                problems.append(f"exit code {p.returncode}, expected -9 (killed): {err[-400:]!r}")
            check_killed(out_dir, problems)
        else:
            if p.returncode != 128 + sig:
                problems.append(f"exit code {p.returncode}, expected {128 + sig}: {err[-400:]!r}")
            try:
                s = json.load(open(summary))
                if s.get("completed") is not False or not s.get("time_reached_s", 0) > 0:
                    problems.append(f"summary: {s}")
            except (OSError, ValueError) as e:
                problems.append(f"summary {summary}: {e}")
            check_outputs(out_dir, problems)
        left = glob.glob(os.path.join(tempfile.gettempdir(), f"dembridge_*_{p.pid}_*"))
        if left:
            problems.append(f"temporary files left: {left}")
        print(f"{os.path.basename(argv[0])}: stopped {time.time() - start:.1f} s after the start by "
              f"{signal.Signals(sig).name}: {err.strip().splitlines()[-1] if err.strip() else ''}")
    for pr in problems:
        print(pr)
    print(f"{len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
