#!/bin/bash
# The per-frame answer's margin over the runner-up on the three real sets, each as one stream
# (docs/results.md, "The per-frame answer on look-alike floors"): `toposlam map` at each margin
# (--loop-min-margin), every other setting the default, read off frames.csv (the published answer) by
# `toposlam eval`. ie-tower has no revisit, so every match it publishes is wrong. Then the leave-one-set-out
# choice with the rule of "The per-frame answer, leave one set out" (most published right matches with none
# wrong, ties to the larger margin) and, where no margin publishes none wrong, the fewest wrong.
# Usage: docs/results/frame-margin-real.sh BUILD_DIR WORK_DIR   (about 5 minutes on 2 cores)
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
build=$1 work=$2
T="$build/src/apps/toposlam/toposlam"
[ -x "$T" ] || { echo "frame-margin-real: no $T (build first: scripts/build.sh)" >&2; exit 2; }
mkdir -p "$work/runs"
"$repo/scripts/corridor-stream.sh" "$repo/tests/data/vprbench-corridor" "$work/corridor" >/dev/null
declare -A source truth
source[samples]="images:$repo/tests/data/rtabmap-samples/samples"
truth[samples]="$repo/tests/data/rtabmap-samples/samples_GT.bmp"
source[corridor]="images:$work/corridor/frames"
truth[corridor]="$work/corridor/gt_pairs.csv"
source[ie-tower]="images:$repo/tests/data/ie-tower/frames"
truth[ie-tower]="$repo/tests/data/ie-tower/labels.csv"
margins=(0.5 1 2 3)
for margin in "${margins[@]}"; do
  for set in samples corridor ie-tower; do
    run="$work/runs/$set-margin$margin"
    [ -f "$run.json" ] && continue
    "$T" map "${source[$set]}" --out "$run" --quiet --loop-min-margin "$margin" >/dev/null 2>&1
    "$T" eval "$run" --truth "${truth[$set]}" --json >"$run.json" 2>/dev/null
  done
done
python3 - "$work/runs" "${margins[@]}" <<'PY'
import json, sys
runs, margins = sys.argv[1], sys.argv[2:]
sets = ["samples", "corridor", "ie-tower"]
fig = {}
for s in sets:
    for m in margins:
        e = json.load(open(f"{runs}/{s}-margin{m}.json"))["frame_loop_closure"]
        fig[s, m] = (e["right_detections"], e["detections"] - e["right_detections"], e["frames_with_match"],
                     e["recall_at_100_precision"])
print("| margin | " + " | ".join(f"{s}: right / wrong of frames with a match (recall at 100 % precision)" for s in sets) + " |")
print("|---" * (len(sets) + 1) + "|")
for m in margins:
    print(f"| {m} | " + " | ".join("%d / %d of %d (%.3f)" % fig[s, m] for s in sets) + " |")
def choose(train):
    clean = [m for m in margins if all(fig[s, m][1] == 0 for s in train)]
    if clean:  # most right with none wrong; ties to the larger margin
        return max(clean, key=lambda m: (sum(fig[s, m][0] for s in train), float(m))), "none wrong"
    return min(margins, key=lambda m: (sum(fig[s, m][1] for s in train), -float(m))), "fewest wrong"
print()
print("| held out | margin chosen on the other two | rule that chose it | its figure there | with the default 0.5 |")
print("|---|---|---|---|---|")
for held in sets:
    m, rule = choose([s for s in sets if s != held])
    print(f"| {held} | {m} | {rule} | " + "%d / %d of %d (%.3f)" % fig[held, m] + " | " + "%d / %d of %d (%.3f)" % fig[held, "0.5"] + " |")
PY
