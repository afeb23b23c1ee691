#!/bin/sh
# The lcmlog: replay (issue 16): toposlamd on the simulator publishes into an LCM log (liblcm's file://
# provider writes lcm-logger's format), `toposlam listen --from lcmlog:FILE` prints every message of it as a
# live listen would (lines and JSON), `--run-folder` and `toposlam report lcmlog:FILE` make a run folder the
# report and eval read (with the daemon's frame recording as its thumbnails); a truncated or corrupt log is an
# error naming the byte offset (exit 1).
# Usage: check_lcmlog.sh TOPOSLAM TOPOSLAMD DIR
set -u
toposlam="$1" toposlamd="$2" dir="$3"
rm -rf "$dir" && mkdir -p "$dir"
fail() { echo "FAIL: $*"; exit 1; }
log="$dir/run.lcmlog"
printf 'record:\n  dir: %s/rec\n  queue_frames: 1024\n' "$dir" >"$dir/record.yaml"  # the frames too, for the report
out="$("$toposlamd" -c "$dir/record.yaml" --source "sim:office?route=loop&fps=3&size=160x120" --lcm-url "file://$log?mode=w" \
  --map "" --overflow block 2>&1)" || fail "toposlamd: $out"
places="$(echo "$out" | sed -n 's/.*toposlamd: 481 frames published, 0 dropped, \([0-9]*\) places.*/\1/p')"
[ -n "$places" ] && [ "$places" -ge 5 ] || fail "toposlamd: $out"

# Every place estimate and place event, in order, as lines and as JSON.
"$toposlam" listen --from "lcmlog:$log" >"$dir/lines.txt" 2>&1 || fail "listen --from: $(tail -3 "$dir/lines.txt")"
[ "$(grep -c '^place  frame' "$dir/lines.txt")" = 481 ] || fail "not 481 place lines: $(head -3 "$dir/lines.txt")"
[ "$(grep -c '^EVENT  place' "$dir/lines.txt")" = "$places" ] || fail "not $places place events"
grep -q "^place  frame    480  place  *[0-9]*  node" "$dir/lines.txt" || fail "no estimate of frame 480"
"$toposlam" listen --from "lcmlog:$log" --channels place_event,topology --json >"$dir/events.json" || fail "listen --json"
python3 - "$dir/events.json" "$places" <<'EOF' || fail "the JSON lines"
import json, sys
messages = [json.loads(line) for line in open(sys.argv[1])]
events = [m for m in messages if m["kind"] == "place_event"]
topologies = [m for m in messages if m["kind"] == "topology"]
assert len(events) == int(sys.argv[2]), len(events)
assert [e["place"] for e in events] == list(range(len(events)))
assert all(e["first_frame"] <= e["representative_frame"] <= e["last_frame"] for e in events)
assert topologies and len(topologies[-1]["nodes"]) >= 3, topologies[-1:]
print("json: %d place events, %d topologies, last %d nodes" % (len(events), len(topologies), len(topologies[-1]["nodes"])))
EOF
out="$("$toposlam" listen --from "lcmlog:$log" --channels status --hz)" || fail "--hz"
echo "$out" | grep -q "^rate TOPOSLAM_STATUS: [1-9][0-9]* messages in " || fail "--hz: $out"

# A run folder for report and eval.
"$toposlam" listen --from "lcmlog:$log" --count 1 --run-folder "$dir/run" >/dev/null 2>&1 || fail "--run-folder"
[ "$(($(wc -l <"$dir/run/frames.csv") - 1))" = 481 ] && [ "$(($(wc -l <"$dir/run/places.csv") - 1))" = "$places" ] \
  || fail "run folder: $(wc -l "$dir/run/frames.csv" "$dir/run/places.csv")"
[ "$(ls "$dir/run/frames" | grep -c '\.jpg$')" = "$places" ] || fail "not one thumbnail per place"
"$toposlam" sim office --route loop --fps 3 --size 160x120 --out "$dir/truth" >/dev/null 2>&1 || fail "sim"
"$toposlam" eval "$dir/run" --truth "$dir/truth/labels.csv" --json >"$dir/eval.json" 2>/dev/null || fail "eval of the run folder"
python3 -c "import json,sys; e=json.load(open(sys.argv[1])); assert e['frames'] == 481 and e['places'] == int(sys.argv[2]), e; print('eval of the log: %d frames, %d places' % (e['frames'], e['places']))" "$dir/eval.json" "$places" \
  || fail "eval.json: $(head -c 300 "$dir/eval.json")"
out="$("$toposlam" report "lcmlog:$log" 2>&1)" || fail "report lcmlog: $out"
echo "$out" | grep -q "^converted $log ([0-9]* events: 481 place estimates, $places places) into the run folder $log.run$" \
  || fail "report lcmlog: $out"
grep -q "<svg" "$log.run/report.html" || fail "the report has no figure"
# The log alone carries one picture per place: every frame of the strip shows its place's, and nothing is
# "could not be read" (it was, for every frame but the representatives).
"$toposlam" report "lcmlog:$log" --json >"$dir/report-log.json" 2>/dev/null || fail "report lcmlog --json"
python3 -c "import json,sys; r=json.load(open(sys.argv[1])); assert r['thumbnails'] >= 50 and r['warnings'] == 0, r" \
  "$dir/report-log.json" || fail "report of the log alone: $(cat "$dir/report-log.json")"
# With the daemon's own recording as the frames: every thumbnail found (frames.csv names them as recorded).
"$toposlam" report "lcmlog:$log" --frames "$(ls -d "$dir"/rec/*Z)" --json >"$dir/report.json" 2>/dev/null || fail "report --frames"
python3 -c "import json,sys; r=json.load(open(sys.argv[1])); assert r['frames'] == 481 and r['thumbnails'] >= 50 and r['warnings'] == 0, r" \
  "$dir/report.json" || fail "report with the recording: $(cat "$dir/report.json")"
echo "report: $(echo "$out" | grep '^wrote')"

# Damaged logs: the messages before the damage, then the error with the offset, exit 1.
size="$(wc -c <"$log")"
head -c $((size - 7)) "$log" >"$dir/cut.lcmlog"
out="$("$toposlam" listen --from "lcmlog:$dir/cut.lcmlog" 2>&1)"
rc=$?
[ "$rc" = 1 ] || fail "truncated log: exit $rc"
echo "$out" | grep -q "^toposlam: error: $dir/cut.lcmlog: truncated: the event announces .* (the log was cut short) (event [0-9]* at byte [0-9]* of $((size - 7)))$" \
  || fail "truncated log: $(echo "$out" | tail -2)"
[ "$(echo "$out" | grep -c '^place  frame')" -ge 480 ] || fail "truncated log: the messages before the cut were not printed"
printf 'NOPE' | dd of="$dir/cut.lcmlog" bs=1 seek=0 conv=notrunc 2>/dev/null
out="$("$toposlam" report "lcmlog:$dir/cut.lcmlog" 2>&1)"
rc=$?
[ "$rc" = 1 ] && echo "$out" | grep -q "no LCM sync word (0xEDA1DA01), found 0x4E4F5045: not an LCM log (event 0 at byte 0 of" \
  || fail "not a log: rc=$rc $out"
"$toposlam" listen --from "lcmfile:$log" >/dev/null 2>&1
[ $? = 2 ] || fail "--from without lcmlog: is not a usage error"
echo "lcmlog OK"
