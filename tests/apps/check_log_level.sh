#!/bin/sh
# --log-level and the journal's format (issue 16). JOURNAL_STREAM is set to the device:inode of the file
# toposlamd's stderr goes to, as systemd does for a service whose output is the journal: every line must
# then start with its sd-daemon priority ("<6>" info, "<4>" warning, "<3>" error) and carry no timestamp.
# Usage: check_log_level.sh TOPOSLAM TOPOSLAMD BRIDGE SAMPLES DIR
set -u
toposlam="$1" toposlamd="$2" bridge="$3" samples="$4" dir="$5"
rm -rf "$dir" && mkdir -p "$dir/frames"
fail() { echo "FAIL: $*"; exit 1; }
cp "$samples/1.jpg" "$samples/2.jpg" "$samples/3.jpg" "$dir/frames/"
echo "not a jpeg" >"$dir/frames/4.jpg"   # "images: skipping ...": a warning
log="$dir/journal.log"
: >"$log"
stream="$(stat -c '%d:%i' "$log")"
run() { JOURNAL_STREAM="$stream" "$toposlamd" --source "images:$dir/frames" --map '' --lcm-url memq:// "$@" 2>>"$log" >/dev/null; }

# 1. The journal's format: priorities, no timestamps; the warning is <4>.
run || fail "toposlamd exited $?"
lines="$(grep -c . "$log")"
[ "$lines" -ge 4 ] || fail "only $lines log lines"
grep -qv '^<[0-7]>' "$log" && fail "a line without a priority: $(grep -v '^<[0-7]>' "$log" | head -1)"
grep -q '\[20[0-9][0-9]-' "$log" && fail "a timestamp in the journal's format"
grep -q '^<6>toposlamd: running' "$log" || fail "no <6> info line"
grep -q '^<4>images: skipping .*4.jpg' "$log" || fail "the unreadable frame is not a <4> warning"
echo "journal: $lines lines, $(grep -c '^<6>' "$log") info, $(grep -c '^<4>' "$log") warning"

# 2. A start error is <3> and exit 2.
: >"$log"
JOURNAL_STREAM="$stream" "$toposlamd" --source "images:$dir/none" --map '' --lcm-url memq:// 2>>"$log"
rc=$?
[ "$rc" = 2 ] || fail "a missing source exited $rc, not 2"
grep -q "^<3>toposlamd: error: images: '$dir/none'" "$log" || fail "the start error is not <3>: $(cat "$log")"

# 3. --log-level warn keeps the warning and drops the info lines; so does the config's log_level.
: >"$log"
run --log-level warn || fail "toposlamd --log-level warn exited $?"
[ "$(grep -c '^<6>' "$log")" = 0 ] || fail "--log-level warn printed info lines"
[ "$(grep -c '^<4>' "$log")" = 1 ] || fail "--log-level warn lost the warning"
printf 'log_level: error\n' >"$dir/error.yaml"
: >"$log"
run -c "$dir/error.yaml" || fail "toposlamd with log_level: error exited $?"
[ "$(grep -c . "$log")" = 0 ] || fail "log_level: error printed: $(head -1 "$log")"

# 4. Not the journal (JOURNAL_STREAM names another file): timestamps, no priorities.
"$toposlamd" --source "images:$dir/frames" --map '' --lcm-url memq:// 2>"$dir/plain.log" >/dev/null
grep -q '^\[20[0-9-]* [0-9:.]*\] \[info\] toposlamd: running' "$dir/plain.log" || fail "plain format: $(head -1 "$dir/plain.log")"
JOURNAL_STREAM="$stream" "$toposlamd" --source "images:$dir/frames" --map '' --lcm-url memq:// 2>"$dir/other.log" >/dev/null
grep -q '^<' "$dir/other.log" && fail "priorities on a stderr that is not the journal's stream"

# 5. toposlam: --log-level before or after the command; toposlam-bridge takes it too.
"$toposlam" segment --log-level warn "images:$dir/frames" --out "$dir/seg" >/dev/null 2>"$dir/seg.log" || fail "segment exited $?"
grep -q 'images: skipping' "$dir/seg.log" || fail "segment --log-level warn lost the warning"
"$toposlam" --log-level error segment "images:$dir/frames" --out "$dir/seg2" >/dev/null 2>"$dir/seg2.log" || fail "segment exited $?"
grep -q 'images: skipping' "$dir/seg2.log" && fail "toposlam --log-level error printed a warning"
for exe in "$toposlam segment" "$toposlamd" "$bridge"; do
  $exe --log-level loud >/dev/null 2>&1
  rc=$?
  [ "$rc" = 2 ] || fail "$exe --log-level loud exited $rc, not 2"
done
echo "log level OK"
