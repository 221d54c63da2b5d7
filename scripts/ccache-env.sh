# Sourced by the build scripts (test.sh, test-asan.sh, render-example.sh) from the repository's root: compile
# through ccache when it is installed (scripts/install-deps.sh installs it), with the paths taken relative to
# the checkout, so that a clean clone elsewhere (CI) finds what an earlier build of the same sources compiled.
# Sets DELTAGI_LAUNCHER, the arguments for cmake's configure step.
DELTAGI_LAUNCHER=()
if command -v ccache >/dev/null 2>&1; then
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
  # The precompiled header of the tests (tests/CMakeLists.txt) is cached only with these.
  export CCACHE_SLOPPINESS="${CCACHE_SLOPPINESS:-pch_defines,time_macros,include_file_mtime,include_file_ctime}"
  DELTAGI_LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
