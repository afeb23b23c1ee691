# Sourced by tests/vm/guest.sh inside the VM (uses its pass/fail/step/show helpers, $toposlamd, the
# running ffmpeg writer on /dev/video0 and the `toposlam listen` subscriber started early as $listener):
# runs the real toposlamd on the v4l2loopback camera for 30 s and checks that place estimates
# (TOPOSLAM_PLACE, one per processed frame) and status messages arrived over LCM (multicast on lo).
step "toposlamd on v4l2loopback + LCM"
timeout -s TERM 30 "$toposlamd" --source "v4l2:/dev/video0?size=320x240&fps=10&format=yuyv" \
  --map /tmp/vm-map.tsm --no-map-load >daemon.txt 2>&1
daemon_rc=$?
kill $listener 2>/dev/null; wait $listener 2>/dev/null
places=$(grep -c '^place ' listen.txt)
events=$(grep -c '^EVENT ' listen.txt)
statuses=$(grep -c '^STATUS ' listen.txt)
show daemon daemon.txt 400 | tail -6
grep -E '^(place|EVENT|STATUS) ' listen.txt | tail -3 | sed 's/^/  listen| /'
echo "VMTEST toposlamd exit $daemon_rc (124 = stopped by SIGTERM after 30 s): $places place, $events place-event, $statuses status messages received"
if grep -q "unknown scheme 'v4l2:'" daemon.txt; then
  echo "VMTEST SKIP toposlamd: this toposlamd does not register the v4l2: scheme yet (registerV4l2FrameSourceScheme)"
elif [ "$places" -ge 5 ] && [ "$statuses" -ge 1 ]; then
  pass "toposlamd over LCM: $places place estimates, $events place events, $statuses status messages"
else
  fail "toposlamd over LCM: expected >= 5 place and >= 1 status messages"
fi
