#!/bin/sh
# Installs missing Debian packages, builds the main demo and runs it: a
# coupled shell / discrete-element cantilever in free bending vibration.
# Idempotent: a second call rebuilds nothing and only reruns the demo.
# Extra arguments go to the demo (e.g. --load axial, --fe solid).
set -eu
cd "$(dirname "$0")/.."
sh scripts/install-deps.sh
[ -f build/CMakeCache.txt ] || cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target coupled_cantilever
./build/bin/coupled_cantilever --load bending --output out/coupled_cantilever \
  --summary out/coupled_cantilever/summary.json "$@"
echo "Results: out/coupled_cantilever/shell.xdmf and particles.xdmf (ParaView), history.csv, summary.json"
