#!/bin/sh
# Installs missing Debian packages, builds everything and runs the whole test
# suite through CTest. Idempotent and quick when nothing changed.
set -eu
cd "$(dirname "$0")/.."
sh scripts/install-deps.sh
[ -f build/CMakeCache.txt ] || cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
cd build
ctest --output-on-failure -j"$(nproc)"
