#!/bin/sh
# `cmake --install` puts the service binaries, their units, the default configs and the LCM definitions in place,
# at the FHS paths a package uses: with --prefix /usr the config is /etc/toposlam/toposlam.yaml (where
# toposlamd and the unit's ConfigurationDirectory= look), never /usr/etc. Another prefix keeps it under
# the prefix (P/etc/toposlam).
set -eu
build="$1"
dest="$(mktemp -d)"
trap 'rm -rf "$dest"' EXIT
fail() { echo "$*"; exit 1; }

# 1. A package's install: DESTDIR staging, prefix /usr.
DESTDIR="$dest/pkg" cmake --install "$build" --prefix /usr >/dev/null
for f in usr/sbin/toposlamd usr/bin/toposlam usr/lib/systemd/system/toposlamd.service etc/toposlam/toposlam.yaml \
         usr/bin/toposlam-bridge usr/lib/systemd/system/toposlam-bridge.service \
         usr/share/toposlam/lcm/place_t.lcm usr/share/toposlam/lcm/motion_t.lcm usr/include/toposlam_lcm/place_t.hpp \
         usr/share/doc/toposlam/examples/50-toposlam-multicast.network etc/toposlam/toposlam-bridge.yaml \
         usr/lib/python3/dist-packages/toposlam_lcm/__init__.py usr/lib/python3/dist-packages/toposlam_lcm/udpm_reader.py \
         usr/share/doc/toposlam/examples/python/listen_places.py usr/share/doc/toposlam/examples/cpp/listen_places.cpp \
         usr/share/toposlam/view/live_view.py usr/share/toposlam/view/live_view.html; do
  [ -e "$dest/pkg/$f" ] || fail "missing after install --prefix /usr: $f"
done
[ -z "$(find "$dest/pkg" -name __pycache__ -o -name '*.pyc')" ] || fail "install --prefix /usr wrote Python byte code"
[ ! -e "$dest/pkg/usr/etc" ] || fail "install --prefix /usr wrote usr/etc/ (toposlamd never reads it): $(find "$dest/pkg/usr/etc")"
grep -q "^ExecStart=/usr/sbin/toposlamd\$" "$dest/pkg/usr/lib/systemd/system/toposlamd.service" \
  || fail "the unit installed with --prefix /usr does not start /usr/sbin/toposlamd"
grep -q "^Documentation=file:///usr/share/doc/toposlam/daemon.md\$" "$dest/pkg/usr/lib/systemd/system/toposlamd.service" \
  || fail "the unit installed with --prefix /usr does not name /usr/share/doc/toposlam/daemon.md"
"$dest/pkg/usr/sbin/toposlamd" --check-config -c "$dest/pkg/etc/toposlam/toposlam.yaml"
grep -q "^ExecStart=/usr/bin/toposlam-bridge\$" "$dest/pkg/usr/lib/systemd/system/toposlam-bridge.service" \
  || fail "the bridge unit installed with --prefix /usr does not start /usr/bin/toposlam-bridge"
grep -q "^Documentation=file:///usr/share/doc/toposlam/firmware-host.md\$" "$dest/pkg/usr/lib/systemd/system/toposlam-bridge.service" \
  || fail "the bridge unit installed with --prefix /usr does not name /usr/share/doc/toposlam/firmware-host.md"
# The video module (loaded on first use) is installed beside the programs, and the installed program
# loads that copy, not the build tree's.
module=$(find "$dest/pkg/usr/lib" -name toposlam-source-video.so)
[ -n "$module" ] || fail "missing after install --prefix /usr: the video module toposlam-source-video.so"
if command -v ffmpeg >/dev/null; then
  ffmpeg -loglevel error -f lavfi -i testsrc=size=96x64:rate=5 -t 1 -y "$dest/clip.mp4"
  LD_DEBUG=files "$dest/pkg/usr/bin/toposlam" segment "video:$dest/clip.mp4" --out "$dest/seg" >"$dest/ld.log" 2>&1 \
    || { cat "$dest/ld.log"; fail "the installed toposlam could not segment a video"; }
  grep -q "file=$module " "$dest/ld.log" || fail "the installed toposlam did not load the installed video module $module"
fi

