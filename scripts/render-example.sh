#!/usr/bin/env bash
# Installs the dependencies, builds deltagi and renders examples/cornell-box.json to out/cornell-box.png
# (AOVs and timings in out/cornell-box-aov/). Extra arguments go to `deltagi render`, e.g. --threads 2.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1; then
  sudo scripts/install-deps.sh
else
  scripts/install-deps.sh
fi

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j2 --target deltagi
mkdir -p out
build/deltagi render examples/cornell-box.json -o out/cornell-box.png --aov out/cornell-box-aov "$@"
