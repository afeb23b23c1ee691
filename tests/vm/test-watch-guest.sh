#!/usr/bin/env bash
# The VM test's budget logic (tests/vm/watch-guest.sh with tests/vm/budget.sh), without QEMU: a fake
# guest writes the console lines with chosen delays, limits are 1-2 s.
#   1. a guest whose boot says "4x slower" (10 s) gets 4 s for a 1 s step and passes, taking 2 s;
#   2. the same steps after an idle boot (2.0 s): the 2-s step overruns its 1 s and is stopped, named;
#   3. a guest stuck in a step is stopped within its limit x slowness, and the process is gone;
#   4. no boot line within TOPOSLAM_VM_BOOT_LIMIT: stopped; 5. the factor is capped (boot 100 s: 6.00).
set -u
here=$(cd "$(dirname "$0")" && pwd)
. "$here/budget.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; failures=$((failures + 1)); fi; }

# fake_guest LOG BOOT_S SECONDS_IN_STEP_1: boot line, step 1 (limit 1), step 2 (limit 1, 0.3 s), DONE.
fake_guest() {
  { sleep 0.3; echo "junk from the firmware VMTEST BOOTED [$2 s]"; sleep 0.3
    echo "VMTEST STEP [1.0 s] limit=1 first step"; sleep "$3"
    echo "VMTEST PASS [2.0 s] something"; echo "VMTEST STEP [2.1 s] limit=1 second step"; sleep 0.3
    echo "VMTEST DONE failures=0"; sleep 0.3; } >"$1"
}

fake_guest "$work/slow.log" 10.0 2 & pid=$!
out=$("$here/watch-guest.sh" "$work/slow.log" $pid); rc=$?
echo "$out" | sed 's/^/  | /'
check "a 4x slower guest with a 2 s step (limit 1 s x 4) passes" '[ $rc -eq 0 ]'
check "it measured slowness 4.00" 'echo "$out" | grep -q "slowness 4.00 "'
check "it timed the first step" 'echo "$out" | grep -Eq "step .first step. took [12]\.[0-9] s here \(limit 1 s x 4.00\)"'

fake_guest "$work/idle.log" 2.0 2 & pid=$!
out=$("$here/watch-guest.sh" "$work/idle.log" $pid); rc=$?
echo "$out" | sed 's/^/  | /'
check "after an idle boot the same 2 s step fails" '[ $rc -eq 1 ]'
check "the failure names the step and its limit" \
  'echo "$out" | grep -Eq "FAILED: step .first step. still running after 1\.[0-9] s \(its limit: 1 s x slowness 1.00\)"'
sleep 0.2
check "the fake guest was stopped" '! kill -0 $pid 2>/dev/null'

{ echo "VMTEST BOOTED [5.0 s]"; echo "VMTEST STEP [1.0 s] limit=1 hangs"; exec sleep 60; } >"$work/hang.log" & pid=$!
start=$(cut -d' ' -f1 /proc/uptime)
out=$("$here/watch-guest.sh" "$work/hang.log" $pid); rc=$?
took=$(awk -v a="$(cut -d' ' -f1 /proc/uptime)" -v b="$start" 'BEGIN { printf "%.1f", a - b }')
echo "$out" | sed 's/^/  | /'
check "a hung step fails (took $took s; limit 1 s x 2.00)" '[ $rc -eq 1 ] && awk -v t="$took" "BEGIN { exit !(t >= 2 && t < 10) }"'
sleep 0.2
check "the hung guest was stopped" '! kill -0 $pid 2>/dev/null'

{ echo "firmware only"; exec sleep 60; } >"$work/noboot.log" & pid=$!
out=$(TOPOSLAM_VM_BOOT_LIMIT=1 "$here/watch-guest.sh" "$work/noboot.log" $pid); rc=$?
echo "$out" | sed 's/^/  | /'
check "no boot within the boot limit fails" '[ $rc -eq 1 ] && echo "$out" | grep -q "did not boot within 1 s"'

check "slowness is capped at $VM_MAX_SLOWNESS" '[ "$(vm_slowness 100)" = "6.00" ] && [ "$(vm_slowness 1.2)" = "1.00" ]'
check "scaled limits round up" '[ "$(vm_scaled 40 1.5)" = 60 ] && [ "$(vm_scaled 7 1.01)" = 8 ]'

[ $failures -eq 0 ] && echo "PASS" || { echo "$failures checks failed"; exit 1; }
