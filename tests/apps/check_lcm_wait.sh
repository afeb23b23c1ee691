#!/bin/sh
# toposlamd started before the network (issue 16): in a network namespace with no route at all, it waits
# (READY=1, STATUS= "waiting for the network", watchdog pings) instead of exiting, and runs once the
# multicast route appears; SIGTERM while it waits is a clean exit 0 with STOPPING=1. systemd's notify
# socket is played by a small Python receiver. Exit 77 without unprivileged network namespaces or ip.
# Usage: check_lcm_wait.sh TOPOSLAMD SAMPLES DIR
set -u
toposlamd="$1" samples="$2" dir="$3"
if [ -z "${TOPOSLAM_LCM_WAIT_INSIDE:-}" ]; then
  unshare -rn true 2>/dev/null && command -v ip >/dev/null || { echo "no network namespaces or ip: skipped"; exit 77; }
  [ -x /usr/bin/python3 ] || { echo "no /usr/bin/python3: skipped"; exit 77; }
  rm -rf "$dir" && mkdir -p "$dir"
  exec unshare -rn env TOPOSLAM_LCM_WAIT_INSIDE=1 sh "$0" "$@"
fi
fail() { echo "FAIL: $*"; cat "$dir"/*.log; exit 1; }
printf 'lcm:\n  open_retry_s: 0.2\n' >"$dir/retry.yaml"
# The notify socket: every datagram as one line of notify-<name>.log.
listen() {
  /usr/bin/python3 -c '
import socket, sys
s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
s.bind(sys.argv[1])
with open(sys.argv[2], "a") as out:
    while True:
        data = s.recv(4096).decode()
        out.write(data.replace("\n", " ") + "\n")
        out.flush()
' "$dir/$1.sock" "$dir/notify-$1.log" &
  receiver=$!
  i=0
  while [ ! -S "$dir/$1.sock" ] && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
}
start() {  # NAME: toposlamd on the samples, told about the notify socket and a 1 s watchdog
  listen "$1"
  NOTIFY_SOCKET="$dir/$1.sock" WATCHDOG_USEC=1000000 "$toposlamd" -c "$dir/retry.yaml" \
    --source "images:$samples?fps=30" --map "$dir/$1.tsm" >"$dir/$1.log" 2>&1 &
  daemon=$!
  i=0
  while [ $i -lt 100 ] && ! grep -q "^WATCHDOG=1" "$dir/notify-$1.log" 2>/dev/null; do sleep 0.1; i=$((i + 1)); done
  sleep 1  # a few retries and pings (the figures below count them)
}

# 1. No route: waiting, READY, pings; then the route appears and the run completes (exit 0, a map).
start up
kill -0 $daemon 2>/dev/null || fail "toposlamd did not wait for the network"
grep -q "waiting for the network: no route to the multicast group 239.255.76.67: Network is unreachable" "$dir/up.log" \
  || fail "no 'waiting for the network' line"
ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo || fail "cannot add the route"
wait $daemon
rc=$?
kill $receiver
[ "$rc" = 0 ] || fail "exit $rc after the network came up"
grep -q "the network is up after [0-9]* attempts" "$dir/up.log" || fail "no 'network is up' line"
grep -q "frames published" "$dir/up.log" && [ -s "$dir/up.tsm" ] || fail "the run did not complete"
n="$(grep -c '^READY=1' "$dir/notify-up.log")"
[ "$n" -ge 1 ] || fail "no READY=1"
head -1 "$dir/notify-up.log" | grep -q '^READY=1' || fail "READY=1 is not the first notification"
grep -q '^STATUS=waiting for the network: no route to the multicast group 239.255.76.67: Network is unreachable (lcm.url udpm://239.255.76.67:7667?ttl=0, attempt [0-9]*)' \
  "$dir/notify-up.log" || fail "no waiting STATUS="
waiting="$(grep -c '^STATUS=waiting for the network' "$dir/notify-up.log")"
pings="$(sed -n '/^STATUS=waiting/,/^STATUS=running/p' "$dir/notify-up.log" | grep -c '^WATCHDOG=1')"
[ "$waiting" -ge 3 ] && [ "$pings" -ge 2 ] || fail "$waiting waiting statuses, $pings pings while waiting"
grep -q '^STATUS=running' "$dir/notify-up.log" || fail "no running STATUS= after the wait"
echo "waited: $waiting attempts, $pings watchdog pings, then ran: $(grep -o '[0-9]* frames published' "$dir/up.log")"

# 2. SIGTERM while waiting (route gone again): exit 0 with STOPPING=1, at once.
ip route del 224.0.0.0/4 dev lo
start stop
kill -0 $daemon 2>/dev/null || fail "toposlamd did not wait for the network (second run)"
kill -TERM $daemon
wait $daemon
rc=$?
sleep 0.2
kill $receiver
[ "$rc" = 0 ] || fail "SIGTERM while waiting exited $rc"
grep -q '^STOPPING=1' "$dir/notify-stop.log" || fail "no STOPPING=1"
grep -q "received while waiting for the network: nothing to save, exiting" "$dir/stop.log" || fail "no stop line"
echo "SIGTERM while waiting: exit 0, STOPPING=1"
echo "lcm wait OK"
