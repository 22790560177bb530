#!/bin/sh
# Installs missing Debian packages, builds the main demo and runs it.
# Idempotent: a second call rebuilds nothing and only reruns the demo.
# Extra arguments go to the demo (e.g. --load static-tip).
set -eu
cd "$(dirname "$0")/.."
sh scripts/install-deps.sh
[ -f build/CMakeCache.txt ] || cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target shell_cantilever
./build/bin/shell_cantilever --load bending --output out/shell_cantilever \
  --summary out/shell_cantilever/summary.json "$@"
echo "Results: out/shell_cantilever/cantilever.xdmf (ParaView), history.csv, summary.json"
