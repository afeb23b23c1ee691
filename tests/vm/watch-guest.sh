#!/usr/bin/env bash
# Watches the VM test's guest through its console log while QEMU (PID) runs, and stops it on a fault:
#   - no "VMTEST BOOTED [T s]" within TOPOSLAM_VM_BOOT_LIMIT host seconds (default 120: a boot that idles
#     in 2-3 s of guest time and ~5 s here);
#   - a step ("VMTEST STEP [t s] limit=N what", or the poweroff after "VMTEST DONE", limit 30) still
#     running N x slowness host seconds after it began, where slowness = tests/vm/budget.sh's factor of the
#     guest's boot time (TOPOSLAM_VM_SLOWNESS overrides it).
# Prints each step's host time against its limit. Exit 0 when QEMU ended by itself (the caller judges the
# guest's checks), 1 after killing it on a fault.
# Usage: watch-guest.sh CONSOLE_LOG QEMU_PID
set -u
here=$(cd "$(dirname "$0")" && pwd)
. "$here/budget.sh"
log=${1:?usage: watch-guest.sh CONSOLE_LOG QEMU_PID}
pid=${2:?usage: watch-guest.sh CONSOLE_LOG QEMU_PID}
boot_limit=${TOPOSLAM_VM_BOOT_LIMIT:-120}
poweroff_limit=30

now() { cut -d' ' -f1 /proc/uptime; }  # host seconds since boot: monotonic, not the wall clock
minus() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f\n", a - b }'; }
over() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a > b) }'; }
fault() {
  echo "vm-test: FAILED: $*"
  kill -KILL "$pid" 2>/dev/null
  exit 1
}

started=$(now)
slowness=""
step="" step_name="" step_limit=0 step_started=0
finish_step() {
  [ -n "$step" ] || return 0
  echo "vm-test: step '$step_name' took $(minus "$(now)" "$step_started") s here (limit ${step_limit} s x $slowness)"
}
while kill -0 "$pid" 2>/dev/null; do
  t=$(now)
  lines=$(tr -d '\r' <"$log" 2>/dev/null | grep -a -oE "VMTEST (BOOTED|STEP|DONE) .*")
  if [ -z "$slowness" ]; then
    boot=$(echo "$lines" | sed -n 's/^VMTEST BOOTED \[\([0-9.]*\) s\].*/\1/p' | head -n 1)
    if [ -n "$boot" ]; then
      slowness=${TOPOSLAM_VM_SLOWNESS:-$(vm_slowness "$boot")}
      echo "vm-test: booted in $boot s of guest time ($(minus "$t" "$started") s here): slowness $slowness" \
           "(boot / ${VM_REFERENCE_BOOT_S} s, at most $VM_MAX_SLOWNESS); each step gets its limit x $slowness"
    elif over "$(minus "$t" "$started")" "$boot_limit"; then
      fault "the guest did not boot within $boot_limit s"
    fi
  fi
  if [ -n "$slowness" ]; then
    last=$(echo "$lines" | grep -E "^VMTEST (STEP|DONE)" | tail -n 1)
    if [ -n "$last" ] && [ "$last" != "$step" ]; then
      finish_step
      step=$last step_started=$t
      case $last in
        "VMTEST DONE"*) step_name="poweroff" step_limit=$poweroff_limit ;;
        *) step_limit=$(echo "$last" | sed -n 's/^VMTEST STEP \[[0-9.]* s\] limit=\([0-9]*\) .*/\1/p')
           step_name=$(echo "$last" | sed 's/^VMTEST STEP \[[0-9.]* s\] limit=[0-9]* //')
           [ -n "$step_limit" ] || fault "a step without limit=N: $last" ;;
      esac
    fi
    if [ -n "$step" ] && over "$(minus "$t" "$step_started")" "$(vm_scaled "$step_limit" "$slowness")"; then
      fault "step '$step_name' still running after $(minus "$t" "$step_started") s (its limit: $step_limit s x slowness $slowness)"
    fi
  fi
  sleep 0.25
done
finish_step
exit 0
