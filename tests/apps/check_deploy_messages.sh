#!/bin/sh
# docs/deploy.md quotes the failures a deployment meets with their exact messages: they must stay what the
# programs print. Runs each failure and looks for its first error line, verbatim, in the page.
set -u
toposlam="$1" toposlamd="$2" doc="$3" samples="$4" dir="$5"
rm -rf "$dir" && mkdir -p "$dir"
fail() { echo "FAIL: $*"; exit 1; }
quoted() { grep -qF -- "$1" "$doc" || fail "docs/deploy.md does not quote: $1"; }

# 1. No multicast route (a network namespace with no route at all).
line="$(unshare -rn "$toposlamd" --source "images:$samples" --map '' 2>&1 | grep 'error:')"
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
