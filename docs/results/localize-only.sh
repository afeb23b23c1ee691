#!/bin/bash
# Localisation only (docs/daemon.md, "Localisation only"; docs/results.md, "Localisation only"): each set's
# first lap is mapped (`toposlam map`), its second lap localised in that map (`toposlam map --localize-only
# --resume`), which is never changed. A frame's answer (frames.csv's node: what toposlamd publishes in
# place_t) is right when the node holds a first-lap frame of the same place: by the ground-truth pairs on
# the real sets (rtabmap samples: frames 1-40 then 41-84; the corridor: ref/ then query/), by the pose on the
# simulated worlds (a first-lap frame of the node within 2 m and 1 rad; office and home, --route loop2 split
# at the second lap). "unknown" is a frame answered "not a known node". The baseline is the same localiser
# with the places' representatives only (segmentation.place_views=0 when mapping: the map the thesis keeps).
# Then every setting of the grid, leave one set out: the setting with the most frames right less wrong on
# the other sets (a wrong answer costs a robot more than "not known").
# Usage: docs/results/localize-only.sh BUILD_DIR WORK_DIR   (about 5 minutes on 2 cores)
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
build=$1 work=$2
T="$build/src/apps/toposlam/toposlam"
[ -x "$T" ] || { echo "localize-only: no $T (build first: scripts/build.sh)" >&2; exit 2; }
mkdir -p "$work"
data="$repo/tests/data"
for world in office home; do "$repo/scripts/sim-laps.sh" "$T" "$world" "$work/$world"; done
mkdir -p "$work/samples/lap1" "$work/samples/lap2"
for i in $(seq 1 84); do
  lap=lap1 && [ "$i" -gt 40 ] && lap=lap2
  ln -sf "$data/rtabmap-samples/samples/$i.jpg" "$work/samples/$lap/$i.jpg"
done
declare -A lap1 lap2 truth
for world in office home; do
  lap1[$world]="images:$work/$world/lap1/frames" lap2[$world]="images:$work/$world/lap2/frames"
  truth[$world]="pose:$work/$world/lap1/labels.csv:$work/$world/lap2/labels.csv"
done
lap1[samples]="images:$work/samples/lap1" lap2[samples]="images:$work/samples/lap2"
truth[samples]="pairs:$data/rtabmap-samples/samples_GT_pairs.csv"
lap1[corridor]="images:$data/vprbench-corridor/ref" lap2[corridor]="images:$data/vprbench-corridor/query"
truth[corridor]="pairs:$data/vprbench-corridor/gt.csv"
# Another building: the home's second lap localised in the office's map, where the right answer is always
# "not a known node" (counted right; any node counted wrong).
lap1[foreign]="${lap1[office]}" lap2[foreign]="${lap2[home]}" truth[foreign]="foreign:"
sets=(office home samples corridor foreign)
settings=("0.01 0.5" "0.001 0.5" "0.1 0.5" "0.01 0.3" "0.01 0.7")  # jump_weight min_probability
for set in "${sets[@]}"; do
  for views in 7 0 3 15; do
    map="$work/runs/$set-map-views$views"
    [ "$set" = foreign ] && { mkdir -p "$map"; cp -u "$work/runs/office-map-views$views/map.tsm" "$work/runs/office-map-views$views/frames.csv" "$map/"; }
    [ -f "$map/map.tsm" ] || "$T" map "${lap1[$set]}" --out "$map" --quiet --set segmentation.place_views=$views >/dev/null 2>&1
  done
  for s in "${settings[@]}"; do
    read -r jump minp <<<"$s"
    views_tried="7 0"
    [ "$s" = "${settings[0]}" ] && views_tried="7 0 3 15"
    for views in $views_tried; do
      run="$work/runs/$set-loc-views$views-jump$jump-min$minp"
      [ -f "$run/frames.csv" ] || "$T" map "${lap2[$set]}" --localize-only --resume "$work/runs/$set-map-views$views/map.tsm" \
        --out "$run" --quiet --resume-other-settings --set map.localize.jump_weight=$jump --set map.localize.min_probability=$minp >/dev/null 2>&1
    done
  done
