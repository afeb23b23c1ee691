# Sourced by tests/vm/guest.sh inside the VM (uses its pass/fail/step/show/s helpers, $toposlamd, $vivid and
# the `toposlam listen` started early on $unplug_url into unplug-listen.txt): toposlamd on the vivid camera
# while it is unplugged and plugged back (issue 19):
#   - unplug: vivid's platform device is unbound from its driver, so its /dev/videoN goes away while
#     toposlamd streams from it, as a USB camera's node does (vivid's "disconnect" control, which the
#     capture test uses, only lasts until the last file handle closes: the camera is back at once);
#   - while it is away the daemon runs on: its status (TOPOSLAM_STATUS) says "camera reconnecting";
#   - replug (bound again: the same /dev/videoN): the daemon's log says "camera back" within 2 s of the
#     node's return, place estimates flow again with frame numbers going on (the same run and map), and
#     the status says "camera streaming (1 reconnects";
#   - SIGTERM: exit 0, the map saved.
step 90 "toposlamd on vivid: unplug and replug the camera"
now_s() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a - b }'; }
places() { grep -c '^place ' unplug-listen.txt; }
last_frame() { grep '^place ' unplug-listen.txt | tail -n 1 | awk '{ print $3 + 0 }'; }
# Waits up to $1 (scaled) seconds for the command "$2" to succeed.
wait_until() {
  deadline=$(awk -v t="$(now_s)" -v d="$(s "$1")" 'BEGIN { printf "%.2f", t + d }')
  until eval "$2"; do
    awk -v t="$(now_s)" -v d="$deadline" 'BEGIN { exit !(t > d) }' && return 1
    sleep 0.1
  done
}

node=$(basename "$vivid")
platform_device=$(basename "$(readlink -f "/sys/class/video4linux/$node/device")")  # vivid.0
driver=/sys/bus/platform/drivers/vivid
rm -f /tmp/vm-unplug.tsm
"$toposlamd" --source "v4l2:$vivid?size=320x240&format=bgr24" --map /tmp/vm-unplug.tsm --no-map-load \
  --lcm-url "$unplug_url" >daemon-unplug.txt 2>&1 &
daemon=$!
if ! wait_until 60 '[ "$(places)" -ge 10 ]'; then
  fail "toposlamd on vivid: $(places) place estimates before the unplug (expected 10)"
  show unplug daemon-unplug.txt 400 | tail -8
else
  frames_before=$(last_frame)
  statuses_before=$(grep -c '^STATUS ' unplug-listen.txt)
  echo "$platform_device" >"$driver/unbind"
  unplugged_at=$(now_s)
  [ -e "$vivid" ] && fail "unplug: $vivid is still there after unbinding $platform_device"
  # The status says so while the camera is away (one status a second).
  if wait_until 10 'tail -n +$((statuses_before + 1)) unplug-listen.txt | grep "^STATUS " | grep -q "camera reconnecting"'; then
    reported_after=$(elapsed "$(now_s)" "$unplugged_at")
  else
    reported_after=""
  fi
  # Away for 3 s in all: the reconnect backoff has grown to its ceiling by then.
  sleep "$(awk -v t="$(elapsed "$(now_s)" "$unplugged_at")" 'BEGIN { x = 3 - t; print x > 0 ? x : 0 }')"
  kill -0 $daemon 2>/dev/null || fail "toposlamd ended while the camera was away"
  places_away=$(places)
  replugged_at=$(now_s)  # before the bind: the node appears inside it, and the daemon may open it at once
  echo "$platform_device" >"$driver/bind"
  wait_until 10 '[ -e "$vivid" ]' || fail "replug: $vivid did not come back after binding $platform_device"
  back_line=""
  wait_until 10 'grep -q "camera back after" daemon-unplug.txt' && back_line=$(grep -m 1 "camera back after" daemon-unplug.txt)
  # "[2026-12-02 11:23:48.794] [info] v4l2:/dev/video1: camera back after 5 attempt(s)": the log's clock is
  # the guest's wall clock, as is now_s.
  back_at=$(date -d "$(echo "$back_line" | sed -n 's/^\[\([^]]*\)\].*/\1/p')" +%s.%N 2>/dev/null)
  wait_until 20 '[ "$(places)" -ge $((places_away + 10)) ]'
  frames_after=$(last_frame)
  wait_until 10 'grep "^STATUS " unplug-listen.txt | tail -n 1 | grep -q "camera streaming (1 reconnects"'
  streaming_again=$?
  kill -TERM $daemon
  wait $daemon
  daemon_rc=$?
  show unplug daemon-unplug.txt 400 | grep -E "camera|frames published" | head -6
  grep '^STATUS ' unplug-listen.txt | grep -m 1 "camera reconnecting" | sed 's/^/  listen| /'

  if [ -n "$reported_after" ]; then
    pass "toposlamd status while the camera is away: 'camera reconnecting' ${reported_after} s after the unplug"
  else
    fail "toposlamd status never said 'camera reconnecting' while the camera was away"
  fi
  if [ -z "$back_at" ]; then
    fail "toposlamd: no 'camera back' in its log after the replug"
  else
    resumed=$(elapsed "$back_at" "$replugged_at")
    if awk -v r="$resumed" 'BEGIN { exit !(r <= 2.0) }'; then
      pass "toposlamd resumed ${resumed} s after the camera came back (at most 2 s): $(echo "$back_line" | sed 's/.*v4l2:/v4l2:/')"
    else
      fail "toposlamd resumed ${resumed} s after the camera came back (expected at most 2 s)"
    fi
  fi
  if [ "$(places)" -ge $((places_away + 10)) ] && [ "${frames_after:-0}" -gt "${frames_before:-0}" ]; then
    pass "toposlamd kept its run across the unplug: frames up to $frames_before before, $frames_after after ($(places) estimates)"
  else
    fail "toposlamd after the replug: $(places) estimates (had $places_away), last frame ${frames_after:-none} (had $frames_before)"
  fi
  [ $streaming_again -eq 0 ] && pass "toposlamd status after the replug: camera streaming, 1 reconnect" ||
    fail "toposlamd status after the replug does not say 'camera streaming (1 reconnects'"
  if [ "$daemon_rc" -eq 0 ] && [ -s /tmp/vm-unplug.tsm ]; then
    pass "toposlamd stopped cleanly after the replug, map saved ($(wc -c </tmp/vm-unplug.tsm) bytes)"
  else
    fail "toposlamd after the replug: exit $daemon_rc, map $(ls -l /tmp/vm-unplug.tsm 2>&1)"
  fi
fi
kill $daemon 2>/dev/null; wait $daemon 2>/dev/null
