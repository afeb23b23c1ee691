#!/bin/sh
# `cmake --install` puts the service binary, the unit, the default config and the LCM definitions in place.
set -eu
build="$1"
dest="$(mktemp -d)"
trap 'rm -rf "$dest"' EXIT
cmake --install "$build" --prefix "$dest/usr" >/dev/null
for f in usr/sbin/toposlamd usr/bin/toposlam usr/lib/systemd/system/toposlamd.service usr/etc/toposlam/toposlam.yaml \
         usr/share/toposlam/lcm/place_t.lcm usr/share/toposlam/lcm/motion_t.lcm usr/include/toposlam_lcm/place_t.hpp; do
  [ -e "$dest/$f" ] || { echo "missing after install: $f"; exit 1; }
done
grep -q "^ExecStart=$dest/usr/sbin/toposlamd\$" "$dest/usr/lib/systemd/system/toposlamd.service" \
  || { echo "the installed unit does not start the installed binary"; exit 1; }
"$dest/usr/sbin/toposlamd" --check-config -c "$dest/usr/etc/toposlam/toposlam.yaml"
echo "install OK"
