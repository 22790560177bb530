#!/usr/bin/python3
"""Feeds an executable bad values for every option its --help declares.

Each option of dembridge's programs states what it allows in its help
(demos/common/options.h): "[allowed: (0, 10]; 0 = automatic]" for a number,
"[allowed: a | b]" for a choice, "[input file]", "[output folder]",
"[output file]", "[program]". This script reads that back and tries, option by option:
- numbers: nan, inf, -inf, a word, an empty string, and the values just
  outside the declared interval (0, -1 and 1e300 where they are outside);
- choices: a word that is not one, an empty string;
- input files: a missing one, a folder, an empty file, a malformed file;
- output folders and files: a place that cannot be created.
Every run must exit with a non-zero code (not a signal: no crash), print an
"error:" line naming the option (or, for a malformed file, the file), and
stop within the time limit. An option with no declaration fails the test.

Usage: bad_input.py EXE [--skip OPTION ...]
Prints one line per failure and a summary line; exits 1 on any failure.
"""
import math
import os
import re
import subprocess
import sys
import tempfile

BLOCK = re.compile(r"^\s+(?:-\w,)?(--[\w-]+)")
INTERVAL = re.compile(r"\[allowed: ([\(\[])([^,\]]+), ([^\]\)]+)([\)\]])(?:; (\S+) = [^\]]*)?\]")
CHOICE = re.compile(r"\[allowed: ([\w.-]+(?: \| [\w.-]+)+)\]")
SKIP_ALWAYS = {"--help"}


def options(exe):
    """(name, help text) of each option."""
    text = subprocess.run([exe, "--help"], capture_output=True, text=True, timeout=60).stdout
    blocks, name = [], None
    for line in text.splitlines():
        m = BLOCK.match(line)
        if m:
            name = m.group(1)
            blocks.append([name, line])
        elif name and line.startswith(" "):
            blocks[-1][1] += " " + line.strip()
    return blocks


def number(s):
    return float(s.replace("inf", "Infinity")) if s not in ("inf", "-inf") else float(s)


def numeric_bad_values(m, integer):
    lo_open, lo, hi, hi_open, special = m.group(1) == "(", number(m.group(2)), number(m.group(3)), \
        m.group(4) == ")", m.group(5)
    special = float(special) if special is not None else None

    def allowed(v):
        if special is not None and v == special:
            return True
        return (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)

    bad = ["nan", "inf", "-inf", "abc", ""]
    candidates = [0.0, -1.0, 1e300]
    if math.isfinite(lo):
        candidates += [lo - max(1.0, abs(lo))] + ([lo] if lo_open else [])
    if math.isfinite(hi):
        candidates += [hi + max(1.0, abs(hi))] + ([hi] if hi_open else [])
    if integer:
        candidates.append(1.5)
    for v in candidates:
        if not allowed(v) and repr(v) not in bad:
            bad.append(repr(int(v)) if v.is_integer() and abs(v) < 1e18 else repr(v))
    return bad


def cases(name, help_text, tmp):
    """(argument list, what the error must name) for each bad value of an option."""
    if name in SKIP_ALWAYS:
        return []
    m = INTERVAL.search(help_text)
    if m:
        integer = " INT" in help_text or " UINT" in help_text or "[INT" in help_text
        return [([name, v], name) for v in numeric_bad_values(m, integer)]
    if CHOICE.search(help_text):
        return [([name, "no-such-choice"], name), ([name, ""], name)]
    if "[input file]" in help_text:
        empty = os.path.join(tmp, "empty.txt")
        open(empty, "w").close()
        malformed = os.path.join(tmp, "malformed.txt")
        with open(malformed, "w") as f:
            f.write("this is { not what any reader expects\n1 2\n")
        missing = os.path.join(tmp, "no_such_file.json")
        return [([name, missing], name), ([name, tmp], name), ([name, empty], name),
                ([name, malformed], (name, malformed))]
    if "[program]" in help_text:
        return [([name, "no-such-program-here"], name), ([name, tmp], name)]
    if "[output folder]" in help_text or "[output file]" in help_text:
        return [([name, "/proc/no_such_dir/x"], name)]
    return None  # undeclared


def main(argv):
    if not argv:
        raise SystemExit(__doc__)
    exe, skip = os.path.abspath(argv[0]), set()
    if "--skip" in argv:
        skip = set(argv[argv.index("--skip") + 1:])
    failures, runs = [], 0
    with tempfile.TemporaryDirectory() as tmp:
        for name, help_text in options(exe):
            if name in skip:
                continue
            if not re.match(r"\s+(?:-\w,)?" + re.escape(name) + r"\s+\[?[A-Z]{3,}", help_text):
                continue  # a flag: no value to get wrong
            cs = cases(name, help_text, tmp)
            if cs is None:
                failures.append(f"{name}: its help declares nothing allowed (demos/common/options.h)")
                continue
            for args, must_name in cs:
                runs += 1
                try:
                    r = subprocess.run([exe] + args, capture_output=True, text=True, timeout=120,
                                       stdin=subprocess.DEVNULL, cwd=tmp)
                except subprocess.TimeoutExpired:
                    failures.append(f"{' '.join(args)!r}: still running after 120 s")
                    continue
                names = must_name if isinstance(must_name, tuple) else (must_name,)
                errors = [l for l in r.stderr.splitlines() if l.startswith("error:")]
                if r.returncode == 0:
                    failures.append(f"{args!r}: exit code 0 (accepted)")
                elif r.returncode < 0 or r.returncode >= 128:
                    failures.append(f"{args!r}: killed by a signal (exit {r.returncode}): {r.stderr[-300:]!r}")
                elif not any(any(n in l for n in names) for l in errors):
                    failures.append(f"{args!r}: no 'error:' line naming {' or '.join(names)}: {r.stderr[-300:]!r}")
    for f in failures:
        print(f)
    print(f"{os.path.basename(exe)}: {runs} bad inputs tried, {len(failures)} failures")
    if runs == 0:
        print("no option found: the --help format or this parser changed")
        return 1
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
