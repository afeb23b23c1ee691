#!/bin/sh
# --json on the commands that print results (issue 16: map, segment, sim, capture, report here; eval,
# fingerprint, similarity, localize, recognition, listen have their own tests; benchmarks: tests/bench) parses as JSON with the run's
# numbers; the one progress line (count, rate, ETA) shows on a terminal and stays out of pipes.
# Usage: check_json_and_progress.sh TOPOSLAM SAMPLES DIR
set -u
toposlam="$1" samples="$2" dir="$3"
rm -rf "$dir" && mkdir -p "$dir"
fail() { echo "FAIL: $*"; exit 1; }
field() { python3 -c "import json,sys; v=json.load(open(sys.argv[1]))
for k in sys.argv[2].split('.'): v=v[k]
print(v)" "$1" "$2"; }

"$toposlam" segment "images:$samples" --out "$dir/seg" --json >"$dir/segment.json" 2>/dev/null || fail "segment --json"
[ "$(field "$dir/segment.json" frames)" = 84 ] && [ "$(field "$dir/segment.json" places)" -ge 4 ] || fail "segment: $(cat "$dir/segment.json")"
"$toposlam" map "images:$samples" --out "$dir/map" --json >"$dir/map.json" 2>/dev/null || fail "map --json"
[ "$(field "$dir/map.json" frames)" = 84 ] && [ "$(field "$dir/map.json" nodes)" -ge 2 ] || fail "map: $(cat "$dir/map.json")"
[ "$(field "$dir/map.json" places)" = "$(($(wc -l <"$dir/map/places.csv") - 1))" ] || fail "map: places != places.csv"
"$toposlam" sim home --route loop --fps 1 --size 96x72 --out "$dir/sim" --json >"$dir/sim.json" 2>/dev/null || fail "sim --json"
[ "$(field "$dir/sim.json" frames)" = "$(($(wc -l <"$dir/sim/labels.csv") - 1))" ] && [ "$(field "$dir/sim.json" rooms)" -ge 3 ] \
  || fail "sim: $(cat "$dir/sim.json")"
"$toposlam" capture "images:$samples" -n 10 --json --record "$dir/rec" >"$dir/capture.json" 2>/dev/null || fail "capture --json"
[ "$(field "$dir/capture.json" frames)" = 10 ] && [ "$(field "$dir/capture.json" recorded.frames)" = 10 ] || fail "capture: $(cat "$dir/capture.json")"
"$toposlam" report "$dir/map" --json >"$dir/report.json" 2>/dev/null || fail "report --json"
[ "$(field "$dir/report.json" frames)" = 84 ] && [ "$(field "$dir/report.json" thumbnails)" -ge 50 ] || fail "report: $(cat "$dir/report.json")"
for f in segment map sim capture report; do python3 -m json.tool "$dir/$f.json" >/dev/null || fail "$f.json"; done
echo "json: segment, map, sim, capture, report parse with their numbers"

# Progress: forced on (as on a terminal), one line rewritten in place, then the summary; off in a pipe.
TOPOSLAM_PROGRESS=1 "$toposlam" map "images:$samples" --out "$dir/map2" 2>"$dir/progress.txt" >/dev/null || fail "map with progress"
tr '\r' '\n' <"$dir/progress.txt" | grep -q "^map: [0-9]*/84 frames  *[0-9]*%  [0-9.]* frames/s  ETA [0-9]*s" || fail "no progress line: $(head -c 400 "$dir/progress.txt")"
grep -q "^map: 84 frames in [0-9.]* s ([0-9.]* frames/s)$" "$dir/progress.txt" || fail "no summary line"
"$toposlam" map "images:$samples" --out "$dir/map3" 2>"$dir/quiet.txt" >/dev/null || fail "map in a pipe"
grep -q "frames/s" "$dir/quiet.txt" && fail "progress in a pipe: $(cat "$dir/quiet.txt")"
# A real terminal (script(1) gives the command a pty).
if command -v script >/dev/null 2>&1; then
  script -qec "\"$toposlam\" sim home --route loop --fps 1 --size 96x72 --out \"$dir/sim2\"" /dev/null >"$dir/tty.txt" 2>&1 \
    || fail "sim on a terminal: $(tail -c 300 "$dir/tty.txt")"
  grep -q "sim: [0-9]* frames in [0-9.]* s" "$dir/tty.txt" || fail "sim on a terminal: no summary: $(tail -c 300 "$dir/tty.txt")"
fi
echo "json and progress OK"
