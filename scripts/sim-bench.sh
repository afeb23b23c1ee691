#!/usr/bin/env bash
# The simulated worlds of the acceptance test (issue "one revisit decision"): the office and the home with
# world seeds 1-5, two laps each as ONE continuous stream, a day lap then a night lap of the office (two
# recordings), and the look-alike rooms of tests/data/worlds/twins.yaml (one lap, two laps). Each is mapped
# with the defaults (or the options after --) through the daemon's data path (`toposlam map`) and judged by
# the camera's pose (`toposlam eval`: frame_matches_by_pose, place_revisits). One table on stdout.
#
#   scripts/sim-bench.sh [BUILD_DIR] [WORK_DIR] [-- extra options for toposlam map]
#
# The worlds are rendered once into WORK_DIR/worlds and reused by later runs with the same WORK_DIR.
# Columns: published frame matches right / wrong by pose (2 m, 1 rad), the topology's place revisits
# closed right / wrong closures / missed (new node or left on the previous node) of all revisits, places,
# nodes.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
work="${2:-$(mktemp -d)}"
shift $(( $# >= 2 ? 2 : $# )) || true
[ "${1:-}" = "--" ] && shift
extra=("$@")
toposlam="$build/src/apps/toposlam/toposlam"
[ -x "$toposlam" ] || { echo "sim-bench: no $toposlam (build first: scripts/build.sh)" >&2; exit 2; }
worlds="$work/worlds"
mkdir -p "$worlds" "$work/runs"

render() {  # name world options...
  local name="$1"; shift
  [ -f "$worlds/$name/labels.csv" ] && return 0
  "$toposlam" sim "$@" --out "$worlds/$name" --progress 0 >/dev/null 2>"$worlds/$name.log" \
    || { echo "sim-bench: rendering $name failed: $(tail -2 "$worlds/$name.log")" >&2; exit 1; }
}
for s in 1 2 3 4 5; do
  render "office-s$s" office --seed "$s" --route loop2
  render "home-s$s" home --seed "$s" --route loop2
done
render day office --route loop --light day
render night office --route loop --light night
render twins "$root/tests/data/worlds/twins.yaml" --route loop
render twins2 "$root/tests/data/worlds/twins.yaml" --route loop2

run_world() {  # name sources... (truths follow the sources' order)
  local name="$1"; shift
  local sources=() truths=()
  for w in "$@"; do sources+=("images:$worlds/$w/frames"); truths+=(--truth "$worlds/$w/labels.csv"); done
  rm -rf "$work/runs/$name"
  "$toposlam" map "${sources[@]}" --out "$work/runs/$name" --quiet "${extra[@]}" >"$work/runs/$name.map.txt" 2>&1 \
    || { echo "sim-bench: map on $name failed: $(tail -2 "$work/runs/$name.map.txt")" >&2; return 1; }
  "$toposlam" eval "$work/runs/$name" "${truths[@]}" --json >"$work/runs/$name.eval.json" 2>/dev/null
}
names=()
for s in 1 2 3 4 5; do names+=("office-s$s" "home-s$s"); done
# Two at a time (the machine's cores); each map is one process.
pids=()
for n in "${names[@]}" twins twins2; do
  run_world "$n" "$n" & pids+=($!)
  if [ ${#pids[@]} -ge 2 ]; then wait "${pids[0]}"; pids=("${pids[@]:1}"); fi
done
run_world day-night day night & pids+=($!)
for p in "${pids[@]}"; do wait "$p"; done

echo "| world | published matches by pose right / wrong | topology: revisits closed / wrong / missed | places / nodes |"
echo "|---|---|---|---|"
for n in "${names[@]}" day-night twins twins2; do
  python3 - "$n" "$work/runs/$n.eval.json" <<'PY'
import json, sys
name, path = sys.argv[1:3]
e = json.load(open(path))
m = e.get("frame_matches_by_pose", {"right": 0, "wrong": 0})
v = e["place_revisits"]
nodes = e["topology"]["nodes"]
print("| %s | %d / %d | %d / %d / %d of %d | %d / %d |" % (
    name, m["right"], m["wrong"], v["closed_right"], v["wrong_closures"], v["missed"] + v["merged_with_previous"],
    v["revisits"], e["places"], nodes))
PY
done
