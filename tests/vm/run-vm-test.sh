#!/usr/bin/env bash
# The VM test (ctest label `vm`): boots Debian's own kernel under QEMU (TCG, no KVM needed), with
# v4l2loopback, vivid and vimc loaded, shares this machine's root read-only over 9p and runs the real
# toposlam binaries from BUILD_DIR inside (tests/vm/guest.sh). Passes when every guest check passed.
# Exit 77 (skipped) when QEMU or a tool the guest is built with is missing here (each named with its
# package).
# Time: no fixed budget. tests/vm/watch-guest.sh follows the guest: the boot must come within 120 s, and
# each guest step within its own limit for an idle machine times the slowness the guest's boot measured
# (tests/vm/budget.sh), so a busy machine stretches the limits and a hang still fails, naming its step.
# Usage: tests/vm/run-vm-test.sh BUILD_DIR [CACHE_DIR]    (CACHE_DIR default BUILD_DIR/vm-cache)
# Environment: TOPOSLAM_VM_BOOT_LIMIT (host seconds for the boot, default 120),
#              TOPOSLAM_VM_SLOWNESS (the factor instead of the one measured),
#              TOPOSLAM_VM_SMP (guest CPUs, default 2),
#              TOPOSLAM_VM_DAEMON (another toposlamd binary to run inside instead of BUILD_DIR's).
set -euo pipefail

build=$(cd "${1:?usage: run-vm-test.sh BUILD_DIR [CACHE_DIR]}" && pwd)
cache=${2:-$build/vm-cache}
here=$(cd "$(dirname "$0")" && pwd)
scripts=$(cd "$here/../../scripts/vm" && pwd)
started=$(date +%s)

qemu=$(command -v qemu-system-x86_64 || true)
if [ -z "$qemu" ]; then
  echo "vm-test: SKIPPED: qemu-system-x86_64 is not installed (scripts/setup.sh installs qemu-system-x86)"
  exit 77
fi
for need in busybox:busybox-static cpio:cpio modprobe:kmod depmod:kmod dpkg-deb:dpkg make:make gcc:gcc xz:xz-utils; do
  tool=${need%%:*}
  command -v "$tool" >/dev/null || [ -x "/bin/$tool" ] || [ -x "/sbin/$tool" ] || [ -x "/usr/sbin/$tool" ] ||
    { echo "vm-test: SKIPPED: $tool is not installed (package ${need#*:}; scripts/setup.sh --test installs it)"; exit 77; }
done
[ -x "$build/src/apps/toposlam/toposlam" ] || { echo "vm-test: FAILED: build toposlam in $build first"; exit 1; }

kver=$("$scripts/prepare.sh" "$cache")
initrd="$cache/initrd.cpio.gz"
"$scripts/build-initramfs.sh" "$cache" "$initrd"
prepared=$(date +%s)
echo "vm-test: kernel $kver prepared in $((prepared - started)) s; booting"

log="$build/vm-test.log"
: >"$log"
set +e
"$qemu" -accel tcg -m 1024 -smp "${TOPOSLAM_VM_SMP:-2}" \
  -kernel "$cache/vmlinuz" -initrd "$initrd" \
  -virtfs local,path=/,mount_tag=host,security_model=none,readonly=on,multidevs=remap \
  -append "console=ttyS0 quiet loglevel=3 panic=-1 tsguest=$here/guest.sh tsbuild=$build${TOPOSLAM_VM_DAEMON:+ tsdaemon=$TOPOSLAM_VM_DAEMON}" \
  -nographic -no-reboot -monitor none -serial stdio </dev/null >"$log" 2>&1 &
qemu_pid=$!
trap 'kill -KILL $qemu_pid 2>/dev/null' EXIT  # ctest's own timeout, or ^C: no QEMU left behind
"$here/watch-guest.sh" "$log" "$qemu_pid"
watch_rc=$?
wait "$qemu_pid"
qemu_rc=$?
set -e
trap - EXIT
finished=$(date +%s)
tr -d '\r' <"$log" | grep -oE "VMTEST .*|^  [a-z0-9]+\| .*" | grep -v "| frame seq=" || true
echo "vm-test: guest ran $((finished - prepared)) s (qemu exit $qemu_rc), whole test $((finished - started)) s; log $log"

[ "$watch_rc" -eq 0 ] || { echo "vm-test: FAILED: stopped by the watcher (see above and $log)"; exit 1; }
grep -q "VMTEST BOOTED" "$log" || { echo "vm-test: FAILED: the guest did not boot (see $log)"; exit 1; }
grep -q "VMTEST DONE failures=0" "$log" || { echo "vm-test: FAILED: guest checks failed"; exit 1; }
if grep -q "VMTEST FAIL" "$log"; then echo "vm-test: FAILED"; exit 1; fi
echo "vm-test: PASSED"
