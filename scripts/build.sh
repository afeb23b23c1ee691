#!/usr/bin/env bash
# Configures and builds toposlam. Usage: [BUILD_TARGETS="t1 t2"] scripts/build.sh [BUILD_DIR] [extra cmake args...]
# (BUILD_TARGETS empty: everything.)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
shift || true
# The generator: CMAKE_GENERATOR if set (CI builds its Release tree with "Unix Makefiles", so both
# generators stay proven), else the one a configured tree already has, else Ninja when present.
generator=()
if [ -z "${CMAKE_GENERATOR:-}" ] && [ ! -f "$build/CMakeCache.txt" ] && command -v ninja >/dev/null; then
  generator=(-G Ninja)
fi
# ccache (a build package of scripts/setup.sh) when present: a rebuild, another clone or the sanitizer
# builds of CI reuse what was compiled before. Paths under the checkout are hashed relative to it.
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$(dirname "$root")}"
fi
cmake -S "$root" -B "$build" "${generator[@]}" "${launcher[@]}" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" "$@" >/dev/null
targets=()
for t in ${BUILD_TARGETS:-}; do targets+=(--target "$t"); done
cmake --build "$build" -j "$(nproc)" "${targets[@]}"
