#!/bin/sh
# Installs missing Debian packages, builds the main demo and runs it: the
# paper's validation bar, coupled shells + discrete elements, dynamic tension
# (end displacement ramped, then released; free vibration).
# Idempotent: a second call rebuilds nothing and only reruns the demo.
# Extra arguments go to the demo (e.g. --load bending, --model de, --compare).
set -eu
cd "$(dirname "$0")/.."
sh scripts/install-deps.sh
[ -f build/CMakeCache.txt ] || cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target bar
./build/bin/bar --model coupled --load tension --regime dynamic --output out/bar \
  --summary out/bar/summary.json "$@"
echo "Results: out/bar/shell.xdmf and particles.xdmf (ParaView), history.csv, summary.json"
