#!/bin/sh
# Each program reads its own conffile by default, from the install it belongs to: toposlamd
# <prefix>/etc/toposlam/toposlam.yaml and toposlam-bridge <prefix>/etc/toposlam/toposlam-bridge.yaml, for a
# program copied to <prefix>/sbin or <prefix>/bin as `cmake --install --prefix <prefix>` puts it (not the
# configure-time /usr/local/etc, and the bridge read no file at all without -c). The bridge then runs with
# the file's link: an emulated controller on a pseudo-terminal, LCM in memory (memq://).
# Usage: check_config_prefix.sh TOPOSLAMD BRIDGE DIR
set -u
toposlamd="$1" bridge="$2" dir="$3"
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$dir" && mkdir -p "$dir/prefix/sbin" "$dir/prefix/bin" "$dir/prefix/etc/toposlam"
prefix="$dir/prefix"
cp "$toposlamd" "$prefix/sbin/toposlamd" && cp "$bridge" "$prefix/bin/toposlam-bridge" || fail "cannot copy the programs"
unset CONFIGURATION_DIRECTORY  # systemd's, which would come first

# 1. toposlamd: --print-config and --check-config name and read the prefix's toposlam.yaml.
printf 'map:\n  save_period_s: 7.0\n' >"$prefix/etc/toposlam/toposlam.yaml"
out="$("$prefix/sbin/toposlamd" --print-config)" || fail "toposlamd --print-config exited $?"
echo "$out" | grep -qx "# toposlamd's effective config: $prefix/etc/toposlam/toposlam.yaml" \
  || fail "toposlamd did not read the prefix's config: $(echo "$out" | head -n 1)"
echo "$out" | grep -qx "  save_period_s: 7.0" || fail "toposlamd --print-config does not show the file's value"
"$prefix/sbin/toposlamd" --check-config | grep -qx "toposlamd: config OK: $prefix/etc/toposlam/toposlam.yaml" \
  || fail "toposlamd --check-config did not check the prefix's config"
echo "toposlamd: $prefix/etc/toposlam/toposlam.yaml"

# 2. toposlam-bridge: the same for toposlam-bridge.yaml.
printf 'link:\n  baud: 57600\n' >"$prefix/etc/toposlam/toposlam-bridge.yaml"
out="$("$prefix/bin/toposlam-bridge" --print-config)" || fail "toposlam-bridge --print-config exited $?"
echo "$out" | grep -qx "# toposlam-bridge's effective config: $prefix/etc/toposlam/toposlam-bridge.yaml" \
  || fail "toposlam-bridge did not read the prefix's config: $(echo "$out" | head -n 1)"
echo "$out" | grep -qx "  baud: 57600" || fail "toposlam-bridge --print-config does not show the file's value"
"$prefix/bin/toposlam-bridge" --check-config 2>"$dir/check.log"
rc=$?
[ $rc -eq 2 ] || fail "toposlam-bridge --check-config without a link exited $rc, expected 2"
grep -q "$prefix/etc/toposlam/toposlam-bridge.yaml: no link" "$dir/check.log" \
  || fail "the missing link is not said with the file: $(cat "$dir/check.log")"
echo "toposlam-bridge: $prefix/etc/toposlam/toposlam-bridge.yaml"

# 3. toposlam-bridge --duration 1 runs the file's link: an emulated controller's pty, LCM in memory.
"$bridge" --emulate wheel-odometry --loop >"$dir/pty" 2>"$dir/emulator.log" &
emulator=$!
i=0
while [ ! -s "$dir/pty" ] && [ $i -lt 100 ]; do sleep 0.05; i=$((i + 1)); done
pty="$(head -n 1 "$dir/pty")"
[ -n "$pty" ] || { kill "$emulator"; fail "the emulator printed no pty: $(cat "$dir/emulator.log")"; }
printf 'link:\n  serial: %s\nlcm:\n  url: "memq://"\nstatus:\n  period_s: 0\n' "$pty" \
  >"$prefix/etc/toposlam/toposlam-bridge.yaml"
"$prefix/bin/toposlam-bridge" --check-config >/dev/null || { kill "$emulator"; fail "--check-config of the pty's config"; }
"$prefix/bin/toposlam-bridge" --duration 1 2>"$dir/bridge.log"
rc=$?
kill "$emulator" 2>/dev/null
wait "$emulator" 2>/dev/null
[ $rc -eq 0 ] || fail "toposlam-bridge --duration 1 exited $rc: $(cat "$dir/bridge.log")"
grep -q "config $prefix/etc/toposlam/toposlam-bridge.yaml" "$dir/bridge.log" || fail "no config line: $(cat "$dir/bridge.log")"
grep -q "bridge: $pty .*-> LCM TOPOSLAM_MOTION on memq://" "$dir/bridge.log" \
  || fail "the bridge did not open the file's link: $(cat "$dir/bridge.log")"
echo "toposlam-bridge --duration 1: $(grep -m 1 "bridge exit" "$dir/bridge.log" | cut -c 1-120)"
echo "config prefix OK"
