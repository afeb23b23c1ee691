#!/bin/sh
# The unit's restart policy and the shipped multicast route (issue 16):
#  - Restart=on-failure with RestartPreventExitStatus=2: a config error (exit 2) is not restarted in a loop;
#  - config/50-toposlam-multicast.network routes exactly the group of the default lcm.url on loopback.
set -u
root="$1" unit="$2"
fail() { echo "FAIL: $*"; exit 1; }
grep -qx "Restart=on-failure" "$unit" || fail "no Restart=on-failure in $unit"
grep -qx "RestartPreventExitStatus=2" "$unit" || fail "no RestartPreventExitStatus=2 in $unit"
group="$(sed -n 's|^  url: "udpm://\([0-9.]*\):.*|\1|p' "$root/config/toposlam.yaml")"
[ -n "$group" ] || fail "no udpm group in config/toposlam.yaml"
network="$root/config/50-toposlam-multicast.network"
[ -f "$network" ] || fail "no $network"
grep -qx "Name=lo" "$network" || fail "the .network does not match lo"
grep -qx "Multicast=yes" "$network" || fail "the .network does not turn multicast on"
grep -qx "Destination=$group/32" "$network" || fail "the .network does not route $group (lcm.url's group)"
grep -q "ip route add $group/32 dev lo" "$network" || fail "the by-hand command is not given for $group"
echo "unit policy OK (group $group)"
