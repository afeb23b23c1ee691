#!/usr/bin/env bash
# Installs every Debian package toposlam needs to build, test and run. Idempotent; needs root (or sudo).
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libopencv-dev libeigen3-dev libyaml-cpp-dev libcli11-dev libspdlog-dev catch2
  liblcm-dev liblcm-bin liblcm-java libsystemd-dev libcamera-dev
  graphviz
  chromium chromium-driver python3  # browser check of `toposlam report` over WebDriver (ctest -L browser)
  qemu-system-x86 busybox-static cpio kmod xz-utils v4l-utils ffmpeg iproute2  # VM camera test (tests/vm)
  libcamera-ipa libcamera-tools  # VM test: libcamera's vimc IPA module, `cam --list` (tests/vm)
)

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
