#!/bin/sh
# The Debian package installed with dpkg and its service started by systemd, in a container that boots
# systemd (systemd-nspawn -b): this machine and CI run no systemd as PID 1, so the container is where a unit
# can start. The container sees the host's /usr, /etc and /var through overlays (writes go to a temporary
# upper layer; the host is not changed) and has its own network with only loopback, given the multicast
# route. In it: `dpkg -i` (the conffile /etc/toposlam/toposlam.yaml in place), the config pointed at a folder
# of images (no camera), `systemctl start toposlamd` (Type=notify: returns once READY=1), its status, place
# messages read with `toposlam listen`, `systemctl stop` (the final map saved, exit 0); then the bridge's
# unit, given a UDP link, started and stopped.
# Usage: check_deb_service.sh CPACK BUILD_DIR VERSION FRAMES_DIR   (TOPOSLAM_DEB=FILE: that package instead)
# Exit 77 (skipped) without root, systemd-nspawn, systemd, overlayfs or dpkg-deb, or when the container does
# not boot (an environment that cannot run one: the boot log is printed).
set -eu
cpack="$1" build="$2" version="$3" frames="$4"
skip() { echo "SKIP: $*"; exit 77; }
[ "$(id -u)" = 0 ] || skip "needs root (systemd-nspawn boots a container)"
command -v systemd-nspawn >/dev/null || skip "systemd-nspawn is not installed (apt-get install systemd-container; scripts/setup.sh --test)"
[ -x /usr/lib/systemd/systemd ] || skip "no /usr/lib/systemd/systemd to boot in the container (apt-get install systemd)"
grep -qw overlay /proc/filesystems || skip "the kernel has no overlayfs (the container's writable /usr, /etc, /var)"
command -v dpkg-deb >/dev/null || skip "dpkg-deb is not installed"
command -v nsenter >/dev/null || skip "nsenter (util-linux) is not installed"

tmp="$(mktemp -d /tmp/toposlam-deb-service.XXXXXX)"
nspawn_pid=""
cleanup() {
  if [ -n "$nspawn_pid" ] && kill -0 "$nspawn_pid" 2>/dev/null; then
    kill -TERM "$nspawn_pid" 2>/dev/null || true  # asks the container to halt
    i=0
    while kill -0 "$nspawn_pid" 2>/dev/null && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
    kill -TERM "$nspawn_pid" 2>/dev/null || true  # a second SIGTERM ends it at once
    wait "$nspawn_pid" 2>/dev/null || true
  fi
  rm -rf "$tmp"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  [ -z "$leader" ] || in_container journalctl --no-pager -u toposlamd.service -u toposlam-bridge.service 2>/dev/null \
    | tail -40 || true
  exit 1
}
leader=""
in_container() { nsenter -t "$leader" -a env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 "$@"; }
seconds() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(seconds)" 'BEGIN { printf "%.1f", b - a }'; }
t0="$(seconds)"

# 1. The package, from the build tree (as check_deb.sh), or the one TOPOSLAM_DEB names (scripts/package.sh's).
deb="toposlam_${version}_$(dpkg --print-architecture).deb"
if [ -n "${TOPOSLAM_DEB:-}" ]; then
  mkdir -p "$tmp/out" && cp "$TOPOSLAM_DEB" "$tmp/out/$deb"
else
  "$cpack" -G DEB --config "$build/CPackConfig.cmake" -B "$tmp/out" >"$tmp/cpack.log" 2>&1 \
    || { cat "$tmp/cpack.log"; fail "cpack -G DEB failed"; }
fi
[ -f "$tmp/out/$deb" ] || { cat "$tmp/cpack.log"; fail "no $deb in $(ls "$tmp/out")"; }
echo "package: $deb ($(elapsed "$t0") s)"

# 2. The container: a skeleton root (nspawn wants an os-release before it mounts anything) whose /usr, /etc
#    and /var are the host's under a writable overlay; the package and the frames bound read-only.
root="$tmp/root"
mkdir -p "$root/usr" "$root/etc" "$root/var" "$root/tmp" "$root/root" "$root/mnt/deb" "$root/srv/frames" \
         "$tmp/upper/usr" "$tmp/upper/etc" "$tmp/upper/var"
