#!/usr/bin/python3
"""Checks README.md's picture and caption against the run they come from.

scripts/impact_picture.sh renders docs/impact.png from the main demo's run
and writes the figures the picture shows beside it, in docs/impact.json.
Given the figures of a fresh run of the same command (RUN_FIGURES, written
the same way), this checks that
- docs/impact.json holds the fresh run's figures: the runs are the same bit
  for bit on any machine and thread count, so a difference means the
  picture is stale (re-render it: sh scripts/impact_picture.sh);
- the caption under the picture in README.md states the same spheres,
  striking and residual velocity ("N bonded spheres", "strikes ... at V
  m/s", "leaves it at R m/s").

Usage: check_picture.py SOURCE_DIR RUN_FIGURES
Prints one line per problem and exits 1 if there is any.
"""
import json
import re
import sys
from pathlib import Path


def caption(readme: str) -> str:
    """The italic paragraph right under docs/impact.png."""
    after = readme.split("(docs/impact.png)", 1)[1].lstrip("\n")
    return after.split("\n\n", 1)[0].replace("\n", " ")


def stated(text: str):
    """The figures a caption states, or None for those it does not."""
    def number(pattern):
        m = re.search(pattern, text)
        return None if m is None else int(m.group(1).replace(",", ""))
    return {"particles": number(r"([\d,]+) bonded spheres"),
            "striking_velocity_m_s": number(r"strikes .*? at (\d+) m/s"),
            "residual_velocity_m_s": number(r"leaves it at (\d+) m/s")}


def main(argv):
    if len(argv) != 2:
        raise SystemExit(__doc__)
    src, fresh = Path(argv[0]), json.loads(Path(argv[1]).read_text())
    shipped = json.loads((src / "docs" / "impact.json").read_text())
    problems = [f"docs/impact.json: {k} = {shipped.get(k)}, the run gives {v} (re-render the picture)"
                for k, v in fresh.items() if shipped.get(k) != v]
    for k, v in stated(caption((src / "README.md").read_text())).items():
        if v is None:
            problems.append(f"README.md: the caption does not state {k}")
        elif v != fresh[k]:
            problems.append(f"README.md: the caption says {k} = {v}, the run gives {fresh[k]}")
    for p in problems:
        print(p)
    print(f"picture and caption against the run: {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
