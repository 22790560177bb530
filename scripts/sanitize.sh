#!/bin/sh
# Builds the test programs with AddressSanitizer and UndefinedBehaviorSanitizer
# in their own folder (build-asan) and runs them: unit_tests whole, dem_tests
# without the identification's long runs ([calibrate]). Any report stops the
# run with a non-zero exit. About 12 minutes to build and 5 to run on 2 cores.
set -eu
cd "$(dirname "$0")/.."
sh scripts/install-deps.sh
flags="-fsanitize=address,undefined -fno-omit-frame-pointer"
[ -f build-asan/CMakeCache.txt ] || cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_C_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined"
cmake --build build-asan -j"$(nproc)" --target unit_tests dem_tests
# leaks off: MPI and PETSc keep allocations until exit by design
export ASAN_OPTIONS=detect_leaks=0:halt_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
OMP_NUM_THREADS=1 ./build-asan/bin/unit_tests
OMP_NUM_THREADS=1 ./build-asan/bin/dem_tests "~[calibrate]"
