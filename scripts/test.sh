#!/bin/sh
# Installs missing Debian packages, builds everything and runs the whole test
# suite through CTest. Idempotent and quick when nothing changed.
set -eu
cd "$(dirname "$0")/.."
sh scripts/install-deps.sh --test
# configured again when it exists, to find the tools installed since (pvpython,
# which the test of ParaView's readers needs, after scripts/demo.sh configured
# the build without it)
if [ -f build/CMakeCache.txt ]; then
  cmake -S . -B build > /dev/null
else
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
fi
cmake --build build -j"$(nproc)"
cd build
# one OpenMP thread per test: CTest already runs one test per core. The
# Catch2 cases labelled "sanitized" are run once, by scripts/sanitize.sh
# below, under AddressSanitizer and UndefinedBehaviorSanitizer (a plain
# ctest runs them here too)
OMP_NUM_THREADS=1 ctest --output-on-failure -j"$(nproc)" -LE sanitized
cd ..
sh scripts/sanitize.sh
