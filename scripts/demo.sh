#!/bin/sh
# Installs missing Debian packages, builds the main demo and runs it: a
# 20 mm steel ogive perforating a reinforced-concrete slab (0.6 x 0.6 m,
# 40 mm thick) at 300 m/s, the concrete round the impact discrete elements
# coupled to reinforced-concrete shells over the rest (the shipped scenario
# `small-slab`: 5,107 spheres and 1,024 shell nodes, about 5 s on 2 cores).
# Idempotent: a second call rebuilds nothing and only reruns the demo.
# Extra arguments go to the demo (e.g. --set projectile.velocity_m_s=400,
# or --model de for the slab all in spheres).
set -eu
cd "$(dirname "$0")/.."
sh scripts/install-deps.sh
[ -f build/CMakeCache.txt ] || cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target impact
./build/bin/impact small-slab --output out/slab --summary out/slab/summary.json "$@"
echo "Results in out/slab: particles.xdmf (ParaView: spheres with damage, cracks, projectile),"
echo "  shell.xdmf (the shells' deflection), bars.xdmf, history.png and history.csv, summary.json"
