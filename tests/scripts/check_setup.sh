#!/bin/sh
# scripts/setup.sh installs build + runtime packages only; --test adds the test-only tools, and
# scripts/test.sh (CI: .ci/run) asks for them. Reads the lists with --print: nothing is installed.
set -u
root="$1"
fail() { echo "FAIL: $*"; exit 1; }
runtime="$(bash "$root/scripts/setup.sh" --print)" || fail "setup.sh --print failed"
all="$(bash "$root/scripts/setup.sh" --test --print)" || fail "setup.sh --test --print failed"
has() { printf '%s\n' "$1" | grep -qx "$2"; }
for p in qemu-system-x86 busybox-static chromium chromium-driver ffmpeg libcamera-tools cpio lintian systemd-container; do
  has "$runtime" "$p" && fail "test-only package $p is in the default (build + runtime) set"
  has "$all" "$p" || fail "test-only package $p is missing from --test"
done
# What the build and the README's demo need: compilers, libraries, LCM, dot (map drawing), ip (netns),
# help2man (man pages).
for p in build-essential cmake libopencv-dev liblcm-dev liblcm-bin libsystemd-dev catch2 graphviz iproute2 help2man; do
  has "$runtime" "$p" || fail "$p is missing from the default set"
done
for p in $runtime; do has "$all" "$p" || fail "--test drops $p"; done
grep -q '^scripts/setup.sh --test' "$root/scripts/test.sh" || fail "scripts/test.sh does not run setup.sh --test"
bash "$root/scripts/setup.sh" --bogus >/dev/null 2>&1; [ $? -eq 2 ] || fail "an unknown option is not exit 2"
echo "setup lists OK: $(printf '%s\n' "$runtime" | wc -l) build+runtime, $(printf '%s\n' "$all" | wc -l) with --test"
