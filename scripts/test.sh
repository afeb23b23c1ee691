#!/usr/bin/env bash
# Sets up, builds and runs the whole test suite: a Release build, then (in CI, or with
# TOPOSLAM_SANITIZERS=1) a second build under AddressSanitizer + UndefinedBehaviorSanitizer and a third,
# smaller one under ThreadSanitizer for the code that owns threads (pipeline, queues, worker pool).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"

scripts/setup.sh --test  # build, runtime and the test-only tools (browser, VM)
jobs="$(nproc)"
# Each stage's start, with the minutes since the script began: CI's budget is 45 minutes on 2 cores.
stage() { echo "== $* [$(date +%T), $((SECONDS / 60)) min ${SECONDS}s in]"; }

stage "release build and tests"
# A fresh Release tree is built with CMake's default generator (Unix Makefiles) and the sanitizer trees with
# Ninja: both generators are proven from a clean tree on every run. A tree already configured keeps its own.
release_generator=()
[ -f "$root/build/CMakeCache.txt" ] || release_generator=(env CMAKE_GENERATOR="Unix Makefiles")
BUILD_TYPE=Release "${release_generator[@]}" scripts/build.sh "$root/build" -DTOPOSLAM_WERROR=ON
stage "release tests"
ctest --test-dir "$root/build" --output-on-failure -j "$jobs" ${CTEST_ARGS:-}

if [ "${CI:-}" = "true" ] || [ "${TOPOSLAM_SANITIZERS:-0}" = "1" ]; then
  # Sanitizer builds at -O1 with line tables only (-g1): what the sanitizers' own docs advise, enough for
  # symbolised stack traces, and half the compile time of -O2 -g (measured on file_sources.cpp: 26 s
  # against 56 s), which keeps .ci/run inside its budget on 2 cores.
  sanitizer_flags=(-DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG")
  stage "address + undefined sanitizer build and tests"
  BUILD_TYPE=RelWithDebInfo scripts/build.sh "$root/build-asan" -DTOPOSLAM_SANITIZE=address,undefined \
    -DTOPOSLAM_WERROR=ON "${sanitizer_flags[@]}"
  stage "address + undefined sanitizer tests"
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir "$root/build-asan" --output-on-failure -j "$jobs" -LE "slow|vm|browser" ${CTEST_ARGS:-}

  stage "3-minute soak of toposlamd under ASan + UBSan (scripts/soak.sh; no drops, flat RSS, no leaks)"
  # The simulator's own 5 fps played in real time: ASan at -O1 keeps up with it on 2 cores.
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 MINUTES=3 FPS=5 SAMPLE_S=5 \
    scripts/soak.sh "$root/build-asan"

  stage "thread sanitizer build and tests (pipeline, queues, worker pool, the map encoded off the topology thread)"
  # Only the targets whose code owns threads: OpenCV's own TBB threads are not instrumented, so TSan
  # cannot judge code that runs inside OpenCV's parallel loops (docs/architecture.md, "Sanitizers").
  BUILD_TYPE=RelWithDebInfo BUILD_TARGETS="test_pipeline test_core test_topology" \
    scripts/build.sh "$root/build-tsan" -DTOPOSLAM_SANITIZE=thread -DTOPOSLAM_WERROR=ON "${sanitizer_flags[@]}"
  # Tests of the targets not built here are registered as *_NOT_BUILT (Catch2's discovery) or are plain
  # add_test() commands of unbuilt executables or files (fuzz corpus replays, the firmware C encoder, the
  # Python reader's unit test, which needs the generated Python package, the LCM fragment listener's
  # loopback test, whose binary is not built here): leave them out.
  TSAN_OPTIONS=halt_on_error=1 ctest --test-dir "$root/build-tsan" --output-on-failure -j "$jobs" \
    -E "_NOT_BUILT|^fuzz_replay_|^firmware-host-wheel-link-encoder$|^test_platform_udpm_reader$|^lcm_fragment_monitor_loopback$" \
    -LE "slow|vm|browser|e2e|cli" ${CTEST_ARGS:-}

  stage "libFuzzer targets, ${FUZZ_SECONDS:-20} s each (scripts/fuzz.sh; tests/fuzz/)"
  # A fourth build (clang, ASan + UBSan, coverage): about 6 min with a warm ccache on 2 cores under load,
  # then each target from its checked-in corpus. A crash fails CI; copy it into the corpus once fixed.
  SECONDS_PER_TARGET="${FUZZ_SECONDS:-20}" BUILD_DIR="$root/build-fuzz" scripts/fuzz.sh
fi
stage "done"
