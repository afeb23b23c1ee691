#!/bin/sh
# --json of toposlam-bench's sim, topology, similarity, fingerprint and segmentation, run small: each
# parses as {"benchmark": NAME, "rows": [...]} with the run's numbers (issue 16; the benchmarks were
# `toposlam bench` until issue 15). No speed threshold: benchmarks print numbers, they fail no build.
# Usage: check_bench_rows.sh TOPOSLAM_BENCH DIR
set -u
bench="$1" dir="$2"
rm -rf "$dir" && mkdir -p "$dir"
fail() { echo "FAIL: $*"; exit 1; }
# run NAME ARGS...: toposlam-bench NAME ARGS... --json into DIR/bench-NAME.json (the table to /dev/null).
run() {
  name="$1"
  "$bench" "$@" --json >"$dir/bench-$name.json" 2>/dev/null || fail "bench $name: exit $?"
}

run sim --worlds home --widths 64 --route loop
run topology --places 10 20 --steps 4 --no-real
run similarity --frames 4 --repeat 1 --preset default
run fingerprint --repeat 1 --keypoints orb --workers 1
run segmentation --repeat 1
python3 - "$dir" <<'PY' || fail "a benchmark's JSON (above)"
import json, sys
d = sys.argv[1]
def rows(name):
    o = json.load(open(d + "/bench-" + name + ".json"))
    assert o["benchmark"] == name, (name, o)
    return o["rows"]
r = rows("sim")
assert len(r) == 1 and r[0]["frames"] > 100 and r[0]["fps"] > 0 and r[0]["width"] == 64, r
r = rows("topology")
assert [x["places"] for x in r] == [10, 20] and all(x["median_ms"] > 0 for x in r), r
sim = rows("similarity")
assert len(sim) == 1 and sim[0]["pairs"] == 16 and sim[0]["median_similarities_per_s"] > 0, sim
fp = rows("fingerprint")
assert [(r["width"], r["height"]) for r in fp] == [(320, 240), (640, 480)], fp
assert all(r["median_ms"] > 0 and r["keypoints"] > 10 for r in fp), fp
seg = rows("segmentation")
assert [r["similarity"] for r in seg] == ["n-gram", "precomputed table"], seg
assert all(r["median_ms"] > 0 for r in seg), seg
PY
echo "bench rows JSON OK: the five benches parse with their numbers"
