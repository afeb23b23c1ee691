#!/bin/bash
# Frame-level loop closures (docs/topology.md, "Frame level by sequences"): `toposlam map` + `toposlam eval`
# on the real samples, the corridor set played as one sequence and the simulated office (two laps), for
# the sequence detector at several decays and the detections read off the topology (visits), each beside
# the plain ORB baseline of the same run (`toposlam recognition` on the same frames, each frame's best
# earlier frame at least 25 frames back, single frames and sequences of 10).
# Usage: docs/results/frame-loops.sh TOPOSLAM OFFICE_DIR WORK_DIR
#   OFFICE_DIR: `toposlam sim office --route loop2 --out OFFICE_DIR`
set -u
repo="$(cd "$(dirname "$0")/../.." && pwd)"
T=$1 O=$2 work=$3
S=$repo/tests/data/rtabmap-samples; C=$repo/tests/data/vprbench-corridor
mkdir -p "$work/corridor-one-sequence" && cd "$work"
# The corridor's two laps as one folder (a### = reference lap, b### = query lap) and its pairs truth.
for i in $(seq 0 110); do
  n=$(printf %07d "$i"); k=$(printf %03d "$i")
  ln -sf "$C/ref/$n.jpg" "corridor-one-sequence/a$k.jpg"; ln -sf "$C/query/$n.jpg" "corridor-one-sequence/b$k.jpg"
done
python3 - "$C/gt.csv" > corridor-one-sequence.csv <<'PY'
import csv, sys
print("query_image,matching_ref_images")
for r in csv.DictReader(open(sys.argv[1])):
    q = int(r["query_image"][6:13]); m = [int(x[4:11]) for x in r["matching_ref_images"].split()]
    print("b%03d.jpg,%s" % (q, " ".join("a%03d.jpg" % i for i in m)))
PY
r100() {  # RUN TRUTH [eval options]: recall at 100 % precision, right detections / frames with a match
  local run=$1 truth=$2; shift 2
  $T eval "$run" --truth "$truth" "$@" --json | python3 -c '
import json, sys
c = json.load(sys.stdin)["frame_loop_closure"]
print("%.3f (%d of %d)" % (c["recall_at_100_precision"], c["right_detections"], c["frames_with_match"]))'
}
row() {  # NAME TRUTH MAP_ARGS...: one table row
  local name=$1 truth=$2; shift 2
  local out="run-$(echo "$name" | tr -c 'a-z0-9' '-')"
  local start=$(date +%s.%N)
  $T map "$@" --out "$out" >/dev/null 2>&1 || { echo "| $name | map failed |"; return; }
  local secs=$(echo "$(date +%s.%N) - $start" | bc)
  printf '| %s | %s | %.1f s |\n' "$name" "$(r100 "$out" "$truth")" "$secs"
}
echo "| run | frame-level recall at 100 % precision (right of frames with a match) | map time |"
echo "|---|---|---|"
for kp in 100 200; do
  for d in 0.9 0.95 0.975 0.99; do
    row "samples, $kp keypoints, sequence decay $d" "$S/samples_GT_pairs.csv" "images:$S/samples" --max-keypoints $kp --loop-decay $d
    row "corridor, $kp keypoints, sequence decay $d" "$C/gt.csv" "images:$C/ref" "images:$C/query" --max-keypoints $kp --loop-decay $d
  done
  row "samples, $kp keypoints, visits" "$S/samples_GT_pairs.csv" "images:$S/samples" --max-keypoints $kp --frame-loops visits
  row "corridor, $kp keypoints, visits" "$C/gt.csv" "images:$C/ref" "images:$C/query" --max-keypoints $kp --frame-loops visits
done
for d in 0.95 0.975; do
  row "office loop2, 100 keypoints, sequence decay $d" "$O/labels.csv" "images:$O/frames" --loop-decay $d
done
row "office loop2, 100 keypoints, visits" "$O/labels.csv" "images:$O/frames" --frame-loops visits
echo
echo "== ORB baseline, same frames (recognition: each frame's best earlier frame >= 25 back)"
for kp in 100 200; do
  echo "-- samples, $kp keypoints"
  $T recognition "images:$S/samples" --truth "$S/samples_GT_pairs.csv" --min-gap 25 --max-keypoints $kp --sequence 10 --quiet | grep -E "toposlam \(|ORB baseline"
  echo "-- corridor as one sequence, $kp keypoints"
  $T recognition "images:$work/corridor-one-sequence" --truth corridor-one-sequence.csv --min-gap 25 --max-keypoints $kp --sequence 10 --quiet | grep -E "toposlam \(|ORB baseline"
done
