#!/bin/sh
# The map on the desk (issue 40, item 3): a map.tsm alone, from `toposlam map` on the bundled samples, says
# what it holds (map-info: the run's places and nodes), becomes a run folder (export) that eval and report
# read with the original run's figures where the map holds the information (every frame's place and node,
# the places, the loop-closure curve), and is reported directly (report MAP). A missing, truncated or
# foreign map file is a clear error (exit 1) that writes nothing.
# toposlamd's map of the same frames opens the same way (its places by their representative frames).
# Usage: check_map_desk.sh TOPOSLAM TOPOSLAMD SAMPLES_DIR GROUND_TRUTH DIR
set -u
toposlam="$1" toposlamd="$2" samples="$3" truth="$4" dir="$5"
rm -rf "$dir" && mkdir -p "$dir"
fail() { echo "FAIL: $*"; exit 1; }
field() { python3 -c "import json,sys; v=json.load(open(sys.argv[1]))
for k in sys.argv[2].split('.'): v=v[k]
print(v)" "$1" "$2"; }

"$toposlam" map "images:$samples" --out "$dir/run" --json --quiet >"$dir/map.json" 2>/dev/null || fail "map"
map="$dir/run/map.tsm"
[ -f "$dir/run/map.tsm.lock" ] && fail "a stale map.tsm.lock stayed in the run folder after a clean exit"

# 1. map-info: the run's numbers.
"$toposlam" map-info "$map" --json >"$dir/info.json" || fail "map-info --json"
for k in places nodes; do
  [ "$(field "$dir/info.json" $k)" = "$(field "$dir/map.json" $k)" ] \
    || fail "map-info $k $(field "$dir/info.json" $k), the run said $(field "$dir/map.json" $k)"
done
[ "$(field "$dir/info.json" frames)" = 84 ] || fail "map-info frames: $(field "$dir/info.json" frames)"
[ "$(field "$dir/info.json" bytes)" = "$(wc -c <"$map")" ] || fail "map-info bytes"
[ "$(field "$dir/info.json" preset)" = default ] || fail "map-info preset: $(field "$dir/info.json" preset)"
[ "$(field "$dir/info.json" written_by)" = "toposlam map" ] || fail "map-info written_by"
case "$(field "$dir/info.json" source)" in images:/*/samples) ;; *) fail "map-info source: $(field "$dir/info.json" source)" ;; esac
"$toposlam" map-info "$map" >"$dir/info.txt" || fail "map-info"
grep -q "^places  *$(field "$dir/map.json" places)\$" "$dir/info.txt" || fail "map-info text: $(cat "$dir/info.txt")"
grep -q "^saved  *20[0-9-]*T[0-9:]*Z\$" "$dir/info.txt" || fail "map-info text has no save time"
echo "map-info: $(field "$dir/info.json" places) places, $(field "$dir/info.json" nodes) nodes, as the run"

# 2. export: the frames' places and nodes and the places as the run folder has them.
"$toposlam" export "$map" --out "$dir/desk" >"$dir/export.txt" || fail "export"
python3 - "$dir/run" "$dir/desk" <<'PY' || fail "export differs from the run folder"
import csv, json, sys
run, desk = sys.argv[1], sys.argv[2]
def rows(folder, name, cols):
    with open(f"{folder}/{name}") as f:
        return [tuple(r[c] for c in cols) for r in csv.DictReader(f)]
a, b = rows(run, "frames.csv", ["frame", "place", "node"]), rows(desk, "frames.csv", ["frame", "place", "node"])
assert len(a) == 84 and a == b, f"frames.csv: {len(a)} vs {len(b)} rows, first difference {next((x, y) for x, y in zip(a, b) if x != y) if a != b else None}"
cols = ["place", "first", "last", "representative", "keypoints", "node", "end"]
assert rows(run, "places.csv", cols) == rows(desk, "places.csv", cols), "places.csv"
ta, tb = json.load(open(f"{run}/topology.json")), json.load(open(f"{desk}/topology.json"))
assert [(n["id"], n["places"]) for n in ta["nodes"]] == [(n["id"], n["places"]) for n in tb["nodes"]], "topology nodes"
assert ta["edges"] == tb["edges"], "topology edges"
assert abs(ta["probability"] - tb["probability"]) < 1e-9, "topology probability"
assert ta["history"] == tb["history"] and len(tb["history"]) == len(rows(run, "places.csv", ["place"])), "history"
print(f"export: {len(b)} frames, places and topology as the run folder")
PY

# 3. eval and report read the export with the run's figures.
"$toposlam" eval "$dir/run" --truth "$truth" --json >"$dir/eval-run.json" 2>/dev/null || fail "eval run"
"$toposlam" eval "$dir/desk" --truth "$truth" --json >"$dir/eval-desk.json" 2>/dev/null || fail "eval export"
python3 - "$dir/eval-run.json" "$dir/eval-desk.json" <<'PY' || fail "eval of the export differs"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
for k in ["frames", "places", "traversals", "loop_closure", "best_topology_probability"]:
    assert a.get(k) == b.get(k), f"{k}: {a.get(k)} vs {b.get(k)}"
assert a["loop_closure"] is not None, "no loop-closure curve"
print(f"eval: frames {b['frames']}, places {b['places']}, the loop-closure curve as the run's")
PY
"$toposlam" report "$dir/run" --json --out "$dir/run.html" >"$dir/report-run.json" 2>/dev/null || fail "report run"
mkdir -p "$dir/tmp"
TMPDIR="$dir/tmp" "$toposlam" report "$map" --json >"$dir/report-map.json" 2>"$dir/report-map.err" \
  || fail "report MAP: $(cat "$dir/report-map.err")"
[ -z "$(ls -A "$dir/tmp")" ] || fail "report MAP left its temporary run folder: $(ls -A "$dir/tmp")"
[ -s "$dir/run/map.report.html" ] || fail "report MAP wrote no $dir/run/map.report.html"
for k in frames places; do
  [ "$(field "$dir/report-map.json" $k)" = "$(field "$dir/report-run.json" $k)" ] || fail "report MAP $k"
done
[ "$(field "$dir/report-map.json" thumbnails)" -ge 50 ] || fail "report MAP thumbnails: $(cat "$dir/report-map.json")"
echo "report MAP: $(field "$dir/report-map.json" frames) frames, $(field "$dir/report-map.json" thumbnails) thumbnails"

# 4. Damaged or missing maps: a clear error, exit 1, nothing written.
head -c 200 "$map" >"$dir/truncated.tsm"
echo "not a map" >"$dir/foreign.tsm"
for case in missing truncated foreign; do
  for command in map-info export report; do
    out=""
    [ "$command" = export ] && out="--out $dir/bad-$case"
    [ "$command" = report ] && out="--out $dir/bad-$case.html"
    # shellcheck disable=SC2086  # $out is empty or two words
    "$toposlam" $command "$dir/$case.tsm" $out >"$dir/err.out" 2>&1
    rc=$?
    [ $rc = 1 ] || fail "$command on a $case map: exit $rc: $(cat "$dir/err.out")"
    grep -q "^toposlam: error: $command: .*$case.tsm" "$dir/err.out" || fail "$command on a $case map said: $(cat "$dir/err.out")"
    [ -e "$dir/bad-$case" ] || [ -e "$dir/bad-$case.html" ] && fail "$command on a $case map wrote something"
  done
  echo "$case map: $(head -1 "$dir/err.out")"
done
# 5. toposlamd's map: written by it, its places, frames up to the last one it holds, thumbnails from its source.
mkdir -p "$dir/daemon"
"$toposlamd" --source "images:$samples" --map "$dir/daemon/map.tsm" --lcm-url memq:// >"$dir/daemon/log" 2>&1 \
  || fail "toposlamd: $(tail -3 "$dir/daemon/log")"
[ -e "$dir/daemon/map.tsm.lock" ] && fail "toposlamd left its map.tsm.lock after a clean exit"
places=$(sed -n 's/.* \([0-9]*\) places, [0-9]* map saves.*/\1/p' "$dir/daemon/log")
"$toposlam" map-info "$dir/daemon/map.tsm" --json >"$dir/daemon/info.json" || fail "map-info of toposlamd's map"
[ "$(field "$dir/daemon/info.json" written_by)" = toposlamd ] || fail "toposlamd's map: written_by"
[ "$(field "$dir/daemon/info.json" places)" = "$places" ] || fail "toposlamd's map: $(field "$dir/daemon/info.json" places) places, the log said $places"
"$toposlam" report "$dir/daemon/map.tsm" --json >"$dir/daemon/report.json" 2>/dev/null || fail "report of toposlamd's map"
[ "$(field "$dir/daemon/report.json" places)" = "$places" ] && [ "$(field "$dir/daemon/report.json" thumbnails)" -ge "$places" ] \
  || fail "report of toposlamd's map: $(cat "$dir/daemon/report.json")"
echo "toposlamd's map: $places places, $(field "$dir/daemon/report.json" frames) frames, $(field "$dir/daemon/report.json" thumbnails) thumbnails"
echo "map on the desk OK"
