#!/bin/sh
# toposlamd's frame recording (record.dir, issue 16): the daemon on the simulator records the frames it
# processes into a new subfolder, in `toposlam capture --record`'s format; `toposlam map` re-processes the
# recording into as many places as the daemon found (PNG: lossless); the recording replays at the recorded
# pace. The size bound stops recording with a clear line and the daemon goes on; a folder that cannot be
# made, and a write that fails mid-run (a file size limit stands in for a full disk: EFBIG), are errors the
# daemon survives: every frame is still published, exit 0.
# Usage: check_daemon_record.sh TOPOSLAM TOPOSLAMD DIR
set -u
toposlam="$1" toposlamd="$2" dir="$3"
rm -rf "$dir" && mkdir -p "$dir"
fail() { echo "FAIL: $*"; exit 1; }
# A notify socket for systemd's STATUS= lines: every datagram one line of FILE (python3, in the background).
notify_socket() {  # SOCKET FILE
  /usr/bin/python3 -c '
import socket, sys
s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
s.bind(sys.argv[1])
with open(sys.argv[2], "a") as out:
    while True:
        out.write(s.recv(4096).decode().replace("\n", " ") + "\n")
        out.flush()
' "$1" "$2" &
  i=0
  while [ ! -S "$1" ] && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
}
source="sim:office?route=loop&fps=3&size=160x120"  # 481 frames
daemon() { "$toposlamd" --source "$source" --lcm-url memq:// --map "" --overflow block "$@" 2>&1; }

# 1. Lossless and without drops (the writer's queue holds every frame): the recording is the daemon's input.
printf 'record:\n  dir: %s/rec\n  format: png\n  queue_frames: 1024\n' "$dir" >"$dir/png.yaml"
out="$(daemon -c "$dir/png.yaml")" || fail "toposlamd with recording exited $?: $out"
rec="$(ls -d "$dir"/rec/*Z)" || fail "no recording folder under $dir/rec: $out"
echo "$out" | grep -q "recorded 481 frames ([0-9.]* MB, 0 dropped) into $rec (481 frames offered); replay: images:$rec?rate=recorded" \
  || fail "the summary line: $out"
places="$(echo "$out" | sed -n 's/.*toposlamd: 481 frames published, 0 dropped, \([0-9]*\) places.*/\1/p')"
[ -n "$places" ] && [ "$places" -ge 5 ] || fail "the daemon's places: $out"
[ "$(ls "$rec" | grep -c '\.png$')" = 481 ] || fail "not 481 frames in $rec"
[ "$(sed -n 3p "$rec/timestamps.csv")" = "000001.png,0.333333" ] || fail "timestamps.csv: $(head -3 "$rec/timestamps.csv")"
mapped="$("$toposlam" map "images:$rec" --out "$dir/map" 2>/dev/null | tail -1)"
echo "$mapped" | grep -q "^481 frames -> $places places mapped" || fail "map of the recording: '$mapped', the daemon found $places places"
echo "daemon: 481 frames, $places places; map of its recording: $mapped"
out="$("$toposlam" capture "images:$rec?rate=recorded" --count 7 -q 2>&1)" || fail "replay: $out"
echo "$out" | grep -q "fps=3.00" || fail "replay: $out"
seconds="$(echo "$out" | sed -n 's/.* seconds=\([0-9.]*\) .*/\1/p')"
awk -v s="$seconds" 'BEGIN { exit !(s >= 1.9) }' || fail "7 frames recorded over 2 s replayed in $seconds s"

# 2. The size bound: recording stops, the daemon goes on; systemd's STATUS= shows the recording (paced at 160
#    frames/s, so the daemon runs 3 s and sends a few status lines).
printf 'record:\n  dir: %s/small\n  max_mb: 1\n  queue_frames: 1024\n' "$dir" >"$dir/small.yaml"  # JPEG: ~4 kB a frame
notify_socket "$dir/notify.sock" "$dir/notify.log"
receiver=$!
out="$(NOTIFY_SOCKET="$dir/notify.sock" "$toposlamd" --source "$source&rate=160" --lcm-url memq:// --map "" --overflow block \
  -c "$dir/small.yaml" 2>&1)" || fail "size bound: exit $?: $out"
kill "$receiver"
grep -q "^STATUS=running: .*; recording [0-9]* frames ([0-9.]* MB, 0 dropped)" "$dir/notify.log" \
  || fail "no recording in STATUS=: $(cat "$dir/notify.log")"
# (Whether STATUS= also shows the stop depends on how fast the writer, at nice 10, keeps up on a loaded
# machine: the end line below says it in any case.)
n="$(ls "$dir"/small/*Z | grep -c '\.jpg$')"
[ "$n" -ge 10 ] && [ "$n" -lt 481 ] || fail "size bound: $n frames"
echo "$out" | grep -q "recording stopped: the size bound (record.max_mb) was reached after $n frames" || fail "size bound: $out"
echo "$out" | grep -q "481 frames published" || fail "size bound: not every frame published: $out"
# Earlier recordings count: a folder already at the bound records nothing.
head -c 1100000 /dev/zero >"$dir/small/old.bin"
out="$(daemon -c "$dir/small.yaml")" || fail "bound reached before start: exit $?: $out"
echo "$out" | grep -q "not recording: $dir/small already holds [0-9.]* MB of recordings, record.max_mb is 1 MB" || fail "bound reached: $out"
echo "size bound: $n frames within 1 MB, then nothing"

# 3. A folder that cannot be made: an error, and the daemon maps on.
touch "$dir/a-file"
out="$(daemon --record "$dir/a-file/rec")" || fail "unwritable record.dir: exit $?: $out"
echo "$out" | grep -q "\[error\] toposlamd: not recording: record: cannot create the folder $dir/a-file/rec/[0-9T]*Z: Not a directory (record.dir $dir/a-file/rec); running without recording" \
  || fail "unwritable record.dir: $out"
echo "$out" | grep -q "481 frames published" || fail "unwritable record.dir: $out"

# 4. A write fails mid-run (files limited to 4 KiB, SIGXFSZ ignored: write() fails with EFBIG, as on a full disk).
out="$(sh -c "trap '' XFSZ; ulimit -f 8; exec \"$toposlamd\" --source '$source' --lcm-url memq:// --map '' --overflow block --record '$dir/full'" 2>&1)" \
  || fail "failing writes: exit $?: $out"
echo "$out" | grep -q "\[error\] recording stopped: record: write failed: $dir/full/[0-9T]*Z/[0-9]*.jpg: File too large; [0-9]* frames kept in" \
  || fail "failing writes: $out"
echo "$out" | grep -q "recording failed (record: write failed: .*File too large)" || fail "failing writes, summary: $out"
echo "$out" | grep -q "481 frames published" || fail "failing writes: $out"
full="$(ls -d "$dir"/full/*Z)"
kept="$(ls "$full" | grep -c '\.jpg$')"
[ "$(($(wc -l <"$full/timestamps.csv") - 1))" = "$kept" ] || fail "failing writes: timestamps.csv does not list the $kept frames"
echo "failing writes: the daemon went on, $kept frames kept"
echo "daemon record OK"
