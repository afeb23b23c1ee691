#!/usr/bin/env bash
# Leave-one-set-out choice of the filter's sequence evidence weight (topology.sequence_evidence.weight,
# `toposlam map --sequence-evidence W`): the topology's place revisits (closed right / wrong closures /
# missed) on every real set as one stream (scripts/real-bench.sh: judged by the set's loop-closure truth,
# ie-tower's look-alike floors by its floor labels)
# and every simulated world of scripts/sim-bench.sh (judged by the camera's pose), for each weight and
# filter seeds 1-6. For each set the weight is chosen on all the OTHER sets: the most right closures less
# COST times the wrong ones (a wrong closure costs more than a missed one; COST = 10), ties to the lower
# weight (closer to the thesis' filter). Prints the table per weight and the leave-one-set-out table.
#
#   bash docs/results/loso-topology-evidence.sh [BUILD_DIR] [WORK_DIR]
#
# WORK_DIR keeps the rendered worlds (WORK_DIR/worlds) and every run's table (WORK_DIR/tables); a table
# already there is not run again, so an interrupted run goes on where it stopped.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
build="${1:-$root/build}"
work="${2:-$(mktemp -d)}"
weights="${WEIGHTS:-0 0.5 0.8 0.85 0.9 0.95 0.99}"
seeds="${SEEDS:-1 2 3 4 5 6}"
cost="${COST:-10}"
mkdir -p "$work/tables"
for w in $weights; do
  for s in $seeds; do
    t="$work/tables/w$w-s$s.txt"
    [ -s "$t" ] && continue
    echo "loso: weight $w, filter seed $s" >&2
    { "$root/scripts/real-bench.sh" "$build" "$work/real-w$w-s$s" -- --sequence-evidence "$w" --seed "$s"
      "$root/scripts/sim-bench.sh" "$build" "$work" -- --sequence-evidence "$w" --seed "$s"; } > "$t.part"
    mv "$t.part" "$t"
  done
done
python3 - "$work/tables" "$cost" "$weights" "$seeds" <<'PY'
import re, sys
tables, cost = sys.argv[1], float(sys.argv[2])
weights, seeds = sys.argv[3].split(), sys.argv[4].split()
cell = re.compile(r"(\d+) / (\d+) / (\d+) of (\d+)")
res = {}  # (weight, set) -> [right, wrong, missed, revisits] summed over seeds
for w in weights:
    for s in seeds:
        for line in open("%s/w%s-s%s.txt" % (tables, w, s)):
            cols = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cols) < 3 or cols[0].startswith(("real set", "world", "---")): continue
            m = [cell.fullmatch(c) for c in cols]
            m = [x for x in m if x]
            if not m: continue
            acc = res.setdefault((w, cols[0]), [0, 0, 0, 0])
            for i in range(4): acc[i] += int(m[0].group(i + 1))
sets = []
for (w, name) in res:
    if name not in sets: sets.append(name)
def fmt(v): return "%d / %d / %d of %d" % tuple(v)
print("Place revisits closed right / wrong / missed, summed over filter seeds %s:" % ", ".join(seeds))
print()
print("| set | " + " | ".join("weight %s" % w for w in weights) + " |")
print("|---|" + "---|" * len(weights))
for name in sets:
    print("| %s | " % name + " | ".join(fmt(res[(w, name)]) for w in weights) + " |")
def gain(w, names): return sum(res[(w, n)][0] - cost * res[(w, n)][1] for n in names)
print()
print("Leave one set out (choice: most right closures less %g x wrong ones on the other sets; ties to the lower weight):" % cost)
print()
print("| held-out set | weight chosen without it | its revisits with that weight | with the weight chosen on all sets |")
print("|---|---|---|---|")
best_all = max(weights, key=lambda w: (gain(w, sets), -float(w)))
for name in sets:
    others = [n for n in sets if n != name]
    w = max(weights, key=lambda w: (gain(w, others), -float(w)))
    print("| %s | %s | %s | %s |" % (name, w, fmt(res[(w, name)]), fmt(res[(best_all, name)])))
print()
print("Chosen on all sets: weight %s" % best_all)
PY
