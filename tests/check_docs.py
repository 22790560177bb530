#!/usr/bin/python3
"""Checks that the commands README.md, docs/*.md, docs/studies/*.md and
tests/README.md show still exist.

Every line of a ```sh block, and every inline `build/bin/...` span, is a
command. Its program must exist: `build/bin/NAME` an executable of the build
(BIN), `sh scripts/X`, `scripts/X` or `/usr/bin/python3 scripts/X` a file of
the source tree, or one of a few system tools. For build/bin programs each
`--option` on the line must appear in the program's --help, so a renamed or
removed option fails here.

Usage: check_docs.py SOURCE_DIR BIN_DIR
Prints one line per problem and exits 1 if there is any.
"""
import re
import shlex
import subprocess
import sys
from pathlib import Path

SYSTEM_TOOLS = {"cmake", "ctest", "apt-get", "git", "cd", "pvpython", "paraview", "mpirun", "export"}
ENV_ASSIGNMENT = re.compile(r"^[A-Z_][A-Z0-9_]*=\S*$")


def commands(md: Path):
    """(line number, command) for each command the page shows."""
    in_sh = False
    for no, line in enumerate(md.read_text().splitlines(), 1):
        stripped = line.strip()
        if stripped.startswith("```"):
            in_sh = not in_sh and stripped[3:].strip() in ("sh", "bash", "shell", "console")
            continue
        if in_sh:
            cmd = stripped.split(" #")[0].strip()
            if cmd and not cmd.startswith("#"):
                yield no, cmd
        else:
            for span in re.findall(r"`([^`]+)`", line):
                if span.startswith("build/bin/") and span != "build/bin/":  # not the folder itself
                    yield no, span


def help_text(exe: Path, cache={}):
    if exe not in cache:
        r = subprocess.run([str(exe), "--help"], capture_output=True, text=True, timeout=60)
        cache[exe] = r.stdout + r.stderr
    return cache[exe]


def check(cmd: str, src: Path, bin_dir: Path):
    """Problems with one command (empty if none)."""
    try:
        words = shlex.split(cmd)
    except ValueError as e:
        return [f"cannot parse: {e}"]
    while words and ENV_ASSIGNMENT.match(words[0]):
        words.pop(0)
    if not words:
        return []
    prog = words[0]
    if prog in ("sh", "bash", "/usr/bin/python3", "python3") and len(words) > 1:
        return [] if (src / words[1]).is_file() else [f"{words[1]} does not exist"]
    if prog.startswith("scripts/"):
        return [] if (src / prog).is_file() else [f"{prog} does not exist"]
    if prog.startswith("build/bin/"):
        exe = bin_dir / prog[len("build/bin/"):]
        if not exe.is_file():
            return [f"{prog}: no such executable in the build"]
        text = help_text(exe)
        return [f"{prog} has no option {w.split('=')[0]}" for w in words[1:]
                if w.startswith("--") and not re.search(r"(?<![\w-])" + re.escape(w.split("=")[0])
                                                        + r"(?![\w-])", text)]
    if prog in SYSTEM_TOOLS:
        return []
    return [f"'{prog}' is neither build/bin/NAME, a script of the tree nor a known tool"]


def main(argv):
    if len(argv) != 2:
        raise SystemExit(__doc__)
    src, bin_dir = Path(argv[0]), Path(argv[1])
    pages = ([src / "README.md"] + sorted((src / "docs").glob("*.md"))
             + sorted((src / "docs" / "studies").glob("*.md")) + [src / "tests" / "README.md"])
    problems, n = [], 0
    for md in pages:
        for no, cmd in commands(md):
            n += 1
            problems += [f"{md.relative_to(src)}:{no}: {p}  [{cmd}]" for p in check(cmd, src, bin_dir)]
    for p in problems:
        print(p)
    print(f"{n} commands in {len(pages)} pages, {len(problems)} problems")
    if n == 0:
        print("no command found: the pages or this check's parser changed")
        return 1
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
