#!/usr/bin/env bash
# Builds deltagi (Release) and runs every test. This is the README's test command; .ci/run calls it too, so
# the two cannot drift apart. Dependencies: scripts/install-deps.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release && cmake --build build -j2 && ctest --test-dir build --output-on-failure -j2
