#!/bin/sh
# Runs INSIDE the VM (chroot into the host's root, shared read-only over 9p; /tmp is a tmpfs) and
# exercises the real, dynamically linked toposlam binaries against real V4L2 drivers:
#   1. vivid (the kernel's test driver), BGR24: frames are handed out zero-copy (the lease re-queues
#      the buffer); its "disconnect" control unplugs the camera mid-stream and the capture reconnects
#      and carries on;
#   2. v4l2loopback fed the bundled frames as YUYV by ffmpeg: `toposlam capture` receives frames with
#      increasing sequence numbers and monotonic timestamps;
#   3. libcamera (tests/vm/guest-libcamera.sh, beside 2.): `toposlam capture libcamera:ID` on the kernel's
#      vimc camera through libcamera's vimc pipeline handler: 30 frames of the size asked for;
#   4. toposlamd on the loopback device, publishing over LCM on lo, checked by a subscriber (a missing
#      toposlamd binary is a failure, not a skip);
#   5. toposlamd on vivid while the camera is unplugged and plugged back (tests/vm/guest-unplug.sh).
# Time: every step declares its limit for an idle machine (step LIMIT what); the host's watcher allows it
# LIMIT x the slowness measured by the boot, and the timeouts here stretch by the same factor (s N).
# Prints "VMTEST PASS|FAIL <what>" lines for tests/vm/run-vm-test.sh, then "VMTEST DONE failures=N".
# Usage (from the initramfs init): guest.sh BUILD_DIR
build=${1:?usage: guest.sh BUILD_DIR}
toposlam=$build/src/apps/toposlam/toposlam
toposlamd=${tsdaemon:-$build/src/apps/toposlamd/toposlamd}  # tsdaemon= on the kernel command line overrides
export HOME=/tmp PATH=/usr/local/bin:/usr/bin:/bin:/usr/sbin:/sbin
cd /tmp || exit 1
failures=0
uptime() { cut -d' ' -f1 /proc/uptime; }
pass() { echo "VMTEST PASS [$(uptime) s] $*"; }
fail() { echo "VMTEST FAIL [$(uptime) s] $*"; failures=$((failures + 1)); }
step() { limit=$1; shift; echo "VMTEST STEP [$(uptime) s] limit=$limit $*"; }  # step LIMIT_S what
. "$(dirname "$0")/budget.sh"
slowness=$(vm_slowness "${tsboot:-$VM_REFERENCE_BOOT_S}")
s() { vm_scaled "$1" "$slowness"; }  # s SECONDS: a timeout for an idle machine, stretched by the slowness
show() { sed "s/^/  $1| /" "$2" | head -n "${3:-400}"; }

# Waits until the loopback device has a writer with the given pixel format (fourcc), up to ~15 s (scaled).
wait_for_writer() {
  i=0
  while [ $i -lt "$(s 60)" ]; do
    v4l2-ctl -d /dev/video0 --get-fmt-video 2>/dev/null | grep -q "'$1'" && return 0
    sleep 0.25
    i=$((i + 1))
  done
  return 1
}

# Checks a capture log: N frames, strictly increasing sequence and timestamps.
check_capture_log() {  # log expected_frames what
  if ! grep -q "^summary frames=$2 " "$1"; then fail "$3: expected $2 frames"; return 1; fi
  if ! awk '/^frame /{ split($2,s,"="); split($3,t,"=");
              if (n++ && (s[2]+0 <= seq || t[2]+0 <= ts)) bad++; seq=s[2]+0; ts=t[2]+0 }
            END { exit bad ? 1 : 0 }' "$1"; then
    fail "$3: sequence numbers or timestamps do not increase"; return 1
  fi
  pass "$3: $(grep '^summary' "$1")"
}

echo "VMTEST kernel $(uname -r), $(ls /dev/video* | tr '\n' ' '); slowness $slowness (boot ${tsboot:-?} s)"
[ -x "$toposlam" ] || { fail "no toposlam binary at $toposlam (build it first)"; echo "VMTEST DONE failures=$failures"; exit 1; }
[ -x "$toposlamd" ] || fail "no toposlamd binary at $toposlamd (build it first)"
samples=$(cd "$(dirname "$0")/../data/rtabmap-samples/samples" && pwd)

