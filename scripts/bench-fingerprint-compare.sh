#!/usr/bin/env bash
# Before/after timing of VPACK extraction in one run: two builds take turns, ROUNDS times, on
# `toposlam-bench fingerprint` (ORB, one worker, both sizes); the second also times the camera formats.
# Usage: scripts/bench-fingerprint-compare.sh BEFORE_BIN AFTER_BIN [ROUNDS]
# A BIN is a toposlam-bench (build/bench/toposlam-bench), or a toposlam from before issue 15, when the
# benchmarks were its `bench` subcommand.
# (BEFORE_BIN: a build of the commit to compare against, e.g. `git worktree add /tmp/before 6086850` and
# scripts/build.sh there.) Prints each round's tables, then the median over the rounds of each row's median.
set -euo pipefail
before=$1 after=$2 rounds=${3:-5}
log=$(mktemp)
# fingerprint_bench BIN ARGS...: the fingerprint benchmark of BIN, a toposlam-bench or an older toposlam.
fingerprint_bench() {
  local bin=$1
  shift
  case "$(basename "$bin")" in
    toposlam-bench*) "$bin" fingerprint "$@" ;;
    *) "$bin" bench fingerprint "$@" ;;
  esac
}
for round in $(seq "$rounds"); do
  echo "== round $round: before" | tee -a "$log"
  fingerprint_bench "$before" --keypoints orb --workers 1 --repeat 3 | sed 's/^\([0-9]*x[0-9]*\) *orb /\1 orb bgr /' |
    awk '{print "before", $0}' | tee -a "$log"
  echo "== round $round: after" | tee -a "$log"
  fingerprint_bench "$after" --keypoints orb --workers 1 --repeat 3 \
    --formats bgr yuyv-via-bgr yuyv grey-via-bgr grey | awk '{print "after", $0}' | tee -a "$log"
done
echo
echo "median over $rounds rounds of the per-round median ms (size, format: before-binary, after-binary)"
awk '$2 ~ /^[0-9]+x[0-9]+$/ && $3 == "orb" { key = $2 " " $4 " " $1; v[key] = v[key] " " $6 }
     END { for (k in v) print k, v[k] }' "$log" |
  while read -r size format who values; do
    median=$(tr ' ' '\n' <<<"$values" | grep -v '^$' | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}')
    echo "$size $format $who $median"
  done | sort
rm -f "$log"
