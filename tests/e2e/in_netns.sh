#!/bin/sh
# Runs a command in a fresh network namespace (unshare -rn: an unprivileged user namespace) with multicast
# routed on loopback, so the test's LCM traffic stays inside it and parallel tests cannot hear each other.
# Where namespaces are unavailable, falls back to the host loopback (the tests use ttl=0, so nothing leaves
# the host) and says so.
if [ -z "${TOPOSLAM_IN_NETNS:-}" ] && unshare -rn true 2>/dev/null; then
  exec unshare -rn env TOPOSLAM_IN_NETNS=1 sh -c \
    'ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo && exec "$@"' sh "$@"
fi
echo "e2e: network namespaces unavailable here; using the host loopback with ttl=0" >&2
exec "$@"
