#!/bin/sh
# Installs missing Debian packages, builds the main demo and runs it: a
# rigid ogive projectile perforating a slab of discrete-element concrete at
# 400 m/s (the shipped scenario `small`, at 1 mm mean sphere radius: 25,000
# spheres, about half a minute on 2 cores).
# Idempotent: a second call rebuilds nothing and only reruns the demo.
# Extra arguments go to the demo (e.g. --set projectile.velocity_m_s=600).
set -eu
cd "$(dirname "$0")/.."
sh scripts/install-deps.sh
[ -f build/CMakeCache.txt ] || cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target impact
./build/bin/impact small --set target.mean_radius_m=0.001 --output out/impact \
  --summary out/impact/summary.json "$@"
echo "Results in out/impact: particles.xdmf (ParaView: spheres with damage, cracks, projectile),"
echo "  history.png and history.csv (projectile speed, depth, force), summary.json"
