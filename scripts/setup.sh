#!/usr/bin/env bash
# Installs the Debian packages toposlam needs. Idempotent; needs root (or sudo).
#   scripts/setup.sh          build + run: what scripts/build.sh and scripts/run-demo.sh need
#   scripts/setup.sh --test   also the test-only tools (browser check, VM camera test): scripts/test.sh, CI
#   scripts/setup.sh [--test] --print   print the package list, one a line, and install nothing
set -euo pipefail

# To build (scripts/build.sh builds the test suite too, so Catch2's headers are a build dependency).
BUILD_PACKAGES=(
  build-essential cmake ninja-build pkg-config ccache
  libopencv-dev libeigen3-dev libyaml-cpp-dev libcli11-dev libspdlog-dev catch2 zlib1g-dev
  libjpeg62-turbo-dev libpng-dev  # image files without OpenCV imgcodecs (platform/files/image_codec.cpp)
  liblcm-dev liblcm-bin liblcm-java libsystemd-dev libcamera-dev
  help2man file  # the man pages from --help; `file`: cpack's dpkg-shlibdeps step (scripts/package.sh)
)
# To run toposlam, toposlamd and the demo.
RUNTIME_PACKAGES=(
  graphviz   # `dot`: the topology drawing of `toposlam map`
  iproute2   # `ip`: the demo's private network namespace with multicast on loopback; the multicast route
)
# Only for tests.
TEST_PACKAGES=(
  chromium chromium-driver  # browser check of `toposlam report` over WebDriver (ctest -L browser)
  python3  # that browser check; the Python LCM reader and examples (test_platform_udpm_reader, e2e_examples_*)
  qemu-system-x86 busybox-static cpio kmod xz-utils v4l-utils ffmpeg  # VM camera test (tests/vm)
  libcamera-ipa libcamera-tools  # VM test: libcamera's vimc IPA module, `cam --list` (tests/vm)
  lintian  # the Debian package's check (ctest -L package)
  systemd-container  # systemd-nspawn: the package installed and its service started under systemd (package_deb_service)
  clang libclang-rt-14-dev  # libFuzzer targets (scripts/fuzz.sh; CI fuzzes each for 20 s): clang 14, its fuzzer runtime
)

with_tests=0
print_only=0
for arg in "$@"; do
  case "$arg" in
    --test) with_tests=1 ;;
    --print) print_only=1 ;;
    -h|--help) sed -n '2,5s/^# \{0,1\}//p' "$0"; exit 0 ;;
    *) echo "setup: unknown option '$arg' (expected --test, --print)" >&2; exit 2 ;;
  esac
done

PACKAGES=("${BUILD_PACKAGES[@]}" "${RUNTIME_PACKAGES[@]}")
if [ "$with_tests" = 1 ]; then PACKAGES+=("${TEST_PACKAGES[@]}"); fi
if [ "$print_only" = 1 ]; then printf '%s\n' "${PACKAGES[@]}"; exit 0; fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
