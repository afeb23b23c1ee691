#!/bin/sh
# The VPR-Bench corridor's two laps as ONE continuous stream, with no hint where the second lap begins:
# OUT/frames/000000.jpg .. 000221.jpg (symbolic links: the reference lap's 111 frames, then the query lap's)
# and OUT/gt_pairs.csv, gt.csv's pairs under those names (a pairs CSV for `toposlam eval` and
# `toposlam recognition`). Used by scripts/real-bench.sh and the corridor's regression test.
# Usage: scripts/corridor-stream.sh CORRIDOR_DIR OUT_DIR
set -eu
corridor=$(cd "$1" && pwd) out=$2
rm -rf "$out/frames" && mkdir -p "$out/frames"
i=0
for lap in ref query; do
  for f in $(ls "$corridor/$lap" | sort); do
    ln -s "$corridor/$lap/$f" "$out/frames/$(printf '%06d' "$i").jpg"
    i=$((i + 1))
  done
done
[ "$i" = 222 ] || { echo "corridor-stream: expected 222 frames in $corridor/ref and $corridor/query, found $i" >&2; exit 1; }
python3 - "$corridor/gt.csv" "$out/gt_pairs.csv" <<'PY'
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))[1:]
def renamed(name):
    lap, file = name.split("/")
    return "%06d.jpg" % (int(file.split(".")[0]) + (111 if lap == "query" else 0))
with open(sys.argv[2], "w") as out:
    out.write("query_image,matching_images\n")
    for query, matches in rows:
        out.write("%s,%s\n" % (renamed(query), " ".join(renamed(m) for m in matches.split())))
PY
