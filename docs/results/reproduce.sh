#!/usr/bin/env bash
# Reproduces every figure and table of docs/results.md: simulated worlds (office and home; one traversal
# by day then one by night; and two traversals by day), the 84 bundled real frames (default window, and
# --window 5 for their ~1 Hz keyframes, docs/segmentation.md), then `toposlam eval` and `toposlam report`
# on each run. Default settings otherwise. Usage: docs/results/reproduce.sh [BUILD_DIR] [WORK_DIR]
# Figures go to docs/results/<run>/ (SVG), reports and run folders to WORK_DIR (default /tmp/toposlam-results).
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
build="${1:-$repo/build}"
work="${2:-/tmp/toposlam-results}"
toposlam="$build/src/apps/toposlam/toposlam"
samples="$repo/tests/data/rtabmap-samples"
figures="$repo/docs/results"
mkdir -p "$work"

# Real frames: 84 images, loop-closure ground truth samples_GT.bmp.
"$toposlam" map "images:$samples/samples" --out "$work/samples"
"$toposlam" eval "$work/samples" --truth "$samples/samples_GT.bmp" > "$work/samples/eval.txt"
"$toposlam" report "$work/samples" --truth "$samples/samples_GT.bmp" --frames "$samples/samples" \
  --figures "$figures/samples"

# The same frames segmented as ~1 Hz keyframes: a 5-frame window (the thesis' 5 s at 1 Hz).
"$toposlam" map "images:$samples/samples" --window 5 --out "$work/samples-window5"
"$toposlam" eval "$work/samples-window5" --truth "$samples/samples_GT.bmp" > "$work/samples-window5/eval.txt"
"$toposlam" report "$work/samples-window5" --truth "$samples/samples_GT.bmp" --frames "$samples/samples" \
  --figures "$figures/samples-window5"

for world in office home; do
  # Two traversals of the same loop, the first by day and the second by night.
  for light in day night; do
    "$toposlam" sim "$world" --route loop --light "$light" --out "$work/sim-$world-$light" --progress 0
  done
  "$toposlam" map "images:$work/sim-$world-day/frames" "images:$work/sim-$world-night/frames" \
    --out "$work/$world-day-night"
  truth=(--truth "$work/sim-$world-day/labels.csv" --truth "$work/sim-$world-night/labels.csv")
  "$toposlam" eval "$work/$world-day-night" "${truth[@]}" > "$work/$world-day-night/eval.txt"
  "$toposlam" report "$work/$world-day-night" "${truth[@]}" \
    --frames "$work/sim-$world-day/frames" --frames "$work/sim-$world-night/frames" \
    --figures "$figures/$world-day-night"

  # Two traversals by day in one stream (route loop2); labels.csv's traversal column splits them.
  "$toposlam" sim "$world" --route loop2 --light day --out "$work/sim-$world-loop2" --progress 0
  "$toposlam" map "images:$work/sim-$world-loop2/frames" --out "$work/$world-loop2"
  "$toposlam" eval "$work/$world-loop2" --truth "$work/sim-$world-loop2/labels.csv" \
    > "$work/$world-loop2/eval.txt"
  "$toposlam" report "$work/$world-loop2" --truth "$work/sim-$world-loop2/labels.csv" \
    --frames "$work/sim-$world-loop2/frames" --figures "$figures/$world-loop2"
done
echo "reports: $work/*/report.html; tables: $work/*/eval.txt; figures: $figures/*/"
