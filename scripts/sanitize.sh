#!/usr/bin/env bash
# Builds woven and its unit and CLI tests with AddressSanitizer and
# UndefinedBehaviorSanitizer (WOVEN_SANITIZE=ON, gcc) into build-asan/ and runs ctest
# there. Any sanitizer report fails the test that triggered it: UBSan aborts
# (-fno-sanitize-recover), ASan aborts on errors and, at exit, on leaks. The only
# suppressions are the MPI runtime's own allocations (scripts/lsan-mpi.supp), and the
# tests' mpirun-launched ranks skip the leak check (the runtime unloads its plug-ins
# first); the suite runs clean with OpenMP, OpenBLAS and the image libraries as they are.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DWOVEN_SANITIZE=ON >/dev/null
cmake --build build-asan -j2
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export LSAN_OPTIONS="suppressions=$PWD/scripts/lsan-mpi.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
cd build-asan && ctest --output-on-failure -j2
