#!/usr/bin/env bash
# Installs deltagi's dependencies from Debian 12 packages (run as root); apt-get runs only when one of them is
# missing.
#   scripts/install-deps.sh [--render] [PACKAGE ...]
# Without --render: every build and test dependency, and the packages named as arguments (scripts/fuzz.sh adds
# its own), then the browser test's one npm package (tests/web: playwright-core, at the version of its
# package-lock.json; it drives Debian's chromium and downloads no browser). With --render: only what building
# the command line and rendering need (scripts/render-example.sh).
set -euo pipefail
render_only=0
if [ "${1:-}" = --render ]; then
  render_only=1
  shift
fi
# The library and the command line (the web server of `deltagi serve` and the MP4 output included).
packages=(
  cmake ninja-build g++ pkg-config ccache
  libembree-dev libtbb-dev libassimp-dev libopenexr-dev libpng-dev libturbojpeg0-dev libstb-dev
  nlohmann-json3-dev libcli11-dev libfmt-dev libglm-dev libxxhash-dev
  libavcodec-dev libavformat-dev libavutil-dev libswscale-dev libavdevice-dev libapriltag-dev
  libboost-dev
)
if [ "$render_only" = 0 ]; then
  # The tests, the microbenchmarks, the Python module and the browser test.
  packages+=(
    openimageio-tools libgtest-dev libgmock-dev libbenchmark-dev assimp-testmodels
    pybind11-dev python3-dev python3-numpy python3-pytest
    jq chromium
    "$@"
  )
  # Node.js: Debian's nodejs and npm, unless a node with npm is there already (NodeSource's nodejs package
  # holds npm and conflicts with Debian's).
  if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
    packages+=(nodejs npm)
  fi
else
  packages+=("$@")
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update
  apt-get install -y --no-install-recommends "${missing[@]}"
fi
[ "$render_only" = 1 ] && exit 0

# playwright-core for the browser test (tests/web/live_session.mjs), when it is not installed at the locked
# version already.
web="$(cd "$(dirname "$0")/../tests/web" && pwd)"
if command -v node >/dev/null 2>&1 && command -v npm >/dev/null 2>&1 &&
   [ "$(node -p "try { require('$web/node_modules/playwright-core/package.json').version } catch { '' }")" != \
     "$(node -p "require('$web/package-lock.json').packages['node_modules/playwright-core'].version")" ]; then
  PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --prefix "$web" --no-audit --no-fund
fi