for d in bin sbin lib lib64; do [ -L "/$d" ] && ln -s "usr/$d" "$root/$d"; done
cp /usr/lib/os-release "$root/etc/os-release"
# Boot to basic.target: the host's enabled services (a database, ...) are not toposlam's business.
systemd-nspawn --quiet --register=no --keep-unit --private-network --console=pipe -D "$root" \
    --overlay="/usr:$tmp/upper/usr:/usr" --overlay="/etc:$tmp/upper/etc:/etc" --overlay="/var:$tmp/upper/var:/var" \
    --bind-ro="$tmp/out:/mnt/deb" --bind-ro="$frames:/srv/frames" \
    -b systemd.unit=basic.target </dev/null >"$tmp/boot.log" 2>&1 &
nspawn_pid=$!
i=0
while [ -z "$leader" ] && [ $i -lt 100 ]; do
  kill -0 "$nspawn_pid" 2>/dev/null || break
  leader="$(pgrep -P "$nspawn_pid" -x systemd | head -n 1 || true)"
  [ -n "$leader" ] || { sleep 0.1; i=$((i + 1)); }
done
if [ -z "$leader" ]; then
  cat "$tmp/boot.log"
  skip "systemd-nspawn did not boot a container here (log above)"
fi
# systemctl answers once the container's systemd has its socket; then it waits for the boot to finish.
i=0
state=""
while [ $i -lt 300 ]; do
  state="$(timeout 90 nsenter -t "$leader" -a systemctl is-system-running --wait 2>&1 || true)"
  case "$state" in *"connect to bus"*) sleep 0.1; i=$((i + 1)) ;; *) break ;; esac
done
case "$state" in
  running|degraded) ;;
  *) cat "$tmp/boot.log"; skip "the container's systemd did not finish booting ('$state'; log above)" ;;
esac
echo "container booted: systemd $(in_container systemctl --version | awk 'NR == 1 { print $2 }'), $state ($(elapsed "$t0") s)"
in_container ip link set lo multicast on
in_container ip route add 224.0.0.0/4 dev lo  # the multicast route (docs/deploy.md, section 3)

# 3. dpkg -i: installed, the conffile in place and registered as one, the unit known to systemd.
in_container rm -f /var/lib/man-db/auto-update  # no man-db index rebuild (half a minute here), in the overlay only
in_container dpkg -i "/mnt/deb/$deb" >"$tmp/dpkg.log" 2>&1 || { cat "$tmp/dpkg.log"; fail "dpkg -i $deb"; }
[ "$(in_container dpkg-query -W -f='${Status} ${Version}' toposlam)" = "install ok installed $version" ] \
  || fail "dpkg-query: $(in_container dpkg-query -W -f='${Status} ${Version}' toposlam)"
in_container dpkg-query -W -f='${Conffiles}\n' toposlam | grep -q '^ /etc/toposlam/toposlam.yaml [0-9a-f]\{32\}' \
  || fail "/etc/toposlam/toposlam.yaml is no conffile of the installed package"
in_container test -f /etc/toposlam/toposlam.yaml || fail "no /etc/toposlam/toposlam.yaml after dpkg -i"
[ "$(in_container systemctl is-enabled toposlamd.service 2>&1 || true)" = disabled ] \
  || fail "toposlamd.service should be installed but not enabled: $(in_container systemctl is-enabled toposlamd.service 2>&1)"
echo "installed: $(in_container dpkg-query -W -f='${Package} ${Version}' toposlam) ($(elapsed "$t0") s)"

# 4. The config edited as a user would (a folder of images instead of the camera), then the service started.
in_container sed -i 's|^source: .*|source: "images:/srv/frames?rate=4"|' /etc/toposlam/toposlam.yaml
in_container grep -qx 'source: "images:/srv/frames?rate=4"' /etc/toposlam/toposlam.yaml || fail "the source line was not edited"
in_container toposlamd --check-config -c /etc/toposlam/toposlam.yaml >/dev/null || fail "toposlamd --check-config"
in_container systemctl start toposlamd.service || fail "systemctl start toposlamd.service"
show() { in_container systemctl show -p "$1" --value toposlamd.service; }
[ "$(show ActiveState)/$(show SubState)" = active/running ] || fail "after start: $(show ActiveState)/$(show SubState)"
echo "started (READY=1): $(show ActiveState)/$(show SubState), main process $(show MainPID) ($(elapsed "$t0") s)"
# Place messages over multicast on the container's loopback.
in_container timeout 60 toposlam listen --count 2 --timeout 50 --json >"$tmp/places.json" 2>"$tmp/listen.log" \
  || { cat "$tmp/listen.log"; fail "toposlam listen saw no place messages of the service"; }
