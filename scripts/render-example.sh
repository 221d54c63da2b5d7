#!/usr/bin/env bash
# Installs what rendering needs, builds the command line and renders examples/cornell-box.json to
# out/cornell-box.png (AOVs and timings in out/cornell-box-aov/). Extra arguments go to `deltagi render`, e.g.
# --threads 2. The tests need more packages: scripts/install-deps.sh, then scripts/test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1; then
  sudo scripts/install-deps.sh --render
else
  scripts/install-deps.sh --render
fi

source scripts/ccache-env.sh
# Only the command line: the tests, the microbenchmarks and the Python module need the packages left out.
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DDELTAGI_BUILD_TESTS=OFF -DDELTAGI_BUILD_BENCHMARKS=OFF \
  -DDELTAGI_BUILD_PYTHON=OFF "${DELTAGI_LAUNCHER[@]}"
cmake --build build -j2 --target deltagi
mkdir -p out
build/deltagi render examples/cornell-box.json -o out/cornell-box.png --aov out/cornell-box-aov "$@"
