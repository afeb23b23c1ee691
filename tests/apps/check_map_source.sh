#!/bin/sh
# A map records its source (issue 16): toposlamd and `toposlam map` refuse to continue a map made from
# another source (exit 2, naming both) unless told to; the shipped config reads the camera and waits,
# saying so, while /dev/video0 is absent.
# Usage: check_map_source.sh TOPOSLAM TOPOSLAMD SHIPPED_CONFIG SAMPLES DIR
set -u
toposlam="$1" toposlamd="$2" shipped="$3" samples="$4" dir="$5"
rm -rf "$dir" && mkdir -p "$dir/office" "$dir/lab"
fail() { echo "FAIL: $*"; exit 1; }
for i in 1 2 3 4 5 6 7 8 9 10 11 12; do cp "$samples/$i.jpg" "$dir/office/"; cp "$samples/$((i + 40)).jpg" "$dir/lab/"; done
daemon() { "$toposlamd" --map "$dir/map.tsm" --lcm-url memq:// --log-level warn "$@" 2>&1; }

# 1. toposlamd: made from the office, refused from the lab (exit 2, both named), continued when told to, and
#    from then on the map records the lab.
out="$(daemon --source "images:$dir/office?fps=5")" || fail "first run: $out"
out="$(daemon --source "images:$dir/lab")"
rc=$?
[ "$rc" = 2 ] || fail "another source exited $rc, not 2: $out"
echo "$out" | grep -qF "toposlamd: error: the map $dir/map.tsm was made with source=images:$dir/office but this run uses source=images:$dir/lab" \
  || fail "the refusal does not name both sources: $out"
echo "$out" | grep -qF -- "--resume-other-source" || fail "the refusal does not say how to override: $out"
out="$(daemon --source "images:$dir/office?fps=10")" || fail "the same source with another rate was refused: $out"
out="$(daemon --source "images:$dir/lab" --resume-other-source)" || fail "--resume-other-source exited $?: $out"
echo "$out" | grep -qF "was made from images:$dir/office; continuing it from images:$dir/lab" || fail "no warning: $out"
out="$(daemon --source "images:$dir/lab")" || fail "the map did not record the lab after the override: $out"
printf 'map:\n  resume_other_source: true\n' >"$dir/other.yaml"
out="$(daemon -c "$dir/other.yaml" --source "images:$dir/office")" || fail "map.resume_other_source: true exited $?: $out"
echo "toposlamd: refused with exit $rc, continued with --resume-other-source and map.resume_other_source"

# 2. toposlam map --resume: the same rule, and --keypoints is named too.
"$toposlam" map "images:$dir/office" --window 5 --out "$dir/run1" >/dev/null 2>&1 || fail "map run1"
out="$("$toposlam" map "images:$dir/lab" --window 5 --resume "$dir/run1/map.tsm" --out "$dir/run2" 2>&1)"
rc=$?
[ "$rc" = 2 ] || fail "map --resume from another source exited $rc: $out"
echo "$out" | grep -qF "map: the map $dir/run1/map.tsm was made with source=images:$dir/office but this run uses source=images:$dir/lab: continue it with the same settings, or start a new map (--resume-other-source continues it from this source)" \
  || fail "map refusal: $out"
out="$("$toposlam" map "images:$dir/lab" --window 5 --resume "$dir/run1/map.tsm" --keypoints sift --out "$dir/run2" 2>&1)"
echo "$out" | grep -qF "made with keypoints=orb, source=images:$dir/office but this run uses keypoints=sift, source=images:$dir/lab" \
  || fail "map refusal naming both settings: $out"
out="$("$toposlam" map "images:$dir/lab" --window 5 --resume "$dir/run1/map.tsm" --resume-other-source --keypoints sift --out "$dir/run2" 2>&1)"
[ $? = 2 ] && echo "$out" | grep -qF "made with keypoints=orb but this run uses keypoints=sift" \
  || fail "--resume-other-source must not waive the keypoints: $out"
"$toposlam" map "images:$dir/lab" --window 5 --resume "$dir/run1/map.tsm" --resume-other-source --out "$dir/run2" >/dev/null 2>&1 \
  || fail "map --resume-other-source exited $?"
"$toposlam" map "images:$dir/lab" --resume-other-source --out "$dir/run3" >/dev/null 2>&1
[ $? = 2 ] || fail "--resume-other-source without --resume is not a usage error"
echo "toposlam map: refused with exit $rc, continued with --resume-other-source"

# 3. The shipped config reads /dev/video0 and, while it is absent, waits and says so; SIGTERM ends it with 0.
if [ -e /dev/video0 ]; then echo "shipped config: /dev/video0 exists here, not checked"; echo "map source OK"; exit 0; fi
"$toposlamd" -c "$shipped" --map "$dir/camera.tsm" --lcm-url memq:// >"$dir/camera.log" 2>&1 &
pid=$!
i=0
while [ $i -lt 100 ] && ! grep -q "waiting for the camera" "$dir/camera.log"; do sleep 0.1; i=$((i + 1)); done
kill -TERM $pid
wait $pid
rc=$?
grep -qF "v4l2:/dev/video0: no such device yet; waiting for the camera" "$dir/camera.log" \
  || fail "the shipped config does not wait for /dev/video0: $(cat "$dir/camera.log")"
[ "$rc" = 0 ] || fail "SIGTERM while waiting for the camera exited $rc"
echo "shipped config: waiting for v4l2:/dev/video0 after $((i * 100)) ms, SIGTERM exit 0"
echo "map source OK"
