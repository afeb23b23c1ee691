#!/usr/bin/env bash
# The README's first command: sets up, builds, and runs the main job on the embedded default
# (no camera needed):
#   1. toposlamd, the real-time pipeline, on its default source (the simulated office, two laps),
#      publishing over LCM while `toposlam listen` prints the place messages as they arrive;
#   2. the same stream offline: map, accuracy against the simulator's ground truth, HTML report.
# Outputs go to out/demo/ (override with OUT=DIR). Set SKIP_SETUP=1 to skip apt and the build, and
# BUILD_DIR=DIR to use another build tree (default build/).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
out="${OUT:-$root/out/demo}"
build="${BUILD_DIR:-$root/build}"

# Each stage's start with the time since the demo began (the target: 10 minutes on an idle 2-core machine
# with no packages installed yet).
stage() { echo "== $* [$((SECONDS / 60)) min $((SECONDS % 60)) s in]"; }
if [ "${SKIP_SETUP:-0}" != "1" ]; then
  stage "packages (scripts/setup.sh: build and runtime only)"
  scripts/setup.sh
  # Only the two programs the demo runs: the tests, benchmarks and examples are scripts/test.sh's.
  stage "building toposlam and toposlamd (Release, into ${build#"$root"/})"
  BUILD_TARGETS="toposlam toposlamd" scripts/build.sh "$build"
fi
toposlam="$build/src/apps/toposlam/toposlam"
toposlamd="$build/src/apps/toposlamd/toposlamd"
for exe in "$toposlam" "$toposlamd"; do
  [ -x "$exe" ] || { echo "run-demo: $exe is missing; run without SKIP_SETUP=1 to build it" >&2; exit 1; }
done
rm -rf "$out"
mkdir -p "$out"
source_uri="sim:office?route=loop2"

stage "1/2 live: toposlamd on $source_uri, place messages over LCM"
# The daemon and the listener share a private network namespace with multicast on loopback, so the
# demo needs no network set-up and sends nothing outside. `--overflow block` replays the simulated
# camera losslessly as fast as the pipeline runs; the default `auto` picks it for the simulator anyway (and
# drop_oldest for a real camera), it is spelled out so a config file cannot change the demo.
live_run() {
  "$toposlam" listen --channels TOPOSLAM_PLACE_EVENT,TOPOSLAM_STATUS --timeout 120 &
  listener=$!
  sleep 0.5
  status=0
  "$toposlamd" --source "$source_uri" --overflow block --no-map-load --map "$out/live-map.tsm" || status=$?
  sleep 1  # let the last messages arrive
  kill "$listener" 2>/dev/null || true
  wait "$listener" 2>/dev/null || true
  return "$status"
}
export -f live_run
export toposlam toposlamd source_uri out
netns_setup='ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo'
if unshare -rn true 2>/dev/null && command -v ip >/dev/null; then
  unshare -rn bash -c "$netns_setup && live_run"
elif ip route get 224.0.0.1 >/dev/null 2>&1; then
  echo "run-demo: no private network namespace here; using the host's multicast route (ttl=0: host only)"
  live_run
else
  echo "run-demo: no network namespace and no multicast route; running the daemon without a listener"
  "$toposlamd" --source "$source_uri" --overflow block --no-map-load --map "$out/live-map.tsm" \
    --lcm-url "memq://"
fi

echo
stage "2/2 offline: the same route with ground truth -> map, accuracy, report"
"$toposlam" sim office --route loop2 --out "$out/sim"
"$toposlam" map "images:$out/sim/frames" --out "$out/map"
"$toposlam" eval "$out/map" --truth "$out/sim/labels.csv"
"$toposlam" report "$out/map" --truth "$out/sim/labels.csv" --frames "$out/sim/frames" \
  --out "$out/report.html"

echo
stage "done"
echo "run-demo: done. Open $out/report.html (figures and tables); the map drawing is $out/map/topology.svg"
echo "          and the live daemon's map file is $out/live-map.tsm."
