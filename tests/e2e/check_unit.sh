#!/bin/sh
# `systemd-analyze verify` must accept the unit with no output at all (no warnings). 77 = skipped.
unit="$1"
command -v systemd-analyze >/dev/null 2>&1 || { echo "systemd-analyze not installed: skipped"; exit 77; }
out="$(systemd-analyze verify "$unit" 2>&1)"
rc=$?
[ -n "$out" ] && printf '%s\n' "$out"
[ $rc -eq 0 ] && [ -z "$out" ]