# The libcamera module likewise, when the build made one (pkg-config found libcamera): the installed
# program loads the installed copy at the first libcamera: URI (no camera here: a clear error, exit 1).
if [ -e "$build/modules/toposlam-source-libcamera.so" ]; then
  module=$(find "$dest/pkg/usr/lib" -name toposlam-source-libcamera.so)
  [ -n "$module" ] || fail "missing after install --prefix /usr: the libcamera module toposlam-source-libcamera.so"
  rc=0
  LD_DEBUG=files "$dest/pkg/usr/bin/toposlam" segment "libcamera:no-such-camera" --out "$dest/lc" >"$dest/ld.log" 2>&1 || rc=$?
  [ "$rc" -eq 1 ] || { tail -5 "$dest/ld.log"; fail "the installed toposlam on a missing libcamera camera: exit $rc, expected 1"; }
  grep -q "file=$module " "$dest/ld.log" || fail "the installed toposlam did not load the installed libcamera module $module"
  grep -q "libcamera:no-such-camera: no camera with this ID" "$dest/ld.log" \
    || fail "the installed toposlam did not say the libcamera camera is missing"
fi

# The installed `toposlam view` runs the installed server with the installed toposlam_lcm (not the source
# or build tree's) and serves its page (multicast or not: without a route it says it is waiting for one).
if command -v python3 >/dev/null && command -v curl >/dev/null; then
  port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  "$dest/pkg/usr/bin/toposlam" view --port "$port" --lcm-url "udpm://239.255.76.67:7667?ttl=0" >"$dest/view.log" 2>&1 &
  view=$!
  i=0
  until curl -sf "http://127.0.0.1:$port/" -o "$dest/view.html"; do
    i=$((i + 1))
    [ $i -le 100 ] && kill -0 "$view" 2>/dev/null || { cat "$dest/view.log"; fail "the installed toposlam view did not serve its page"; }
    sleep 0.1
  done
  tr '\0' ' ' <"/proc/$view/cmdline" | grep -q " $dest/pkg/usr/share/toposlam/view/live_view.py " \
    || fail "the installed toposlam view did not run the installed live_view.py: $(tr '\0' ' ' <"/proc/$view/cmdline")"
  tr '\0' '\n' <"/proc/$view/environ" | grep -q "^PYTHONPATH=$dest/pkg/usr/lib/python3/dist-packages" \
    || fail "the installed toposlam view did not put the installed toposlam_lcm first on PYTHONPATH"
  grep -q "toposlam live view" "$dest/view.html" || fail "the installed toposlam view served another page"
  kill -TERM "$view"
  rc=0; wait "$view" || rc=$?
  [ $rc -eq 0 ] || fail "the installed toposlam view exited with $rc after SIGTERM"
  [ -z "$(find "$dest/pkg" -name __pycache__)" ] || fail "the installed toposlam view wrote Python byte code"
fi

# 2. A private prefix: everything under it, the unit pointing at its binary.
cmake --install "$build" --prefix "$dest/local" >/dev/null
for f in sbin/toposlamd bin/toposlam lib/systemd/system/toposlamd.service etc/toposlam/toposlam.yaml \
         bin/toposlam-bridge lib/systemd/system/toposlam-bridge.service etc/toposlam/toposlam-bridge.yaml \
         lib/python3/dist-packages/toposlam_lcm/place_t.py share/toposlam/view/live_view.py; do
  [ -e "$dest/local/$f" ] || fail "missing after install --prefix P: P/$f"
done
grep -q "^ExecStart=$dest/local/sbin/toposlamd\$" "$dest/local/lib/systemd/system/toposlamd.service" \
  || fail "the installed unit does not start the installed binary"
"$dest/local/sbin/toposlamd" --check-config -c "$dest/local/etc/toposlam/toposlam.yaml"
grep -q "^ExecStart=$dest/local/bin/toposlam-bridge\$" "$dest/local/lib/systemd/system/toposlam-bridge.service" \
  || fail "the installed bridge unit does not start the installed binary"
# Without -c, the installed programs read the configs of their own prefix (not the configure-time one).
(unset CONFIGURATION_DIRECTORY; "$dest/local/sbin/toposlamd" --print-config) | head -n 1 \
  | grep -qx "# toposlamd's effective config: $dest/local/etc/toposlam/toposlam.yaml" \
  || fail "the installed toposlamd does not read P/etc/toposlam/toposlam.yaml by default"
(unset CONFIGURATION_DIRECTORY; "$dest/local/bin/toposlam-bridge" --print-config) | head -n 1 \
  | grep -qx "# toposlam-bridge's effective config: $dest/local/etc/toposlam/toposlam-bridge.yaml" \
  || fail "the installed toposlam-bridge does not read P/etc/toposlam/toposlam-bridge.yaml by default"
echo "install OK"