echo "place messages: $(wc -l <"$tmp/places.json"), e.g. $(head -n 1 "$tmp/places.json" | cut -c 1-160)"
status="$(show StatusText)"
case "$status" in running*) ;; *) fail "status: '$status'" ;; esac
echo "status: $status"

# 5. Stopped cleanly: the final map saved into the state directory, exit 0.
in_container systemctl stop toposlamd.service
[ "$(show Result)" = success ] || fail "Result=$(show Result) after stop"
[ "$(show ExecMainStatus)" = 0 ] || fail "exit status $(show ExecMainStatus) after stop"
in_container test -s /var/lib/private/toposlam/map.tsm || fail "no /var/lib/private/toposlam/map.tsm after stop"
in_container journalctl --no-pager -u toposlamd.service -o cat >"$tmp/journal.log"
grep -q "map saved\|saved the map\|map saves" "$tmp/journal.log" || { cat "$tmp/journal.log"; fail "no map save in the journal"; }
echo "stopped: exit 0, $(in_container stat -c %s /var/lib/private/toposlam/map.tsm)-byte map; journal: $(grep -m 1 "frames published" "$tmp/journal.log" || true)"

# 6. toposlam-bridge's unit: installed, not enabled, its conffile registered; the config given a link as a
#    user would (MAVLink from a router on UDP port 14550: no serial device in a container), read by default
#    (--check-config without -c), the unit started (Type=exec), its loop running (the link reported silent:
#    no router sends), stopped (exit 0, the exit counters in the journal).
[ "$(in_container systemctl is-enabled toposlam-bridge.service 2>&1 || true)" = disabled ] \
  || fail "toposlam-bridge.service should be installed but not enabled: $(in_container systemctl is-enabled toposlam-bridge.service 2>&1)"
in_container dpkg-query -W -f='${Conffiles}\n' toposlam | grep -q '^ /etc/toposlam/toposlam-bridge.yaml [0-9a-f]\{32\}' \
  || fail "/etc/toposlam/toposlam-bridge.yaml is no conffile of the installed package"
in_container sed -i 's|^  protocol: wheel$|  protocol: mavlink|; s|^  udp_port: 0$|  udp_port: 14550|' \
  /etc/toposlam/toposlam-bridge.yaml
in_container toposlam-bridge --check-config | grep -qx "toposlam-bridge: config OK: /etc/toposlam/toposlam-bridge.yaml" \
  || fail "toposlam-bridge --check-config does not read /etc/toposlam/toposlam-bridge.yaml by default"
in_container systemctl start toposlam-bridge.service || fail "systemctl start toposlam-bridge.service"
bshow() { in_container systemctl show -p "$1" --value toposlam-bridge.service; }
i=0
while [ $i -lt 100 ] && ! in_container journalctl --no-pager -u toposlam-bridge.service -o cat | grep -q "link silent"; do
  sleep 0.1; i=$((i + 1))
done
[ "$(bshow ActiveState)/$(bshow SubState)" = active/running ] \
  || fail "toposlam-bridge after start: $(bshow ActiveState)/$(bshow SubState)"
in_container journalctl --no-pager -u toposlam-bridge.service -o cat >"$tmp/bridge.log"
grep -q "config /etc/toposlam/toposlam-bridge.yaml" "$tmp/bridge.log" || { cat "$tmp/bridge.log"; fail "the bridge unit read no config"; }
grep -q "bridge: udp:127.0.0.1:14550 (mavlink) -> LCM TOPOSLAM_MOTION" "$tmp/bridge.log" || { cat "$tmp/bridge.log"; fail "the bridge unit opened no UDP link"; }
grep -q "link silent" "$tmp/bridge.log" || { cat "$tmp/bridge.log"; fail "the bridge unit did not report the silent link"; }
echo "bridge started: $(bshow ActiveState)/$(bshow SubState), main process $(bshow MainPID) ($(elapsed "$t0") s)"
in_container systemctl stop toposlam-bridge.service
[ "$(bshow Result)" = success ] || fail "toposlam-bridge: Result=$(bshow Result) after stop"
[ "$(bshow ExecMainStatus)" = 0 ] || fail "toposlam-bridge: exit status $(bshow ExecMainStatus) after stop"
in_container journalctl --no-pager -u toposlam-bridge.service -o cat | grep -q "bridge exit: " \
  || fail "no exit line of the bridge in the journal"
echo "bridge stopped: exit 0"
echo "service OK ($(elapsed "$t0") s)"
