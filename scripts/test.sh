#!/usr/bin/env bash
# Sets up, builds and runs the whole test suite: a Release build, then (in CI, or with
# TOPOSLAM_SANITIZERS=1) a second build under AddressSanitizer + UndefinedBehaviorSanitizer.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"

scripts/setup.sh
jobs="$(nproc)"

echo "== release build and tests"
BUILD_TYPE=Release scripts/build.sh "$root/build" -DTOPOSLAM_WERROR=ON
ctest --test-dir "$root/build" --output-on-failure -j "$jobs" ${CTEST_ARGS:-}

if [ "${CI:-}" = "true" ] || [ "${TOPOSLAM_SANITIZERS:-0}" = "1" ]; then
  echo "== address + undefined sanitizer build and tests"
  BUILD_TYPE=RelWithDebInfo scripts/build.sh "$root/build-asan" -DTOPOSLAM_SANITIZE=address,undefined \
    -DTOPOSLAM_WERROR=ON
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir "$root/build-asan" --output-on-failure -j "$jobs" -LE "slow|vm|browser" ${CTEST_ARGS:-}
fi
