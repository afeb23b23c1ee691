#!/usr/bin/env bash
# Soak test of toposlamd (issue 19): the daemon on the simulated office at camera rate (real time) for
# MINUTES, its resident memory sampled every SAMPLE_S seconds, then SIGTERM. Passes when it exits 0 after
# saving its map, dropped at most MAX_DROPPED frames (default 0: every captured frame published), its log
# holds no sanitizer report, and its RSS after warm-up (the first quarter of the run) grew by at most
# MAX_GROWTH_MB: the lowest sample of the first fifth of the samples after warm-up against the lowest of the
# last fifth. Memory the daemon holds is in every sample; memory in transit is not (ASan keeps freed
# blocks in a quarantine of up to 256 MB and unmaps the large ones in bursts, a saw-tooth of about 25 MB
# under the ASan soak), so a leak lifts the floor while the saw-tooth only moves the median: a median
# comparison failed one CI soak (20.3 MB) whose floor rose 9 MB and whose last sample was back at 346 MB.
# Prints the figures; the samples are in SOAK_DIR/rss.csv.
#
# Usage: [MINUTES=30] [FPS=15] [SIZE=320x240] [SAMPLE_S=10] [MAX_GROWTH_MB=24] [MAX_DROPPED=0] [SOAK_DIR=...]
#        scripts/soak.sh [BUILD_DIR]          (BUILD_DIR: default build/; an ASan build works as well)
# Runs inside tests/e2e/in_netns.sh, so its LCM multicast stays in a private network namespace.
# Exit: 0 pass, 1 a check failed, 77 no toposlamd in BUILD_DIR (skip).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
minutes="${MINUTES:-30}"
fps="${FPS:-15}"
size="${SIZE:-320x240}"
sample_s="${SAMPLE_S:-10}"
# 24 MB: the 16 MB that held before, plus what the per-frame answer keeps by design: every keyframe's
# fingerprint (docs/topology.md "Not solved yet", "Memory"): about 30 KB a keyframe under ASan, 180 keyframes
# in CI's 3-minute soak at 5 fps (measured on that soak: 10.4 MB of growth with the detector off, 15.7-16.0
# MB with it on). A leak of a frame's worth per frame still fails it.
max_growth_mb="${MAX_GROWTH_MB:-24}"
max_dropped="${MAX_DROPPED:-0}"
dir="${SOAK_DIR:-$build/soak}"
daemon="$build/src/apps/toposlamd/toposlamd"
[ -x "$daemon" ] || { echo "SKIP: no toposlamd in $build (build it first)"; exit 77; }

if [ -z "${TOPOSLAM_SOAK_INSIDE:-}" ]; then
  export TOPOSLAM_SOAK_INSIDE=1
  exec "$root/tests/e2e/in_netns.sh" "$0" "$@"
fi

rm -rf "$dir"
mkdir -p "$dir"
# loop20 at FPS: 20 laps of the office, about 53 minutes at 15 fps: longer than any soak asked for.
source_uri="sim:office?route=loop20&fps=$fps&size=$size&rate=$fps"
duration_s=$(( minutes * 60 ))
# The daemon's own log goes to a file; ASan's report (if any) too.
"$daemon" --source "$source_uri" --map "$dir/map.tsm" --lcm-url "udpm://239.255.76.67:7667?ttl=0" \
  --save-period 30 >"$dir/toposlamd.log" 2>&1 &
pid=$!
echo "soak: toposlamd (pid $pid) on $source_uri for $minutes min; RSS every ${sample_s} s; log $dir/toposlamd.log"

rss_kb() { awk '/^VmRSS:/ {print $2}' "/proc/$1/status" 2>/dev/null || true; }
: >"$dir/rss.csv"
echo "elapsed_s,rss_kb" >>"$dir/rss.csv"
start=$(date +%s)
while :; do
  now=$(date +%s)
  elapsed=$(( now - start ))
  kill -0 "$pid" 2>/dev/null || { echo "soak: FAIL: toposlamd ended by itself after ${elapsed} s"; break; }
  rss="$(rss_kb "$pid")"
  [ -n "$rss" ] && echo "$elapsed,$rss" >>"$dir/rss.csv"
  [ "$elapsed" -ge "$duration_s" ] && break
  sleep "$sample_s"
done
kill -TERM "$pid" 2>/dev/null || true
status=0
wait "$pid" || status=$?

fail=0
echo "soak: toposlamd exited $status"
[ "$status" -eq 0 ] || fail=1
# "toposlamd: N frames published, M dropped, P places, S map saves"
summary="$(grep -o '[0-9]* frames published, [0-9]* dropped, [0-9]* places, [0-9]* map saves' "$dir/toposlamd.log" | tail -1)"
echo "soak: ${summary:-no summary line in the log}"
dropped="$(echo "$summary" | sed -n 's/.* \([0-9]*\) dropped.*/\1/p')"
if [ -z "$dropped" ] || [ "$dropped" -gt "$max_dropped" ]; then
  echo "soak: FAIL: ${dropped:-an unknown number of} frames dropped (at most $max_dropped allowed)"; fail=1
fi
if grep -q "ERROR: AddressSanitizer\|ERROR: LeakSanitizer\|runtime error:" "$dir/toposlamd.log"; then
  echo "soak: FAIL: a sanitizer report in the log"; fail=1
fi
# RSS after warm-up: the lowest of its first fifth of samples against the lowest of its last fifth, MB
# (the medians are printed beside them).
awk -F, -v warm="$(( duration_s / 4 ))" -v limit="$max_growth_mb" '
  NR > 1 && $1 >= warm { t[n] = $1; r[n++] = $2 }
  NR > 1 { peak = $2 > peak ? $2 : peak }
  function sorted(a, lo, hi, s,   k, m, i, j, x) { m = 0; for (k = lo; k < hi; k++) s[m++] = a[k];
    for (i = 1; i < m; i++) for (j = i; j > 0 && s[j-1] > s[j]; j--) { x = s[j]; s[j] = s[j-1]; s[j-1] = x }
    return m }
  END {
    if (n < 5) { print "soak: FAIL: only " n " RSS samples after warm-up"; exit 1 }
    f = int(n / 5); if (f < 1) f = 1
    sorted(r, 0, f, a); sorted(r, n - f, n, b)
    first = a[0] / 1024; last = b[0] / 1024
    printf "soak: RSS floor after warm-up %.1f MB -> %.1f MB at the end (growth %.1f MB, limit %s MB; medians %.1f -> %.1f MB); peak %.1f MB; %d samples\n",
           first, last, last - first, limit, a[int(f / 2)] / 1024, b[int(f / 2)] / 1024, peak / 1024, n
    if (last - first > limit) { print "soak: FAIL: RSS grew"; exit 1 }
  }' "$dir/rss.csv" || fail=1
if [ "$fail" -eq 0 ]; then echo "soak: PASS"; else echo "soak: FAIL"; fi
exit "$fail"
