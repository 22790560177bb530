#!/bin/sh
# Renders docs/impact.png, the picture on README.md, from the main demo's own
# output: the shipped coupled scenario `small-slab` (as scripts/demo.sh runs
# it): the DE core cut along the projectile's path at three moments, the
# slab from above and the shells' deflection. Builds the impact demo first
# if it is missing.
#   sh scripts/impact_picture.sh                        # into docs/impact.png
#   sh scripts/impact_picture.sh DIR PNG [impact options] # e.g. --set projectile.velocity_m_s=400
# IMPACT=path picks another impact executable (the test suite sets it).
set -eu
cd "$(dirname "$0")/.."
dir=out/impact_picture
png=docs/impact.png
if [ $# -ge 1 ]; then dir=$1; shift; fi
if [ $# -ge 1 ]; then png=$1; shift; fi
impact=${IMPACT:-build/bin/impact}
if [ ! -x "$impact" ]; then
  sh scripts/install-deps.sh
  [ -f build/CMakeCache.txt ] || cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
  cmake --build build -j"$(nproc)" --target impact
fi
"$impact" small-slab --plot 0 --output "$dir" --summary "$dir/summary.json" "$@"
/usr/bin/python3 scripts/render_slab.py "$dir" "$png"
