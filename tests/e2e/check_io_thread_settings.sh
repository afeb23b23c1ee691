#!/bin/sh
# The daemon's I/O threads come from the one thread table (pipeline.threads.lcm_receiver / .recorder):
# names and nice values set in the config file are the ones the running toposlamd's threads carry. The
# fingerprint stage's pool threads (tsl-vpack-N) take the fingerprint thread's nice.
# Exits 77 (skipped) without /proc. Usage: check_io_thread_settings.sh TOPOSLAMD SAMPLES_DIR WORK_DIR
set -eu
toposlamd=$1 samples=$2 work=$3
[ -d /proc/self/task ] || { echo "skipped: no /proc/self/task here"; exit 77; }
# Threads without a nice of their own keep the one the test runs at (ctest under `nice` passes it on).
base=$(cut -d' ' -f19 /proc/$$/stat)
if [ "$(id -u)" != 0 ] && [ "$base" -gt 3 ]; then
  echo "skipped: running at nice $base, which an unprivileged process cannot lower to the configured 3"; exit 77
fi
rm -rf "$work" && mkdir -p "$work"
cat > "$work/config.yaml" <<'YAML'
fingerprint:
  workers: 3
pipeline:
  threads:
    fingerprint:
      nice: 3
    lcm_receiver:
      name: tsl-rx-custom
    recorder:
      name: tsl-rec-custom
      nice: 5
YAML
"$toposlamd" --config "$work/config.yaml" --source "images:$samples?rate=5" --lcm-url memq:// --map "" \
  --record "$work/rec" > "$work/daemon.log" 2>&1 &
pid=$!
found=""
for _ in 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20; do
  sleep 0.25
  found=$(for t in /proc/$pid/task/*; do echo "$(cat "$t/comm" 2>/dev/null) $(cut -d' ' -f19 "$t/stat" 2>/dev/null)"; done | sort)
  # The I/O threads start before the pipeline's: wait for both (a loaded machine starts them apart).
  case "$found" in *tsl-fingerprint*tsl-rec-custom*) break ;; esac
done
kill -TERM $pid 2>/dev/null || true
wait $pid || true
echo "$found"
echo "$found" | grep -qx "tsl-rx-custom $base" || { echo "no thread tsl-rx-custom (nice $base)"; cat "$work/daemon.log"; exit 1; }
echo "$found" | grep -qx "tsl-rec-custom 5" || { echo "no thread tsl-rec-custom (nice 5)"; cat "$work/daemon.log"; exit 1; }
echo "$found" | grep -qx "tsl-fingerprint 3" || { echo "no thread tsl-fingerprint (nice 3)"; exit 1; }
echo "$found" | grep -qx "tsl-vpack-1 3" || { echo "no pool thread tsl-vpack-1 (nice 3)"; exit 1; }
echo "$found" | grep -qx "tsl-vpack-2 3" || { echo "no pool thread tsl-vpack-2 (nice 3)"; exit 1; }
if echo "$found" | grep -q "tsl-lcm-rx\|tsl-record"; then echo "a default I/O thread name is still used"; exit 1; fi
echo "io threads as configured"
