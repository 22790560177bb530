#!/bin/sh
# Renders docs/coupled-bar.png, the bar's picture in docs/validation.md, from the bar demo's
# own output: the coupled bar (shells and spheres) in static bending, seen
# from the side. Builds the bar demo first if it is missing.
#   sh scripts/picture.sh                      # default sizes, into docs/
#   sh scripts/picture.sh DIR PNG [bar options] # e.g. --mean-radius 0.02
# BAR=path picks another bar executable (the test suite sets it).
set -eu
cd "$(dirname "$0")/.."
dir=out/picture
png=docs/coupled-bar.png
if [ $# -ge 1 ]; then dir=$1; shift; fi
if [ $# -ge 1 ]; then png=$1; shift; fi
bar=${BAR:-build/bin/bar}
if [ ! -x "$bar" ]; then
  sh scripts/install-deps.sh
  [ -f build/CMakeCache.txt ] || cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
  cmake --build build -j"$(nproc)" --target bar
fi
"$bar" --model coupled --load bending --regime static --output "$dir" \
  --summary "$dir/summary.json" "$@"
/usr/bin/python3 scripts/render_picture.py "$dir" "$png"
