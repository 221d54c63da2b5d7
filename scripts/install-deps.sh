#!/usr/bin/env bash
# Installs every build and test dependency of deltagi from Debian 12 packages (run as root), and the packages
# named as arguments (scripts/fuzz.sh adds its own); apt-get runs only when one of them is missing.
#   scripts/install-deps.sh [PACKAGE ...]
set -euo pipefail
packages=(
  cmake ninja-build g++ pkg-config
  libembree-dev libtbb-dev libassimp-dev libopenimageio-dev openimageio-tools
  nlohmann-json3-dev libcli11-dev libfmt-dev libglm-dev
  libavcodec-dev libavformat-dev libavutil-dev libswscale-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  pybind11-dev python3-dev python3-numpy python3-pytest
  jq
  "$@"
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update
  apt-get install -y --no-install-recommends "${missing[@]}"
fi
