#!/bin/sh
# Real-data regression test of frame-level loop closures on the corridor set played as one sequence
# (reference lap, then query lap; docs/topology.md "Frame level by sequences"): `toposlam map` with the
# default preset, then with 200 keypoints per frame, and `toposlam eval` against gt.csv. Fails when the
# recall at 100 % precision falls below 0.9 (measured 0.982, 109 of 111, with the defaults; 1.000 with
# 200 keypoints) or more than a few second-lap frames go undetected.
# Usage: check_corridor_loop_closure.sh TOPOSLAM CORRIDOR_DIR OUT_DIR
set -eu
toposlam=$1 corridor=$2 out=$3
rm -rf "$out"
"$toposlam" map "images:$corridor/ref" "images:$corridor/query" --out "$out/default" >/dev/null 2>&1
"$toposlam" eval "$out/default" --truth "$corridor/gt.csv" --json > "$out/default.json"
"$toposlam" map "images:$corridor/ref" "images:$corridor/query" --max-keypoints 200 --out "$out/kp200" >/dev/null 2>&1
"$toposlam" eval "$out/kp200" --truth "$corridor/gt.csv" --json > "$out/kp200.json"
python3 - "$out/default.json" "$out/kp200.json" <<'PY'
import json, sys
ok = True
for name, path in (("defaults", sys.argv[1]), ("200 keypoints", sys.argv[2])):
    c = json.load(open(path))["frame_loop_closure"]
    print("corridor as one sequence, %s: recall at 100%% precision %.3f, right %d of %d frames with a match"
          % (name, c["recall_at_100_precision"], c["right_detections"], c["frames_with_match"]))
    ok = ok and c["frames_with_match"] == 111 and c["recall_at_100_precision"] >= 0.9 and c["right_detections"] >= 105
sys.exit(0 if ok else 1)
PY
