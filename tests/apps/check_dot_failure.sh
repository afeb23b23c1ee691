#!/bin/sh
# A failing Graphviz `dot` (a full disk, a broken install) leaves no truncated topology.svg/png under the
# real name (issue 19): `map` draws to a temporary name and renames only what dot finished. A fake `dot`
# first in PATH writes half a drawing and fails; the earlier drawing (or none) must remain, no temporary.
# Usage: check_dot_failure.sh TOPOSLAM SAMPLES_DIR OUT_DIR
set -eu
toposlam=$1 samples=$2 out=$3
rm -rf "$out"
mkdir -p "$out/bin"
"$toposlam" map "images:$samples" --out "$out/run" >/dev/null 2>&1
before=$(cat "$out/run/topology.svg" 2>/dev/null | cksum)
cat > "$out/bin/dot" <<'DOT'
#!/bin/sh
# writes half a drawing to the -o file, then fails
while [ $# -gt 0 ]; do [ "$1" = "-o" ] && { printf '<svg half' > "$2"; }; shift; done
exit 1
DOT
chmod +x "$out/bin/dot"
PATH="$out/bin:$PATH" "$toposlam" map "images:$samples" --out "$out/run" > /dev/null 2> "$out/map.err"
grep "warning: .*dot.* failed" "$out/map.err"
after=$(cat "$out/run/topology.svg" 2>/dev/null | cksum)
if [ "$before" != "$after" ]; then echo "topology.svg changed by a failing dot"; exit 1; fi
if ls -a "$out/run" | grep -q '\.tmp$'; then echo "temporary left behind:"; ls -a "$out/run"; exit 1; fi
echo "dot failure OK"
