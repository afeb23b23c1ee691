#!/usr/bin/env bash
# Bench-tests the camera path on a real Linux machine with a virtual V4L2 camera: loads v4l2loopback,
# streams a frame sequence into it with ffmpeg at a chosen rate, then
#   1. `toposlam capture` alone: delivered fps, drops, and frame age (driver timestamp -> application);
#   2. `toposlamd` on the same camera for a while, read over LCM with `toposlam listen`: pipeline fps,
#      capture-to-publish latency (median / p99) and drops from its TOPOSLAM_STATUS messages.
# Needs (Debian/Ubuntu): v4l2loopback-dkms (plus linux-headers for your kernel), ffmpeg, v4l-utils,
# iproute2, and root for modprobe (sudo is used if needed). See docs/cameras.md.
#
# Usage: scripts/bench-v4l2loopback.sh [--build DIR] [--fps 30] [--size 640x480] [--seconds 30]
#                                      [--device /dev/video42] [--frames DIR_WITH_1.jpg..N.jpg]
set -euo pipefail

here=$(cd "$(dirname "$0")/.." && pwd)
build="$here/build"
fps=30
size=640x480
seconds=30
device=/dev/video42
frames="$here/tests/data/rtabmap-samples/samples"
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --fps) fps=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --seconds) seconds=$2; shift 2 ;;
    --device) device=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    -h|--help) sed -n 2,13p "$0"; exit 0 ;;
    *) echo "bench-v4l2loopback: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
toposlam="$build/src/apps/toposlam/toposlam"
toposlamd="$build/src/apps/toposlamd/toposlamd"
for b in "$toposlam" "$toposlamd"; do
  [ -x "$b" ] || { echo "bench-v4l2loopback: $b not built (cmake --build $build)" >&2; exit 1; }
done
for tool in ffmpeg v4l2-ctl modprobe; do
  command -v "$tool" >/dev/null || { echo "bench-v4l2loopback: $tool missing: sudo apt-get install ffmpeg v4l-utils kmod v4l2loopback-dkms" >&2; exit 1; }
done
[ -f "$frames/1.jpg" ] || { echo "bench-v4l2loopback: $frames has no 1.jpg..N.jpg sequence" >&2; exit 1; }
SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO=sudo
width=${size%x*}; height=${size#*x}

if [ ! -e "$device" ]; then
  nr=${device#/dev/video}
  echo "bench: loading v4l2loopback as $device"
  $SUDO modprobe v4l2loopback devices=1 video_nr="$nr" exclusive_caps=0 card_label=toposlam-bench max_buffers=4 ||
    { echo "bench-v4l2loopback: modprobe v4l2loopback failed (is v4l2loopback-dkms built for $(uname -r)?)" >&2; exit 1; }
  sleep 1
fi

pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; }
trap cleanup EXIT

ffmpeg -nostdin -loglevel error -re -stream_loop -1 -framerate "$fps" -start_number 1 -i "$frames/%d.jpg" \
  -vf "scale=$width:$height" -pix_fmt yuyv422 -f v4l2 "$device" &
pids+=($!)
for _ in $(seq 50); do
  v4l2-ctl -d "$device" --get-fmt-video 2>/dev/null | grep -q "'YUYV'" && break
  sleep 0.2
done
uri="v4l2:$device?size=$size&fps=$fps&format=yuyv"

echo "bench: 1/2 capture only, $uri, ffmpeg feeding $fps fps"
count=$((fps * 10))
"$toposlam" capture "$uri" --count "$count" --timeout $((20 + count / fps * 2)) --quiet | tee /tmp/toposlam-bench-capture.txt

echo "bench: 2/2 toposlamd for $seconds s (status over LCM)"
if ! ip route get 239.255.76.67 >/dev/null 2>&1; then
  echo "bench: no multicast route; for loopback-only LCM: sudo ip link set lo multicast on; sudo ip route add 224.0.0.0/4 dev lo" >&2
fi
"$toposlam" listen --channels TOPOSLAM_STATUS --timeout $((seconds + 10)) >/tmp/toposlam-bench-status.txt 2>&1 &
pids+=($!)
set +e
# --preserve-status: toposlamd's own exit code after the SIGTERM (0 = clean stop, map saved); -k: killed
# 20 s later if it does not stop (137).
timeout --preserve-status -k 20 -s TERM "$seconds" "$toposlamd" --source "$uri" --map /tmp/toposlam-bench-map.tsm \
  --no-map-load >/tmp/toposlam-bench-daemon.txt 2>&1
daemon_rc=$?
set -e
sleep 1
echo "bench: last daemon status (fps, capture-to-publish latency, drops):"
grep '^STATUS' /tmp/toposlam-bench-status.txt | tail -1 || echo "  (no TOPOSLAM_STATUS received; see /tmp/toposlam-bench-daemon.txt)"
echo "bench: capture summary: $(grep '^summary' /tmp/toposlam-bench-capture.txt)"
if [ "$daemon_rc" -ne 0 ]; then
  echo "bench-v4l2loopback: toposlamd exited with $daemon_rc after SIGTERM (expected 0); last lines of its log:" >&2
  tail -5 /tmp/toposlam-bench-daemon.txt >&2
  exit 1
fi
