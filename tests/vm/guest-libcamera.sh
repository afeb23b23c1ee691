# Sourced by tests/vm/guest.sh inside the VM (uses its pass/fail/show/check_capture_log helpers and
# $toposlam): libcamera (Debian's 0.0.3, its vimc pipeline handler and IPA module from libcamera-ipa) on
# the kernel's virtual media-controller camera vimc (built by scripts/vm/prepare.sh, loaded by the init):
#   - `cam --list` (libcamera-tools) must list the vimc sensor; its ID is what the capture opens;
#   - `toposlam capture libcamera:ID?size=240x180` must deliver 30 frames of exactly 240x180, zero-copy
#     (RGB888 = OpenCV's BGR, viewed in the mapped buffer), sequence numbers and timestamps increasing.
# libcamera_start runs both in the background (program starts are slow under TCG: it overlaps the
# loopback capture); libcamera_check waits for it and checks.
# The guest has no udevd, and libcamera's udev enumerator only takes devices udev has initialised: an
# "I:" (initialised-at) record per media and video4linux device in /run/udev/data stands in for that.
libcamera_start() {
  mkdir -p /run/udev/data
  for dev in /sys/bus/media/devices/* /sys/class/video4linux/*; do
    [ -r "$dev/dev" ] && echo "I:1" >"/run/udev/data/c$(cat "$dev/dev")"
  done
  (
    export LIBCAMERA_LOG_LEVELS='*:ERROR'  # not its warnings about vimc's sensor having no properties
    timeout "$(s 60)" cam --list >cam-list.txt 2>&1
    camera_id=$(sed -n "s/^[0-9]*: '.*' (\(.*\))$/\1/p" cam-list.txt | grep vimc | head -n 1)
    echo "$camera_id" >camera-id.txt
    [ -n "$camera_id" ] &&
      timeout "$(s 90)" "$toposlam" capture "libcamera:$camera_id?size=240x180" -n 30 --timeout "$(s 75)" >libcamera.txt 2>&1
  ) &
  libcamera_job=$!
}

libcamera_check() {
  wait $libcamera_job
  show cam cam-list.txt 10
  camera_id=$(cat camera-id.txt)
  if [ -z "$camera_id" ]; then
    fail "libcamera: cam --list (libcamera-tools) shows no vimc camera (libcamera-ipa installed?)"
    return
  fi
  show libcam libcamera.txt 400 | grep -v "| frame " | head -8
  frame_lines=$(grep -c '^frame ' libcamera.txt)
  if ! grep -q "^source libcamera:$camera_id (240x180 RGB888, libcamera " libcamera.txt; then
    fail "libcamera vimc: the source did not open as 240x180 RGB888"
  elif [ "$(grep -c '^frame .* size=240x180 zero_copy=1 ' libcamera.txt)" -ne "$frame_lines" ]; then
    odd=$(grep '^frame ' libcamera.txt | grep -v 'size=240x180 zero_copy=1 ' | head -n 1)
    fail "libcamera vimc: not every frame is 240x180 zero-copy: $odd"
  else
    check_capture_log libcamera.txt 30 "libcamera vimc capture ($camera_id, 240x180 RGB888 zero-copy)"
  fi
}
