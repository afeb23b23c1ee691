#!/bin/sh
# `toposlam listen` as a user runs it, over real LCM multicast (run inside tests/e2e/in_netns.sh).
#   check_listen.sh signals TOPOSLAM TOPOSLAMD SAMPLES DIR   Ctrl-C and SIGTERM end it with 0, no "LCM receive failed"
#   check_listen.sh renamed TOPOSLAM TOPOSLAMD SAMPLES DIR   channels renamed in the config (-c), and --hz
set -u
mode="$1" toposlam="$2" toposlamd="$3" samples="$4" dir="$5"
rm -rf "$dir" && mkdir -p "$dir"
fail() { echo "FAIL: $*"; exit 1; }

# Waits until process $1 catches SIGINT and SIGTERM (bits 2 and 15 of SigCgt: 0x4002): it has subscribed
# and installed its handlers.
# A readiness check, not a timing assumption: it returns as soon as the handler is there.
wait_caught() {
  i=0
  while [ $i -lt 200 ]; do
    mask=$(awk '/^SigCgt:/ {print $2}' "/proc/$1/status" 2>/dev/null)
    [ -n "$mask" ] && [ $(( 0x$mask & 0x4002 )) -eq $(( 0x4002 )) ] && return 0
    i=$((i + 1)); sleep 0.05
  done
  fail "listener $1 never installed its signal handlers"
}

case "$mode" in
signals)
  for sig in INT TERM; do
    "$toposlam" listen --channels status --hz >"$dir/$sig.out" 2>"$dir/$sig.err" &
    pid=$!
    wait_caught $pid
    kill -s $sig $pid
    wait $pid; rc=$?
    echo "SIG$sig: exit $rc"; cat "$dir/$sig.out" "$dir/$sig.err"
    [ $rc -eq 0 ] || fail "SIG$sig: exit status $rc, expected 0"
    grep -q "LCM receive failed" "$dir/$sig.err" && fail "SIG$sig: 'LCM receive failed'"
    grep -q "^rate TOPOSLAM_STATUS: 0 messages in [0-9.]* s = 0.00 Hz$" "$dir/$sig.out" || fail "SIG$sig: no --hz line"
  done
  ;;
renamed)
  cat >"$dir/robot7.yaml" <<YAML
lcm:
  channels:
    place: ROBOT7_PLACE
    place_event: ROBOT7_EVENT
    status: ROBOT7_STATUS
YAML
  # A: the default channels (place, place_event) under their configured names. B: by name and by key.
  "$toposlam" listen -c "$dir/robot7.yaml" --count 3 >"$dir/a.out" 2>"$dir/a.err" &
  a=$!
  "$toposlam" listen -c "$dir/robot7.yaml" --channels ROBOT7_PLACE,status --hz --json >"$dir/b.out" 2>"$dir/b.err" &
  b=$!
  wait_caught $a
  wait_caught $b
  "$toposlamd" -c "$dir/robot7.yaml" --source "images:$samples" --overflow block --map "" >"$dir/daemon.log" 2>&1 \
    || { cat "$dir/daemon.log"; fail "toposlamd failed"; }
  wait $a; rc_a=$?
  kill -s TERM $b; wait $b; rc_b=$?
  echo "A: exit $rc_a"; cat "$dir/a.out" "$dir/a.err"; echo "B: exit $rc_b"; tail -3 "$dir/b.out"; cat "$dir/b.err"
  [ $rc_a -eq 0 ] && [ $rc_b -eq 0 ] || fail "listeners exited $rc_a and $rc_b, expected 0"
  [ "$(grep -c . "$dir/a.out")" -eq 3 ] || fail "A printed $(grep -c . "$dir/a.out") lines, expected 3"
  grep -q '"channel":"ROBOT7_STATUS"' "$dir/b.out" || fail "B heard no status on ROBOT7_STATUS"
  # 84 frames, one place message each (UDP on loopback may lose one under load).
  grep -Eq '^\{"rate":\{"channel":"ROBOT7_PLACE","messages":(8[0-4]),' "$dir/b.out" || fail "B: no --hz line with ~84 place messages"
  grep -q '^{"rate":{"channel":"ROBOT7_STATUS","messages":[1-9]' "$dir/b.out" || fail "B: no --hz line for ROBOT7_STATUS"
  # A name the config does not have is a usage error naming the config's channels.
  "$toposlam" listen -c "$dir/robot7.yaml" --channels TOPOSLAM_PLACE >"$dir/c.out" 2>&1; rc_c=$?
  cat "$dir/c.out"
  grep -q "unknown channel 'TOPOSLAM_PLACE'.*ROBOT7_PLACE" "$dir/c.out" || fail "an unknown channel is not named"
  ;;
*) fail "unknown mode $mode" ;;
esac
echo "listen OK"
