#!/bin/sh
# docs/deploy.md quotes the failures a deployment meets with their exact messages: they must stay what the
# programs print. Runs each failure and looks for its first error line, verbatim, in the page.
set -u
toposlam="$1" toposlamd="$2" doc="$3" samples="$4" dir="$5"
rm -rf "$dir" && mkdir -p "$dir"
fail() { echo "FAIL: $*"; exit 1; }
quoted() { grep -qF -- "$1" "$doc" || fail "docs/deploy.md does not quote: $1"; }

# 1. No multicast route (a network namespace with no route at all): toposlamd waits and says so (the log
#    line without spdlog's time and level), or with lcm.open_retry_s: 0 exits 1 with the error.
unshare -rn sh -c '"$1" --source "images:$2" --map "" >"$3" 2>&1 & sleep 1; kill -TERM $!; wait' sh "$toposlamd" "$samples" "$dir/wait.log"
line="$(grep 'waiting for the network' "$dir/wait.log" | sed 's/^\[[^]]*\] \[[a-z]*\] //')"
[ -n "$line" ] || fail "no 'waiting for the network' line: $(cat "$dir/wait.log")"
quoted "$line"
printf 'lcm:\n  open_retry_s: 0\n' >"$dir/no-retry.yaml"
line="$(unshare -rn "$toposlamd" -c "$dir/no-retry.yaml" --source "images:$samples" --map '' 2>&1 | grep 'error:')"
[ -n "$line" ] || fail "no LCM error printed"
quoted "$line"
# 2. A config error, as the installed file would report it.
printf 'pipeline:\n  queues:\n    frames: 0\n' >"$dir/toposlam.yaml"
line="$("$toposlamd" --check-config -c "$dir/toposlam.yaml" 2>&1 | sed "s|$dir/toposlam.yaml|/etc/toposlam/toposlam.yaml|")"
quoted "$line"
# 5. toposlam listen hears nothing (multicast routed on loopback in a namespace, no daemon).
printf 'pipeline:\n  queues:\n    frames: 2\n' >"$dir/ok.yaml"
line="$(unshare -rn sh -c 'ip link set lo up && ip link set lo multicast on && ip route add 239.255.76.67/32 dev lo &&
        "$1" listen -c "$2" --timeout 5 2>&1' sh "$toposlam" "$dir/ok.yaml")"
quoted "$line"
echo "deploy messages OK"
