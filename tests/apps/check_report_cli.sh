#!/usr/bin/env bash
# `toposlam report` options through the command line (ctest label cli), on a small simulated run:
#   - --thresholds is shared with `eval`: the localisation table has exactly the rows asked for;
#   - a named frame missing from the frames folder is reported (`report: warning`), not silently replaced
#     by its neighbour in the folder listing.
# Usage: check_report_cli.sh TOPOSLAM WORK_DIR
set -euo pipefail
toposlam="$1"; work="$2"
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }

"$toposlam" sim home --route loop --fps 1 --progress 0 --out "$work/sim" 2>/dev/null
"$toposlam" map "images:$work/sim/frames" --out "$work/run" >/dev/null 2>&1

"$toposlam" report "$work/run" --truth "$work/sim/labels.csv" --thresholds 0.3 0.4 --out "$work/t.html" \
  >"$work/t.log" 2>&1 || { cat "$work/t.log"; fail "report --thresholds failed"; }
grep -q "<tr><td>0.3</td>" "$work/t.html" || fail "no localisation row for threshold 0.3"
grep -q "<tr><td>0.4</td>" "$work/t.html" || fail "no localisation row for threshold 0.4"
grep -q "<tr><td>0.5</td>" "$work/t.html" && fail "a default threshold row (0.5) is still there"
"$toposlam" report "$work/run" --truth "$work/sim/labels.csv" --thresholds 1.5 >"$work/bad.log" 2>&1 &&
  fail "--thresholds 1.5 was accepted"
grep -q "thresholds" "$work/bad.log" || fail "the error for --thresholds 1.5 does not name the option"
grep -q "report: warning" "$work/t.log" && fail "unexpected warning: $(cat "$work/t.log")"

rm "$work/sim/frames/000010.png"
"$toposlam" report "$work/run" --truth "$work/sim/labels.csv" --out "$work/m.html" >"$work/m.log" 2>&1
cat "$work/m.log"
grep -q "report: warning: 1 frames could not be read for thumbnails" "$work/m.log" ||
  fail "a missing frame file gave no warning"
echo "PASS"
