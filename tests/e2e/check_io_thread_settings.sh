#!/bin/sh
# The daemon's I/O threads come from the one thread table (pipeline.threads.lcm_receiver / .recorder):
# names and nice values set in the config file are the ones the running toposlamd's threads carry. The
# fingerprint stage's pool threads (tsl-vpack-N) take the fingerprint thread's nice.
# Exits 77 (skipped) without /proc. Usage: check_io_thread_settings.sh TOPOSLAMD SAMPLES_DIR WORK_DIR
set -eu
toposlamd=$1 samples=$2 work=$3
[ -d /proc/self/task ] || { echo "skipped: no /proc/self/task here"; exit 77; }
# Threads without a nice of their own keep the one the test runs at (ctest under `nice` passes it on); the
# configured values are set above it, where any process may go, so that the check runs (and passes) at any
# nice up to 14 as any user, and at any nice as root (which may lower a thread's nice).
base=$(cut -d' ' -f19 /proc/$$/stat)
if [ "$base" -le 14 ]; then
  fingerprint_nice=$((base + 3)) recorder_nice=$((base + 5))
elif [ "$(id -u)" = 0 ]; then
  fingerprint_nice=3 recorder_nice=5
else
  echo "skipped: running at nice $base, which leaves no room above it for the configured values"; exit 77
fi
rm -rf "$work" && mkdir -p "$work"
cat > "$work/config.yaml" <<YAML
fingerprint:
  workers: 3
pipeline:
  threads:
    fingerprint:
      nice: $fingerprint_nice
    lcm_receiver:
      name: tsl-rx-custom
    recorder:
      name: tsl-rec-custom
      nice: $recorder_nice
YAML
# At 1 frame a second the samples last 84 s: the daemon is still running when a slow look at it ends (under
# `nice` on a busy machine a look at its threads took longer than the 17 s the source lasted at 5 Hz).
"$toposlamd" --config "$work/config.yaml" --source "images:$samples?rate=1" --lcm-url memq:// --map "" \
  --record "$work/rec" > "$work/daemon.log" 2>&1 &
pid=$!
# Every thread as configured, each name with its nice value: a thread is named before it sets its nice, and
# the pool threads start after the fingerprint thread; a test at a lower priority than the jobs beside it
# (under `nice`) sees them a while apart, so it waits for the whole set (up to 40 s by the clock, however slow
# each look is) rather than the first names.
expected="tsl-fingerprint $fingerprint_nice
tsl-rec-custom $recorder_nice
tsl-rx-custom $base
tsl-vpack-1 $fingerprint_nice
tsl-vpack-2 $fingerprint_nice"
threads() { for t in /proc/$pid/task/*; do echo "$(cat "$t/comm" 2>/dev/null) $(cut -d' ' -f19 "$t/stat" 2>/dev/null)"; done | sort; }
all_there() { echo "$expected" | while read -r line; do echo "$found" | grep -qx "$line" || exit 1; done; }
found=""
deadline=$(($(date +%s) + 40))
while [ "$(date +%s)" -lt "$deadline" ]; do
  sleep 0.25
  found=$(threads)
  all_there && break
  kill -0 $pid 2>/dev/null || break
done
kill -TERM $pid 2>/dev/null || true
wait $pid || true
echo "$found"
missing=$(echo "$expected" | while read -r line; do echo "$found" | grep -qx "$line" || echo "$line"; done)
[ -z "$missing" ] || { echo "threads missing or at another nice (name nice): $missing"; cat "$work/daemon.log"; exit 1; }
if echo "$found" | grep -q "tsl-lcm-rx\|tsl-record"; then echo "a default I/O thread name is still used"; exit 1; fi
echo "io threads as configured"
