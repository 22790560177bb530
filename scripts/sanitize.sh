#!/bin/sh
# Builds the test programs with AddressSanitizer and UndefinedBehaviorSanitizer
# in their own folder (build-asan) and runs them side by side: unit_tests and
# dem_tests (each in two parts) without their longest cases ([long], and the
# identification's runs, [calibrate]), which repeat code paths the other cases
# run. These cases carry the CTest label "sanitized": scripts/test.sh runs them
# here only. Any report stops the run with a non-zero exit. On 2 cores: about
# 3 minutes to build from scratch, 2 to run.
set -eu
cd "$(dirname "$0")/.."
sh scripts/install-deps.sh
# the modules (the code under test, where the tests spend their time) at -O2,
# the tests and the demos' cases at -O0 (DEMBRIDGE_MODULE_FLAGS): the kernels
# run 1.7 times faster than at -O1 (the undamped assembly's 10,000 steps)
# UBSan without its vptr, alignment and null checks: instrumenting every load
# for them doubles a translation unit's compile time and slows the kernels;
# a null dereference faults and ASan reports it with its stack, and x86-64
# loads misaligned data (the code reads no type through a pointer to another,
# bytes apart)
flags="-O0 -g1 -fsanitize=address,undefined -fno-sanitize=vptr,alignment,null -fno-omit-frame-pointer"
# leaks off: MPI and PETSc keep allocations until exit by design
export ASAN_OPTIONS=detect_leaks=0:halt_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# -Bsymbolic-functions: a library calls its own copies of the inline
# functions it uses (std::array's operator[], the force laws of
# link_kernel.h), not the test program's -O0 ones, which the dynamic linker
# would otherwise bind first (10 to 30 times slower than the modules' own).
# No link-time optimisation: its code generation runs on one core at the
# link. Configured each time: an older build-asan takes these flags too.
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=None \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_C_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined -Wl,-Bsymbolic-functions" -DDEMBRIDGE_IPO=OFF \
  -DDEMBRIDGE_MODULE_FLAGS=-O2 > /dev/null
cmake --build build-asan -j"$(nproc)" --target unit_tests dem_tests
export OMP_NUM_THREADS=1
# four processes on the two cores, of about equal work: the unit tests of
# the bridge, the other unit tests, the DE samples, the other DE tests
./build-asan/bin/unit_tests "[bridge]~[long]" > build-asan/unit_bridge.log 2>&1 &
bridge=$!
./build-asan/bin/unit_tests "~[bridge]~[long]" > build-asan/unit_tests.log 2>&1 &
unit=$!
./build-asan/bin/dem_tests "[sample]~[calibrate]~[long]" > build-asan/dem_samples.log 2>&1 &
samples=$!
./build-asan/bin/dem_tests "~[sample]~[calibrate]~[long]" > build-asan/dem_tests.log 2>&1 &
dem=$!
status=0
for job in "unit_bridge $bridge" "unit_tests $unit" "dem_samples $samples" "dem_tests $dem"; do
  set -- $job
  if wait "$2"; then
    echo "sanitizers: $1: $(tail -n 2 build-asan/$1.log | head -n 1)"
  else
    echo "sanitizers: $1 FAILED (build-asan/$1.log):"
    tail -n 60 "build-asan/$1.log"
    status=1
  fi
done
exit $status
