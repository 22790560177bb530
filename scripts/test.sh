#!/bin/sh
# Installs missing Debian packages, builds everything and runs the whole test
# suite through CTest. Idempotent and quick when nothing changed.
set -eu
cd "$(dirname "$0")/.."
sh scripts/install-deps.sh --test
[ -f build/CMakeCache.txt ] || cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
cd build
# one OpenMP thread per test: CTest already runs one test per core
OMP_NUM_THREADS=1 ctest --output-on-failure -j"$(nproc)"
cd ..
# the unit tests again under AddressSanitizer and UndefinedBehaviorSanitizer
sh scripts/sanitize.sh