done
python3 - "$work/runs" "${sets[*]}" "${settings[@]}" <<'PY' "${truth[office]}" "${truth[home]}" "${truth[samples]}" "${truth[corridor]}" "${truth[foreign]}"
import csv, math, sys
runs, sets, settings = sys.argv[1], sys.argv[2].split(), sys.argv[3:8]
truths = dict(zip(sets, sys.argv[8:13]))
def score(set_name, views, setting):
    jump, minp = setting.split()
    mapdir = "%s/%s-map-views%s" % (runs, set_name, views)
    locdir = "%s/%s-loc-views%s-jump%s-min%s" % (runs, set_name, views, jump, minp)
    mframes = list(csv.DictReader(open(mapdir + "/frames.csv")))
    lframes = list(csv.DictReader(open(locdir + "/frames.csv")))
    kind, rest = truths[set_name].split(":", 1)
    right = wrong = unknown = 0
    if kind == "foreign":
        for f in lframes:
            if int(f["node"]) < 0: right += 1
            else: wrong += 1
    elif kind == "pose":
        l1, l2 = rest.split(":")
        p1, p2 = list(csv.DictReader(open(l1))), list(csv.DictReader(open(l2)))
        poses = {}
        for f in mframes:
            lab = p1[int(f["frame"])]
            poses.setdefault(int(f["node"]), []).append((float(lab["x"]), float(lab["y"]), float(lab["heading"])))
        for f in lframes:
            n, lab = int(f["node"]), p2[int(f["frame"])]
            x, y, h = float(lab["x"]), float(lab["y"]), float(lab["heading"])
            if n < 0: unknown += 1
            elif any(math.hypot(x - a, y - b) <= 2.0 and abs(math.atan2(math.sin(h - c), math.cos(h - c))) <= 1.0
                     for a, b, c in poses.get(n, [])): right += 1
            else: wrong += 1
    else:
        node_of = {f["name"]: int(f["node"]) for f in mframes}
        truth = {}
        rows = list(csv.reader(open(rest)))
        for row in rows[1:]:
            truth[row[0].split("/")[-1]] = [m.split("/")[-1] for m in row[1].split()]
        for f in lframes:
            n, matches = int(f["node"]), truth.get(f["name"], [])
            if not matches: continue
            if n < 0: unknown += 1
            elif n in {node_of.get(m, -2) for m in matches}: right += 1
            else: wrong += 1
    nodes = len({int(f["node"]) for f in mframes})
    return right, wrong, unknown, nodes
print("| set | nodes | views 7: right / wrong / unknown | share right | representatives only (baseline) | share right |")
print("|---|---|---|---|---|---|")
default = settings[0]
for s in sets:
    r, w, u, n = score(s, 7, default)
    rb, wb, ub, nb = score(s, 0, default)
    print("| %s | %d | %d / %d / %d | %.3f | %d / %d / %d | %.3f |" % (s, n, r, w, u, r / (r + w + u), rb, wb, ub, rb / (rb + wb + ub)))
print()
print()
print("Views per place (the default localiser), (right - wrong) / frames, and leave one set out:")
print("| views | " + " | ".join(sets) + " |")
print("|---|" + "---|" * len(sets))
vshare = {}
for v in (0, 3, 7, 15):
    for s in sets:
        r, w, u, n = score(s, v, default)
        vshare[(s, v)] = (r - w) / (r + w + u)
    print("| %d | " % v + " | ".join("%.3f" % vshare[(s, v)] for s in sets) + " |")
for held in sets:
    others = [s for s in sets if s != held]
    best = max((0, 3, 7, 15), key=lambda v: (sum(vshare[(s, v)] for s in others), -v))
    print("held out %s: %d views chosen on the others -> %.3f (7: %.3f)" % (held, best, vshare[(held, best)], vshare[(held, 7)]))
print()
# A wrong answer costs a robot more than "not known": each setting is judged by (right - wrong) / frames.
print("Grid (views 7): right / wrong / unknown per set, and leave one set out on (right - wrong) / frames:")
counts = {(s, g): score(s, 7, g) for s in sets for g in settings}
share = {k: (r - w) / (r + w + u) for k, (r, w, u, n) in counts.items()}
print("| jump_weight min_probability | " + " | ".join(sets) + " |")
print("|---|" + "---|" * len(sets))
for g in settings:
    print("| %s | " % g + " | ".join("%d / %d / %d" % counts[(s, g)][:3] for s in sets) + " |")
for held in sets:
    others = [s for s in sets if s != held]
    best = max(settings, key=lambda g: (sum(share[(s, g)] for s in others), g == default))
    print("held out %s: chosen on the others %s -> %.3f (the default %s: %.3f)" % (held, best, share[(held, best)], default, share[(held, default)]))
PY
