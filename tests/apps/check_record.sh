#!/bin/sh
# toposlam capture URI --record DIR and its replay (issue 16): frames and timestamps.csv written, played
# back by images:DIR?rate=recorded at the recorded pace (a lower bound on the wall time: never faster than
# recorded), re-processed offline by `map`; a folder holding a recording is refused; the size bound stops
# the capture. The simulator stands in for the camera (10 fps timestamps).
# Usage: check_record.sh TOPOSLAM DIR
set -u
toposlam="$1" dir="$2"
rm -rf "$dir" && mkdir -p "$dir"
fail() { echo "FAIL: $*"; exit 1; }
rec="$dir/run"
out="$("$toposlam" capture "sim:office?route=loop&fps=10&size=160x120" --count 30 --record "$rec" -q 2>&1)" || fail "capture: $out"
echo "$out" | grep -q "^recorded 30 frames ([0-9.]* MB) into $rec; play back: images:$rec?rate=recorded$" || fail "capture: $out"
[ "$(ls "$rec" | grep -c '\.jpg$')" = 30 ] || fail "not 30 frames in $rec"
[ "$(sed -n 2p "$rec/timestamps.csv")" = "000000.jpg,0.000000" ] && [ "$(sed -n 31p "$rec/timestamps.csv")" = "000029.jpg,2.900000" ] \
  || fail "timestamps.csv: $(head -3 "$rec/timestamps.csv")"

# Replay at the recorded pace: 29 intervals of 0.1 s.
out="$("$toposlam" capture "images:$rec?rate=recorded" --count 30 -q 2>&1)" || fail "replay: $out"
seconds="$(echo "$out" | sed -n 's/.* seconds=\([0-9.]*\) fps=\([0-9.]*\) .*/\1/p')"
fps="$(echo "$out" | sed -n 's/.* seconds=\([0-9.]*\) fps=\([0-9.]*\) .*/\2/p')"
[ "$fps" = "10.00" ] || fail "replayed timestamps give $fps fps: $out"
awk -v s="$seconds" 'BEGIN { exit !(s >= 2.85 && s < 30) }' || fail "replay took $seconds s, expected >= 2.9 s: $out"
echo "replayed 30 frames in $seconds s (recorded over 2.9 s), timestamps at $fps fps"
# Without rate=recorded: as fast as read, same timestamps.
out="$("$toposlam" capture "images:$rec" --count 30 -q 2>&1)" || fail "fast replay: $out"
echo "$out" | grep -q "fps=10.00" || fail "fast replay: $out"

# Re-processed offline.
"$toposlam" map "images:$rec" --window 5 --out "$dir/map" 2>/dev/null | grep -q "^30 frames -> [0-9]* places" || fail "map of the recording"

# Refusals and the size bound.
out="$("$toposlam" capture "sim:office?route=loop&fps=10&size=160x120" --count 3 --record "$rec" -q 2>&1)"
rc=$?
[ "$rc" = 1 ] && echo "$out" | grep -qF "record: $rec already holds a recording (" || fail "second recording into $rec: rc=$rc $out"
"$toposlam" capture "sim:office?route=loop&fps=10" --count 3 --record-format png >/dev/null 2>&1
[ $? = 2 ] || fail "--record-format without --record is not a usage error"
out="$("$toposlam" capture "sim:office?route=loop&fps=10&size=160x120" --count 30 --record "$dir/small" --record-max-mb 0.02 -q 2>&1)"
rc=$?
n="$(ls "$dir/small" | grep -c '\.jpg$')"
[ "$rc" = 0 ] && [ "$n" -ge 1 ] && [ "$n" -lt 30 ] && echo "$out" | grep -q "reached after $n frames" || fail "size bound: rc=$rc, $n frames: $out"
echo "size bound: $n frames within 0.02 MB"
echo "record OK"
