#!/usr/bin/env bash
# Cross-builds toposlam for arm64 (aarch64) with Debian's cross compiler and runs the tests under qemu-user.
# Run on demand (not by CI, not by scripts/test.sh). docs/arm64.md says what it does and what was measured.
#   scripts/cross-arm64.sh              install what is missing, build into build-arm64/, run the tests
#   scripts/cross-arm64.sh --no-tests   build only
#   scripts/cross-arm64.sh --bench      also `toposlam-bench fingerprint` under qemu (emulated timings)
#   scripts/cross-arm64.sh --no-install fail with a message instead of installing anything
# Environment: ARM64_BUILD_DIR (default build-arm64), TOPOSLAM_ARM64_SYSROOT (default ARM64_BUILD_DIR/sysroot),
# CTEST_ARGS (more ctest options), BUILD_TYPE (default Release).
#
# The arm64 libraries are Debian's arm64 packages unpacked into a sysroot folder, not installed with dpkg:
# libopencv-dev, liblcm-dev and libyaml-cpp-dev are not Multi-Arch: same on Debian 12, so apt can only
# install their :arm64 form by removing the native one (and the native build with it).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"

run_tests=1
run_bench=0
may_install=1
for arg in "$@"; do
  case "$arg" in
    --no-tests) run_tests=0 ;;
    --bench) run_bench=1 ;;
    --no-install) may_install=0 ;;
    -h|--help) sed -n '2,10s/^# \{0,1\}//p' "$0"; exit 0 ;;
    *) echo "cross-arm64: unknown option '$arg' (expected --no-tests, --bench, --no-install)" >&2; exit 2 ;;
  esac
done

build="${ARM64_BUILD_DIR:-$root/build-arm64}"
sysroot="${TOPOSLAM_ARM64_SYSROOT:-$build/sysroot}"
die() { echo "cross-arm64: error: $*" >&2; exit 1; }
say() { echo "cross-arm64: $*"; }
# Heavy steps yield to whoever else uses the machine.
low() { nice -n 19 "$@"; }

[ "$(uname -m)" = x86_64 ] || say "warning: this script is written for an x86_64 build host (this is $(uname -m))"
command -v apt-get >/dev/null || die "apt-get not found: the script needs Debian (12, bookworm) or a derivative"

# --- 1. Host tools: the cross compiler, qemu-user, and the build tools of scripts/setup.sh.
HOST_PACKAGES=(gcc-aarch64-linux-gnu g++-aarch64-linux-gnu qemu-user cmake ninja-build pkg-config
               liblcm-bin)  # liblcm-bin: lcm-gen runs on the build host
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
missing=()
for p in "${HOST_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  [ "$may_install" = 1 ] || die "missing host packages: ${missing[*]} (apt-get install ${missing[*]})"
  if [ -n "$SUDO" ] && ! command -v sudo >/dev/null; then
    die "missing host packages ${missing[*]}, and not root with no sudo to install them"
  fi
  say "installing host packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get -o DPkg::Lock::Timeout=600 update -qq ||
    die "apt-get update failed (no network or no Debian mirror?)"
  $SUDO apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends "${missing[@]}" ||
    die "could not install ${missing[*]}: see apt's message above"
fi
command -v aarch64-linux-gnu-g++ >/dev/null ||
  die "aarch64-linux-gnu-g++ not on PATH after installing g++-aarch64-linux-gnu"
if [ "$run_tests" = 1 ] || [ "$run_bench" = 1 ]; then
  command -v qemu-aarch64 >/dev/null || command -v qemu-aarch64-static >/dev/null ||
    die "qemu-aarch64 not on PATH (apt-get install qemu-user): needed to run the arm64 tests"
fi

# --- 2. The arm64 sysroot: the -dev packages of scripts/setup.sh (libraries and Catch2), in their arm64 form,
# with everything they depend on. A private apt state (its own package lists, cache and an empty dpkg status)
# resolves and downloads them; nothing is installed on this machine.
mapfile -t TARGET_PACKAGES < <(scripts/setup.sh --print | grep -E '^lib.*-dev$|^catch2$')
TARGET_PACKAGES+=(libc6-dev libstdc++-12-dev)  # the arm64 C and C++ runtimes to link and run against
stamp="$sysroot/.toposlam-sysroot"
wanted="$(printf '%s\n' "${TARGET_PACKAGES[@]}")"
if [ -f "$stamp" ] && [ "$(sed -n '/^packages:/,$p' "$stamp" | tail -n +2)" = "$wanted" ]; then
  say "arm64 sysroot up to date: $sysroot ($(sed -n 's/^unpacked: //p' "$stamp") packages)"
