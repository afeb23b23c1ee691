#!/bin/sh
# A recording whose clock stepped back (issue 19, docs/reliability.md "Clock jumps"): the 84 sample frames
# stamped 1 s apart, once honestly and once with the clock stepped back 30 s at frame 40 (an NTP step on a
# robot without RTC). `segment` and `map` must find the same places in both (a step back used to keep
# every frame after it in the window until the recording caught up with its own clock: 30 frames), say
# that the clock went back, and write the carried-on times into frames.csv.
# Usage: check_clock_step.sh TOPOSLAM SAMPLES_DIR WORK_DIR
set -u
toposlam="$1" samples="$2" dir="$3"
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$dir" && mkdir -p "$dir/honest" "$dir/stepped"
cp "$samples"/*.jpg "$dir/honest/" && cp "$samples"/*.jpg "$dir/stepped/" || fail "cannot copy the samples"
echo "name,time_s" >"$dir/honest/timestamps.csv"
echo "name,time_s" >"$dir/stepped/timestamps.csv"
i=1
while [ $i -le 84 ]; do
  echo "$i.jpg,$((1000 + i)).000000" >>"$dir/honest/timestamps.csv"
  if [ $i -lt 40 ]; then t=$((1000 + i)); else t=$((970 + i)); fi
  echo "$i.jpg,$t.000000" >>"$dir/stepped/timestamps.csv"
  i=$((i + 1))
done

for command in segment map; do
  "$toposlam" $command "images:$dir/honest" --out "$dir/$command-honest" >/dev/null 2>"$dir/$command-honest.err" ||
    fail "$command honest: $(cat "$dir/$command-honest.err")"
  "$toposlam" $command "images:$dir/stepped" --out "$dir/$command-stepped" >/dev/null 2>"$dir/$command-stepped.err" ||
    fail "$command stepped: $(cat "$dir/$command-stepped.err")"
  grep -q "^$command: the source's clock went back 1 time(s) (the last by 29.000 s)" "$dir/$command-stepped.err" ||
    fail "$command: no word of the clock going back: $(tail -3 "$dir/$command-stepped.err")"
  ! grep -q "clock went back" "$dir/$command-honest.err" || fail "$command: an honest clock reported as going back"
  # frame,time,name,lambda2,place,node: the same places, and frame 39 (40.jpg) one second after frame 38.
  honest_places="$(cut -d, -f1,5 "$dir/$command-honest/frames.csv")"
  stepped_places="$(cut -d, -f1,5 "$dir/$command-stepped/frames.csv")"
  [ "$honest_places" = "$stepped_places" ] ||
    fail "$command: the places differ after the step back: $(diff "$dir/$command-honest/frames.csv" "$dir/$command-stepped/frames.csv" | head -6)"
  [ "$(sed -n 41p "$dir/$command-stepped/frames.csv" | cut -d, -f2)" = "1040.000000" ] ||
    fail "$command: frames.csv time of frame 39: $(sed -n 41p "$dir/$command-stepped/frames.csv")"
  echo "$command: $(tail -n +2 "$dir/$command-honest/places.csv" | wc -l) places with either clock"
done
echo "PASS"
