# Sourced by tests/vm/guest.sh inside the VM (uses its pass/fail/step/show helpers, $toposlamd, the
# running ffmpeg writer on /dev/video0 and the `toposlam listen` subscriber started early as $listener):
# runs the real toposlamd on the v4l2loopback camera for 30 s (stretched by the slowness), stops it with
# SIGTERM and checks that
#   - it exits 0 (clean stop: the filter step finished, the map saved) and the map file exists;
#   - place estimates (TOPOSLAM_PLACE, one per processed frame) arrived over LCM (multicast on lo), each
#     with a frame number, a place and a node (-1 before the first place), frame numbers increasing;
#     the estimates after a place event name a node >= 0;
#   - status messages arrived and say the camera is streaming.
step 75 "toposlamd on v4l2loopback + LCM"
run_s=$(s 30)
rm -f /tmp/vm-map.tsm
# --preserve-status: the exit code is toposlamd's own after the SIGTERM (not timeout's 124); -k: a daemon
# that hangs on SIGTERM is killed 20 s later (137) and fails the check below.
timeout --preserve-status -k "$(s 20)" -s TERM "$run_s" "$toposlamd" --source "v4l2:/dev/video0?size=320x240&fps=10&format=yuyv" \
  --map /tmp/vm-map.tsm --no-map-load >daemon.txt 2>&1
daemon_rc=$?
sleep 1  # the last status/flush messages on their way over lo
kill $listener 2>/dev/null; wait $listener 2>/dev/null
places=$(grep -c '^place ' listen.txt)
events=$(grep -c '^EVENT ' listen.txt)
statuses=$(grep -c '^STATUS ' listen.txt)
show daemon daemon.txt 400 | tail -6
grep -E '^(place|EVENT|STATUS) ' listen.txt | tail -3 | sed 's/^/  listen| /'
echo "VMTEST toposlamd exit $daemon_rc after SIGTERM at $run_s s: $places place, $events place-event, $statuses status messages received"

if [ "$daemon_rc" -eq 0 ]; then
  pass "toposlamd stopped cleanly on SIGTERM (exit 0)"
else
  fail "toposlamd exit code $daemon_rc after SIGTERM (expected 0; 137 = had to be killed)"
fi
if [ -s /tmp/vm-map.tsm ]; then
  pass "toposlamd saved its map at stop ($(wc -c </tmp/vm-map.tsm) bytes)"
else
  fail "toposlamd left no map at /tmp/vm-map.tsm after SIGTERM"
fi
# place lines: "place  frame F  place P  node N  p=..."
if [ "$places" -lt 5 ]; then
  fail "toposlamd over LCM: $places place estimates (expected >= 5)"
elif ! awk -v events="$events" '
    /^place / { n++
      if ($2 != "frame" || $4 != "place" || $6 != "node" || $3 !~ /^[0-9]+$/ || $5 !~ /^-?[0-9]+$/ || $7 !~ /^-?[0-9]+$/) {
        print "  malformed: " $0; bad++; next }
      if (n > 1 && $3 + 0 <= frame) { print "  frame not increasing: " $0; bad++ }
      if ($7 + 0 < -1 || $5 + 0 < -1) { print "  bad place/node: " $0; bad++ }
      if (event_seen) { after_event++; if ($7 + 0 >= 0) nodes++ }
      frame = $3 + 0 }
    /^EVENT / { event_seen = 1 }
    # The estimates after the first place event must carry its node. A place closed by the stop itself
    # (the flush at SIGTERM on a slow machine) is followed by no estimate: the event alone names its node.
    END { if (after_event > 0 && nodes == 0) { print "  estimates after a place event, none with a node"; bad++ }
          exit bad ? 1 : 0 }' listen.txt; then
  fail "toposlamd over LCM: place estimates are malformed or out of order (see above)"
else
  pass "toposlamd over LCM: $places place estimates with increasing frame numbers, $events place events"
fi
if [ "$statuses" -ge 1 ] && grep '^STATUS ' listen.txt | tail -1 | grep -q 'camera streaming'; then
  pass "toposlamd status: $statuses messages, camera streaming"
else
  fail "toposlamd status: expected >= 1 STATUS message saying 'camera streaming'"
fi