else
  [ "$may_install" = 1 ] || die "no arm64 sysroot at $sysroot (run without --no-install to make it)"
  command -v dpkg-deb >/dev/null || die "dpkg-deb not found (package dpkg)"
  state="$build/apt"
  mkdir -p "$state/lists/partial" "$state/cache/archives/partial"
  : > "$state/status"
  apt_private=(-o Dir::State="$state" -o Dir::State::Lists="$state/lists" -o Dir::State::status="$state/status"
               -o Dir::Cache="$state/cache" -o APT::Architecture=arm64 -o APT::Architectures::=arm64
               -o Debug::NoLocking=1)
  if [ "$(id -u)" -eq 0 ]; then apt_private+=(-o APT::Sandbox::User=root); fi
  say "fetching the arm64 package lists (private apt state in $state)"
  low apt-get "${apt_private[@]}" update -qq ||
    die "apt-get update for arm64 failed: does the mirror in /etc/apt/sources.list(.d) carry arm64?"
  say "downloading ${TARGET_PACKAGES[*]} (arm64) and their dependencies"
  low apt-get "${apt_private[@]}" install -y -qq --download-only --no-install-recommends \
    "${TARGET_PACKAGES[@]}" || die "apt could not resolve or download the arm64 packages: see its message above"
  debs=("$state"/cache/archives/*.deb)
  [ -e "${debs[0]}" ] || die "apt downloaded no arm64 package into $state/cache/archives"
  say "unpacking ${#debs[@]} arm64 packages into $sysroot"
  rm -rf "$sysroot"
  mkdir -p "$sysroot"
  for deb in "${debs[@]}"; do
    low dpkg-deb -x "$deb" "$sysroot" || die "could not unpack $deb"
  done
  # Links that dpkg-deb leaves absolute (e.g. usr/lib/aarch64-linux-gnu/libz.so -> /lib/...) would point
  # into the build host: make them relative to the sysroot.
  while IFS= read -r -d '' link; do
    target="$(readlink "$link")"
    ln -sfn "$(realpath -m --relative-to="$(dirname "$link")" "$sysroot$target")" "$link"
  done < <(find "$sysroot" -type l -lname '/*' -print0)
  # What update-alternatives would do on an installed system: the BLAS and LAPACK that OpenCV links.
  multiarch="$sysroot/usr/lib/aarch64-linux-gnu"
  for alt in blas/libblas.so.3 lapack/liblapack.so.3; do
    [ -e "$multiarch/$alt" ] && [ ! -e "$multiarch/$(basename "$alt")" ] && ln -s "$alt" "$multiarch/$(basename "$alt")"
  done
  [ -d "$sysroot/usr/include/aarch64-linux-gnu" ] || die "the unpacked sysroot has no arm64 libc headers"
  { echo "unpacked: ${#debs[@]}"; echo "packages:"; echo "$wanted"; } > "$stamp"
  say "arm64 sysroot ready: ${#debs[@]} packages, $(du -sh "$sysroot" | cut -f1)"
fi

# --- 3. Configure and build. Same options as the native build (Release, warnings as errors); man pages
# off, since help2man would have to run the arm64 binaries.
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$(dirname "$root")}"
fi
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
mkdir -p "$build"
say "configuring $build"
low cmake -S "$root" -B "$build" "${generator[@]}" "${launcher[@]}" \
  -DCMAKE_TOOLCHAIN_FILE="$root/cmake/toolchains/aarch64-linux-gnu.cmake" \
  -DTOPOSLAM_ARM64_SYSROOT="$sysroot" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" -DTOPOSLAM_WERROR=ON \
  -DTOPOSLAM_HELP2MAN=OFF >"$build/configure.log" 2>&1 ||
  { tail -30 "$build/configure.log" >&2; die "cmake configure failed (whole log: $build/configure.log)"; }
say "building (nice 19, $(nproc) jobs)"
start=$(date +%s)
low cmake --build "$build" -j "$(nproc)" || die "the arm64 build failed: see the compiler's message above"
build_seconds=$(( $(date +%s) - start ))
file "$build/src/apps/toposlam/toposlam" 2>/dev/null | grep -q 'ARM aarch64' ||
  die "$build/src/apps/toposlam/toposlam is not an arm64 executable"
say "build done in ${build_seconds} s"

# --- 4. Tests under qemu-user. ctest runs each test executable through CMAKE_CROSSCOMPILING_EMULATOR
# (qemu-aarch64 -L sysroot). What cannot run that way is left out, each with its reason:
declare -A EXCLUDED_LABELS=(
  [vm]="boots an x86 kernel with a virtual camera in qemu-system (tests/vm): not an arm64 user-space test"
  [browser]="drives the host's chromium over WebDriver"
  [package]="builds and lints the Debian package (cpack, lintian) of the native build"
  [e2e]="end-to-end runs over LCM UDP multicast and helper scripts that start the binaries themselves"
  [fuzz]="fuzzers need clang's libFuzzer; the corpus replays run as fuzz_replay_*"
)
binfmt=0
for f in /proc/sys/fs/binfmt_misc/qemu-aarch64*; do [ -e "$f" ] && binfmt=1; done

if [ "$run_tests" = 1 ]; then
  labels="$(IFS='|'; echo "${!EXCLUDED_LABELS[*]}")"
  say "tests under qemu-user; left out, by label:"
  for l in "${!EXCLUDED_LABELS[@]}"; do echo "  $l: ${EXCLUDED_LABELS[$l]}"; done
  # ctest starts a test through qemu only when the test's command is one of our executables. A test whose
  # command is a shell or CMake script that starts build-arm64's binaries itself needs the kernel to run an
  # arm64 file, that is a binfmt_misc handler for aarch64 (qemu-user-static with binfmt-support, on a
  # machine where one may register it): without one, those tests are left out by name.
  excluded_names=""
  if [ "$binfmt" = 0 ]; then
    command -v python3 >/dev/null || die "python3 is needed to pick the tests that can run without binfmt_misc"
    excluded_names="$(ctest --test-dir "$build" --show-only=json-v1 | python3 -c '
import json, sys
build = sys.argv[1]
for test in json.load(sys.stdin)["tests"]:
    command = test.get("command") or []
    labels = next((p["value"] for p in test.get("properties", []) if p["name"] == "LABELS"), [])
    emulated = bool(command) and "qemu-aarch64" in command[0]
    # A script naming one of our binaries, or a test program labelled cli (it runs toposlam with system()).
    script = bool(command) and not emulated and any(build + "/" in part for part in command)
    spawner = emulated and "cli" in labels and any(part.startswith(build + "/tests/") for part in command[1:])
    if script or spawner:
        print(test["name"])
' "$build")"
    if [ -n "$excluded_names" ]; then
      echo "  by name, $(echo "$excluded_names" | wc -l) tests whose script or test program starts an arm64 binary itself (no binfmt_misc handler for aarch64 here):"
      echo "$excluded_names" | sed 's/^/    /' | paste -sd ' ' | fold -s -w 110 | sed 's/^ */    /'
    fi
  fi
  name_filter=()
  if [ -n "$excluded_names" ]; then
    # ctest's -E takes a regular expression: anchor each name and escape its dots (test names here are made
    # of letters, digits, '.', '_' and '-').
    name_filter=(-E "^($(echo "$excluded_names" | sed 's/\./\\./g' | paste -sd '|'))\$")
  fi
  # qemu runs the code 5-20 times slower than the host: scale the timeouts.
  log="$build/ctest-arm64.log"
  start=$(date +%s)
  set +e
  low ctest --test-dir "$build" -j "$(nproc)" --timeout-multiplier 4 -LE "^($labels)\$" "${name_filter[@]}" \
    --output-on-failure ${CTEST_ARGS:-} > "$log" 2>&1
  ctest_rc=$?
  set -e
  test_seconds=$(( $(date +%s) - start ))
  grep -E '^ *[0-9]+/[0-9]+ Test' "$log" | grep -v ' Passed ' || true
  passed=$(grep -cE '^ *[0-9]+/[0-9]+ Test .* Passed' "$log" || true)
  skipped=$(grep -cE '^ *[0-9]+/[0-9]+ Test .* Skipped' "$log" || true)
  ran=$(grep -cE '^ *[0-9]+/[0-9]+ Test ' "$log" || true)
  failed=$(( ran - passed - skipped ))
  total=$(ctest --test-dir "$build" -N | sed -n 's/^Total Tests: //p')
  left_out=$(( total - ran ))
  echo "cross-arm64: tests under qemu-user (emulated) in ${test_seconds} s; $left_out of $total left out (reasons above); log: $log"
  echo "cross-arm64: $passed passed, $failed failed, $skipped skipped"
  [ "$ctest_rc" = 0 ] || [ "$failed" -gt 0 ] || die "ctest failed (exit $ctest_rc) with no failed test counted: see $log"
fi

# --- 5. Emulated timings: wall-clock ms per frame under qemu-user, a relative figure, not arm64 hardware's.
if [ "$run_bench" = 1 ]; then
  qemu="$(command -v qemu-aarch64 || command -v qemu-aarch64-static)"
  say "toposlam-bench fingerprint under $qemu (EMULATED: timings are qemu's, not an arm64 CPU's)"
  low "$qemu" -L "$sysroot" "$build/bench/toposlam-bench" fingerprint --keypoints orb --workers 1 ||
    die "the emulated bench failed"
fi

if [ "$run_tests" = 1 ] && [ "$failed" -gt 0 ]; then exit 1; fi
exit 0
