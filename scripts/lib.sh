# Shared by scripts/test and scripts/serve: configure and build in build/ with Ninja and ccache.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${SPORTSIM_BUILD_DIR:-$root/build}
export CCACHE_BASEDIR=$root
export CCACHE_DIR=${CCACHE_DIR:-${HOME:-/tmp}/.cache/ccache}

configure() {
  if [ ! -f "$build_dir/build.ninja" ]; then
    cmake -S "$root" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=${SPORTSIM_BUILD_TYPE:-Release} "$@"
  fi
}
