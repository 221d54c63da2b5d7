#!/usr/bin/env bash
# Builds deltagi with AddressSanitizer + UndefinedBehaviorSanitizer and with its assertions on (build-asan/: -O2,
# line tables for the reports, assert() and libstdc++'s _GLIBCXX_ASSERTIONS) and runs the tests with CTest, the
# bad-input corpus included. Any sanitizer finding or failed assertion aborts the process and fails its test.
# .ci/run calls it after scripts/test.sh. Dependencies: scripts/install-deps.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ccache-env.sh
# Leak checking stays on (tests/lsan.supp: leaks inside third-party libraries). A finding exits with status
# 86, which no test expects of deltagi, so that it cannot pass for an ordinary error exit.
export ASAN_OPTIONS="${ASAN_OPTIONS:-exitcode=86}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1:exitcode=86}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$PWD/tests/lsan.supp:print_suppressions=0}"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1" \
  -DDELTAGI_SANITIZE=ON -DDELTAGI_ASSERTIONS=ON -DDELTAGI_BUILD_BENCHMARKS=OFF "${DELTAGI_LAUNCHER[@]}"
cmake --build build-asan -j2
ctest --test-dir build-asan --output-on-failure -j2
