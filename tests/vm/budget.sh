# The VM test's time budget (sourced, POSIX sh: by the host's tests/vm/watch-guest.sh and by the guest's
# tests/vm/guest.sh). Under TCG everything in the guest runs as slowly as the host is busy, so no fixed
# number of seconds can tell a fault from a loaded machine (load ~6 on 2 cores overran a fixed 169 s with
# every check passing). Instead the guest's boot, measured on its own clock up to "VMTEST BOOTED [T s]",
# gives the machine's slowness now; every step of the guest declares its limit for an idle machine
# ("VMTEST STEP [t s] limit=N what"), and the host allows N x slowness for it; the guest's own timeouts
# stretch by the same factor. A step that overruns that is a fault (a hang, a lost device), whatever the
# load was when the guest booted.
#   idle boot, measured: 2.1-2.3 s (2026-12-02, 8 runs); under load 3.5-6.8 s.
VM_REFERENCE_BOOT_S=2.5
VM_MAX_SLOWNESS=6  # a machine slower than that is not one the test can judge in any budget CI would accept

# vm_slowness BOOT_S: the factor, from 1 (idle or faster) to VM_MAX_SLOWNESS, two decimals.
vm_slowness() {
  awk -v b="$1" -v r="$VM_REFERENCE_BOOT_S" -v m="$VM_MAX_SLOWNESS" \
    'BEGIN { f = b / r; if (!(f >= 1)) f = 1; if (f > m) f = m; printf "%.2f\n", f }'
}

# vm_scaled SECONDS FACTOR: whole seconds, rounded up.
vm_scaled() {
  awk -v s="$1" -v f="$2" 'BEGIN { x = s * f; printf "%d\n", (x == int(x)) ? x : int(x) + 1 }'
}
