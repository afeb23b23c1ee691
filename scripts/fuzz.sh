#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (AddressSanitizer + UBSan, coverage everywhere) into build-fuzz/
# and fuzzes each for SECONDS (default 600) from its checked-in seed corpus (tests/fuzz/corpus/<target>).
# New interesting inputs go to build-fuzz/tests/fuzz/found-<target>/, crashes to crash-<target>-*; copy a
# crash into tests/fuzz/corpus/<target>/ once fixed: the ordinary build replays it (fuzz_replay_<target>).
# Usage: [SECONDS=600] [TARGETS="map_file config ..."] scripts/fuzz.sh
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${BUILD_DIR:-$root/build-fuzz}"
seconds="${SECONDS_PER_TARGET:-${SECONDS_LIMIT:-600}}"
targets="${TARGETS:-map_file config fingerprint image_header lcm_messages lcm_log firmware_link motion_input}"
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ "${launcher[@]}" \
  -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DTOPOSLAM_FUZZ=ON -DTOPOSLAM_FUZZ_SECONDS="$seconds" >/dev/null
build_targets=()
for t in $targets; do build_targets+=(--target "fuzz_$t"); done
cmake --build "$build" -j "$(nproc)" "${build_targets[@]}"
status=0
for t in $targets; do
  echo "== fuzz_$t for ${seconds}s"
  ctest --test-dir "$build" -R "^fuzz_${t}\$" --output-on-failure || status=1
done
exit $status
