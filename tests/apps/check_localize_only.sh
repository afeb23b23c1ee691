#!/bin/sh
# Localisation only (docs/daemon.md, "Localisation only"; issue 40's target): the simulated office's first lap
# is mapped, its second lap localised in that map, by `toposlam map --localize-only` and by toposlamd
# --localize-only through an LCM log. Fails unless
#   - at least 90 % of the second lap's frames are on a right node by pose (a first-lap frame of the node
#     within 2 m and 1 rad; measured 774 of 801, 96.6 %) and at most 3 % on a wrong one (measured 8);
#   - the map gains nothing: the map file is byte for byte the same after both runs, and the run's topology
#     has the map's nodes (13 measured), none added;
#   - toposlamd publishes, frame by frame, the answer `map` writes (place_t.node and match_node: the node the
#     robot is in now, -1 "not a known node"), for every frame;
#   - toposlamd with no map to localise in exits 2 naming the problem, and writes no map.
# Usage: check_localize_only.sh TOPOSLAM TOPOSLAMD SCRIPTS_DIR OUT_DIR
set -eu
toposlam=$1 toposlamd=$2 scripts=$3 out=$4
rm -rf "$out" && mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }
sh "$scripts/sim-laps.sh" "$toposlam" office "$out" || fail "the two laps of the simulator"
"$toposlam" map "images:$out/lap1/frames" --out "$out/map" --quiet >"$out/map.txt" 2>&1 || fail "map: $(tail -3 "$out/map.txt")"
before=$(cksum <"$out/map/map.tsm")
"$toposlam" map "images:$out/lap2/frames" --localize-only --resume "$out/map/map.tsm" --out "$out/loc" --quiet \
  >"$out/loc.txt" 2>&1 || fail "map --localize-only: $(tail -3 "$out/loc.txt")"
[ ! -e "$out/loc/map.tsm" ] || fail "map --localize-only wrote a map"
"$toposlamd" --localize-only --map "$out/map/map.tsm" --source "images:$out/lap2/frames" \
  --lcm-url "file://$out/loc.lcmlog?mode=w" --overflow block >"$out/daemon.txt" 2>&1 \
  || fail "toposlamd --localize-only: $(tail -3 "$out/daemon.txt")"
[ "$(cksum <"$out/map/map.tsm")" = "$before" ] || fail "the map file changed"
grep -q "localising in" "$out/daemon.txt" || fail "toposlamd did not say it localises"
"$toposlam" listen --from "lcmlog:$out/loc.lcmlog" --channels place --json >"$out/place.jsonl" 2>"$out/listen.txt" \
  || fail "reading the log: $(tail -3 "$out/listen.txt")"
status=0
"$toposlamd" --localize-only --map "$out/none/map.tsm" --source "images:$out/lap2/frames" --lcm-url "memq://" \
  >"$out/nomap.txt" 2>&1 || status=$?
[ "$status" -eq 2 ] || fail "toposlamd with no map exited $status, not 2"
grep -q "map.mode is localize but there is no map at" "$out/nomap.txt" || fail "no reason given: $(tail -2 "$out/nomap.txt")"
[ ! -e "$out/none/map.tsm" ] || fail "toposlamd with no map wrote one"
python3 - "$out" <<'PY' || fail "localisation"
import csv, json, math, sys
d = sys.argv[1]
lap1 = list(csv.DictReader(open(d + "/lap1/labels.csv")))
lap2 = list(csv.DictReader(open(d + "/lap2/labels.csv")))
poses = {}
for f in csv.DictReader(open(d + "/map/frames.csv")):
    lab = lap1[int(f["frame"])]
    poses.setdefault(int(f["node"]), []).append((float(lab["x"]), float(lab["y"]), float(lab["heading"])))
frames = list(csv.DictReader(open(d + "/loc/frames.csv")))
right = wrong = unknown = 0
for f in frames:
    n, lab = int(f["node"]), lap2[int(f["frame"])]
    x, y, h = float(lab["x"]), float(lab["y"]), float(lab["heading"])
    if n < 0:
        unknown += 1
    elif any(math.hypot(x - a, y - b) <= 2.0 and abs(math.atan2(math.sin(h - c), math.cos(h - c))) <= 1.0
             for a, b, c in poses.get(n, [])):
        right += 1
    else:
        wrong += 1
total = len(frames)
map_nodes = len(json.load(open(d + "/map/topology.json"))["nodes"])
loc_nodes = len(json.load(open(d + "/loc/topology.json"))["nodes"])
def places(obj):
    if isinstance(obj, dict):
        if "match_node" in obj and "frame" in obj: yield obj
        for v in obj.values(): yield from places(v)
published = {}
for line in open(d + "/place.jsonl"):
    for p in places(json.loads(line)): published[p["frame"]] = (p["node"], p["match_node"])
same = sum(1 for f in frames if published.get(int(f["frame"])) == (int(f["node"]), int(f["node"])))
print("second lap: %d frames, %d on a right node by pose (%.1f %%), %d wrong, %d not known; map %d nodes, "
      "after %d; toposlamd published %d frames, %d the same as map's" % (total, right, 100.0 * right / total, wrong,
      unknown, map_nodes, loc_nodes, len(published), same))
ok = total > 700 and 10 * right >= 9 * total and 100 * wrong <= 3 * total
ok = ok and map_nodes == loc_nodes and map_nodes >= 8 and len(published) == total and same == total
sys.exit(0 if ok else 1)
PY
echo "localize only OK"