# Under TCG, starting a big dynamically linked program takes 10-20 s (toposlam maps ~250 libraries), so
# the slow starts run side by side: the loopback writer, the vivid capture and the LCM listener.
step 45 "start: ffmpeg writer (bundled frames, 10 fps, YUYV 320x240), vivid capture, LCM listeners"
ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo || fail "cannot set up multicast on lo"
ffmpeg -nostdin -loglevel error -re -stream_loop 20 -framerate 10 -start_number 1 -i "$samples/%d.jpg" \
  -vf scale=320:240 -pix_fmt yuyv422 -f v4l2 /dev/video0 &
writer=$!
"$toposlam" listen --channels TOPOSLAM_PLACE,TOPOSLAM_PLACE_EVENT,TOPOSLAM_STATUS --timeout "$(s 300)" >listen.txt 2>&1 &
listener=$!
# The unplug test's daemon publishes on a port of its own (tests/vm/guest-unplug.sh).
unplug_url="udpm://239.255.76.67:7668?ttl=0"
"$toposlam" listen --url "$unplug_url" --channels TOPOSLAM_PLACE,TOPOSLAM_STATUS --timeout "$(s 300)" \
  >unplug-listen.txt 2>&1 &
unplug_listener=$!

# --- vivid (the kernel's test driver), BGR24 zero copy, with an unplug in the middle -----------------
vivid=""
for d in /sys/class/video4linux/video*; do
  case "$(cat "$d/name")" in vivid*vid-cap*) vivid=/dev/$(basename "$d") ;; esac
done
if [ -z "$vivid" ]; then
  fail "vivid: no vivid capture node"
else
  # The log exists before the capture starts: the wait below counts its frames, and a missing file would
  # end the wait at once (grep -c prints nothing), disconnecting the camera after 0 frames.
  : >vivid.txt
  timeout "$(s 100)" "$toposlam" capture "v4l2:$vivid?size=320x240&format=bgr24" -n 120 --timeout "$(s 90)" \
    >>vivid.txt 2>&1 &
  capture=$!
  i=0
  while [ $i -lt "$(s 600)" ] && [ "$(grep -c '^frame ' vivid.txt 2>/dev/null || true)" -lt 10 ]; do sleep 0.1; i=$((i + 1)); done
  v4l2-ctl -d "$vivid" -c disconnect=1 >/dev/null 2>&1 || echo "  (v4l2-ctl disconnect returned $?)"
  echo "VMTEST vivid disconnected after $(grep -c '^frame ' vivid.txt) frames"
  wait $capture
  show vivid vivid.txt 400 | grep -v "| frame " | head -20
  if check_capture_log vivid.txt 120 "vivid bgr24 capture across an unplug" &&
     ! grep -q "zero_copy=1" vivid.txt; then
    fail "vivid bgr24: frames were not zero-copy"
  fi
  if grep -q "camera lost" vivid.txt && grep -Eq "^summary .*reconnects=[1-9]" vivid.txt; then
    pass "vivid reconnect: $(grep -m1 'camera lost' vivid.txt | sed 's/.*camera lost/camera lost/')"
  else
    fail "vivid reconnect: no reconnect seen after the disconnect control"
  fi
fi

# --- libcamera on vimc (in the background) and v4l2loopback, YUYV from ffmpeg ---------------------------
step 45 "libcamera on vimc (background), loopback yuyv"
. "$(dirname "$0")/guest-libcamera.sh"
libcamera_start
if wait_for_writer YUYV; then
  timeout "$(s 60)" "$toposlam" capture "v4l2:/dev/video0?size=320x240&fps=10&format=yuyv" -n 30 --timeout "$(s 45)" \
    >loop-yuyv.txt 2>&1
  show yuyv loop-yuyv.txt 6
  check_capture_log loop-yuyv.txt 30 "v4l2loopback yuyv capture"
else
  fail "v4l2loopback yuyv: the ffmpeg writer never set a format"
fi
libcamera_check

# --- toposlamd over LCM, on the same loopback camera ----------------------------------------------------
if [ -x "$toposlamd" ]; then
  . "$(dirname "$0")/guest-daemon.sh"
fi
kill $writer 2>/dev/null; wait $writer 2>/dev/null

# --- toposlamd on vivid: the camera unplugged and plugged back ------------------------------------------
if [ -x "$toposlamd" ] && [ -n "$vivid" ]; then
  . "$(dirname "$0")/guest-unplug.sh"
fi
kill $unplug_listener 2>/dev/null; wait $unplug_listener 2>/dev/null

echo "VMTEST DONE failures=$failures"
