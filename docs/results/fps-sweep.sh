#!/usr/bin/env bash
# The segmentation window in seconds, measured (issue 14): the simulated office, two laps, rendered at
# several frame rates and mapped with the defaults; the places found should be the same whatever the rate.
# Prints, per rate: frames, places, nodes, wrong closures, and how many place borders (in seconds) fall
# within 1 s (one doorway: 0.5 m at 0.5 m/s) of a border of the 5 fps run, and the other way round.
# Usage: docs/results/fps-sweep.sh TOPOSLAM WORK_DIR [RATES...]   (default rates: 2 5 15 30)
set -euo pipefail
T=$(realpath "$1"); work=$2; shift 2
rates=("${@:-2 5 15 30}"); [ $# -eq 0 ] && rates=(2 5 15 30)
mkdir -p "$work"; cd "$work"
for fps in "${rates[@]}"; do
  [ -f "office-$fps/labels.csv" ] || "$T" sim office --route loop2 --fps "$fps" --out "office-$fps" --progress 0 >/dev/null
  start=$(date +%s.%N)
  "$T" map "images:office-$fps/frames?fps=$fps" --out "map-$fps" >/dev/null 2>"map-$fps.log"
  end=$(date +%s.%N)
  "$T" eval "map-$fps" --truth "office-$fps/labels.csv" --json > "eval-$fps.json" 2>/dev/null
  echo "$fps $(echo "$end - $start" | bc)" > "time-$fps.txt"
done
python3 - "${rates[@]}" <<'PY'
import csv, json, sys
rates = [float(r) for r in sys.argv[1:]]
def borders(fps):
    f = '%g' % fps
    rows = list(csv.DictReader(open('map-%s/places.csv' % f)))
    return [int(r['first']) / fps for r in rows[1:]]  # start of every place after the first, seconds
ref = borders(5.0) if 5.0 in rates else borders(rates[0])
print('fps  frames  places  nodes  wrong  borders  near_5fps  5fps_near  map_s')
for fps in rates:
    f = '%g' % fps
    d = json.load(open('eval-%s.json' % f))
    t = d['topology']
    b = borders(fps)
    near = sum(1 for x in b if min(abs(x - y) for y in ref) <= 1.0)
    back = sum(1 for y in ref if min(abs(x - y) for x in b) <= 1.0)
    frames = sum(1 for _ in open('map-%s/frames.csv' % f)) - 1
    secs = open('time-%s.txt' % f).read().split()[1]
    print('%-4s %6d  %6d  %5d  %5d  %7d  %9d  %9d  %5.1f' % (f, frames, len(b) + 1, t['nodes'], t['wrong_loop_closures'], len(b), near, back, float(secs)))
PY
