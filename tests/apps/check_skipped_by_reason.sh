#!/bin/sh
# Bad files among good frames, offline (issue 41 item 7): `toposlam map` and `toposlam segment` on a folder
# of 8 sample frames, 2 empty files and 1 JPEG whose data is garbage go on with the good frames and say
# what they skipped, by reason, as toposlamd's last log line does. Fails unless both exit 0 with
# "skipped 3 frames (truncated 2, corrupt 1)" and the 8 good frames mapped.
# Usage: check_skipped_by_reason.sh TOPOSLAM SAMPLES_DIR OUT_DIR
set -eu
toposlam=$1 samples=$2 out=$3
rm -rf "$out" && mkdir -p "$out/frames"
for i in 1 2 3 4 5 6 7 8; do cp "$samples/$i.jpg" "$out/frames/0$i.jpg"; done
: > "$out/frames/09.jpg"
: > "$out/frames/10.jpg"
printf '\377\330garbage, not image data\377\331' > "$out/frames/11.jpg"
"$toposlam" map "images:$out/frames" --out "$out/map" --quiet > "$out/map.txt" 2>&1 || { cat "$out/map.txt"; exit 1; }
"$toposlam" segment "images:$out/frames" --out "$out/segment" > "$out/segment.txt" 2>&1 || { cat "$out/segment.txt"; exit 1; }
grep -h "skipped" "$out/map.txt" "$out/segment.txt"
grep -q "^map: skipped 3 frames (truncated 2, corrupt 1)$" "$out/map.txt" || { echo "FAIL: map's skipped line"; exit 1; }
grep -q "^skipped frames: 3 (truncated 2, corrupt 1)$" "$out/segment.txt" || { echo "FAIL: segment's skipped line"; exit 1; }
grep -q "^8 frames -> " "$out/map.txt" || { echo "FAIL: the 8 good frames were not all mapped"; exit 1; }
echo "skipped by reason OK"
