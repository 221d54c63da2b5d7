#!/usr/bin/env bash
# Builds deltagi (Release) and runs every test. This is the README's test command; .ci/run calls it too, so
# the two cannot drift apart. Dependencies: scripts/install-deps.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ccache-env.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DDELTAGI_BUILD_TESTS=ON -DDELTAGI_BUILD_BENCHMARKS=ON \
  -DDELTAGI_BUILD_PYTHON=ON "${DELTAGI_LAUNCHER[@]}"
cmake --build build -j2
ctest --test-dir build --output-on-failure -j2
