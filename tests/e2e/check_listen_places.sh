#!/bin/sh
# e2e_examples_listen_places: the subscriber examples (examples/python/listen_places.py and
# examples/cpp/listen_places.cpp) and the Python package toposlam_lcm against the real toposlamd on the
# simulated office (sim:office?route=loop2, 1618 frames, lossless queues), over real UDP multicast, on the
# shipped config's lcm.url (which must be the examples' default). Meanwhile subscriber_check.py reads every
# channel with toposlam_lcm.udpm_reader and checks what it decoded (place_t per frame, place events with
# their JPEG, topology_t, the final status), and lcm-logplayer publishes one ~300 kB message, which liblcm
# sends in several LC03 fragments, to check the reader's reassembly against LCM's own sender. lcm-logger
# records the run meanwhile; `toposlam listen --from lcmlog:` reads the log back (issue 16).
# Run by in_netns.sh; exit 77 (skipped) outside a network namespace or without multicast.
# Usage: check_listen_places.sh PYTHON3 TOPOSLAMD CPP_EXAMPLE SOURCE_DIR PYTHONPATH TOPOSLAM
set -eu
python3="$1" toposlamd="$2" cpp_example="$3" src="$4" toposlam="$6"
export PYTHONPATH="$5" PYTHONDONTWRITEBYTECODE=1
[ -n "${TOPOSLAM_IN_NETNS:-}" ] || { echo "SKIP: no network namespace here (unshare -rn failed)"; exit 77; }
command -v lcm-logplayer >/dev/null && command -v lcm-logger >/dev/null || { echo "SKIP: lcm-logplayer or lcm-logger is not installed (liblcm-bin)"; exit 77; }
check="$src/tests/e2e/subscriber_check.py"
tmp="$(mktemp -d)"
pids=""
cleanup() {
  for pid in $pids; do kill "$pid" 2>/dev/null || true; done
  rm -rf "$tmp"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; exit 1; }
start=$(date +%s)

# The URL the daemon publishes on (the shipped config) is the one the examples listen on by default.
url="$(sed -n 's/^ *url: *"\(udpm:[^"]*\)".*/\1/p' "$src/config/toposlam.yaml")"
grep -q "\"$url\"" "$src/examples/cpp/listen_places.cpp" || fail "listen_places.cpp's default URL is not lcm.url ($url)"
"$python3" -c "import sys; from toposlam_lcm.udpm_reader import DEFAULT_URL; sys.exit(DEFAULT_URL != '$url')" \
  || fail "udpm_reader.DEFAULT_URL is not lcm.url ($url)"
"$python3" "$check" probe "$url" || exit $?

# Subscribers first: the checker says when it has joined the group.
"$python3" "$check" collect "$url" "$tmp/ready" >"$tmp/collect.log" 2>&1 &
collect=$!
pids="$pids $collect"
"$python3" "$src/examples/python/listen_places.py" 600 >"$tmp/python.out" 2>"$tmp/python.err" &
python_example=$!
"$cpp_example" 600 >"$tmp/cpp.out" 2>"$tmp/cpp.err" &
cpp_example_pid=$!
pids="$pids $python_example $cpp_example_pid"
i=0
while [ ! -s "$tmp/ready" ]; do
  i=$((i + 1))
  [ $i -le 100 ] || { cat "$tmp/collect.log"; fail "subscriber_check.py did not join the group within 10 s"; }
  kill -0 "$collect" 2>/dev/null || { cat "$tmp/collect.log"; fail "subscriber_check.py ended early"; }
  sleep 0.1
done

# lcm-logger records toposlamd's channels (its own subscription; given a moment to join the group).
lcm-logger --lcm-url="$url" --channel='TOPOSLAM_.*' --force --quiet "$tmp/robot.lcmlog" >"$tmp/logger.log" 2>&1 &
logger=$!
pids="$pids $logger"
sleep 0.5
# One large message through liblcm, then the daemon's whole run.
"$python3" "$check" large-log "$tmp/large.lcmlog"
lcm-logplayer -l "$url" "$tmp/large.lcmlog" >"$tmp/logplayer.log" 2>&1 || { cat "$tmp/logplayer.log"; fail "lcm-logplayer"; }
status=0
"$toposlamd" -c "$src/config/toposlam.yaml" --source "sim:office?route=loop2" --map "$tmp/office.tsm" --no-map-load \
  --overflow block >"$tmp/toposlamd.log" 2>&1 || status=$?
[ $status -eq 0 ] || { tail -20 "$tmp/toposlamd.log"; fail "toposlamd exited with $status"; }
echo "toposlamd ran $(($(date +%s) - start)) s after the start of the test: $(tail -1 "$tmp/toposlamd.log")"
sleep 0.3  # lcm-logger flushes every 100 ms
kill -INT "$logger"
wait "$logger" || true
"$toposlam" listen --from "lcmlog:$tmp/robot.lcmlog" --channels place,place_event >"$tmp/replay.txt" 2>&1 \
  || { tail -3 "$tmp/replay.txt"; fail "listen --from the lcm-logger log"; }
estimates=$(grep -c '^place  frame' "$tmp/replay.txt" || true)
events=$(grep -c '^EVENT  place' "$tmp/replay.txt" || true)
[ "$estimates" -ge 1537 ] && [ "$events" -ge 20 ] || fail "lcm-logger's log replays $estimates place estimates and $events events"
"$toposlam" report "lcmlog:$tmp/robot.lcmlog" >"$tmp/report.log" 2>&1 || { cat "$tmp/report.log"; fail "report lcmlog:"; }
echo "lcm-logger's log ($(wc -c <"$tmp/robot.lcmlog") bytes) replayed: $estimates place estimates, $events place events; report written"

status=0
wait "$collect" || status=$?
cat "$tmp/collect.log"
[ $status -eq 0 ] || fail "subscriber_check.py collect: exit $status"
for example in python cpp; do
  case $example in python) pid=$python_example ;; cpp) pid=$cpp_example_pid ;; esac
  status=0
  wait "$pid" || status=$?
  [ $status -eq 0 ] || { cat "$tmp/$example.err"; fail "the $example example exited with $status"; }
  "$python3" "$check" example-output "$tmp/$example.out" 600 >"$tmp/$example.check" 2>&1 \
    || { cat "$tmp/$example.check"; fail "the $example example's output"; }
  echo "$example example: $(cat "$tmp/$example.check")"
done
pids=""
echo "listen_places OK in $(($(date +%s) - start)) s"
