#!/bin/sh
# Two laps of a simulated world as two image folders, for mapping one and localising the other
# (docs/daemon.md, "Localisation only"): `toposlam sim WORLD --route loop2`, split at the second lap into
# OUT/lap1 and OUT/lap2, each with frames/ (renumbered from 000000.png, timestamps.csv kept) and labels.csv
# (frame,time,room,x,y,heading,traversal of that lap). Does nothing when OUT/lap2/labels.csv exists.
# Usage: scripts/sim-laps.sh TOPOSLAM WORLD OUT
set -eu
toposlam=$1 world=$2 out=$3
[ -f "$out/lap2/labels.csv" ] && exit 0
"$toposlam" sim "$world" --route loop2 --out "$out/both" >/dev/null 2>&1
python3 - "$out" <<'PY'
import csv, os, shutil, sys
d = sys.argv[1]
labels = list(csv.DictReader(open(d + "/both/labels.csv")))
times = {r["name"]: r["time_s"] for r in csv.DictReader(open(d + "/both/frames/timestamps.csv"))}
for lap in ("0", "1"):
    out = "%s/lap%d" % (d, int(lap) + 1)
    os.makedirs(out + "/frames", exist_ok=True)
    rows = [r for r in labels if r["traversal"] == lap]
    with open(out + "/labels.csv", "w") as lf, open(out + "/frames/timestamps.csv", "w") as tf:
        lf.write("frame,time,room,x,y,heading,traversal\n")
        tf.write("name,time_s\n")
        for i, r in enumerate(rows):
            name = "%06d.png" % int(r["frame"])
            shutil.copy("%s/both/frames/%s" % (d, name), "%s/frames/%06d.png" % (out, i))
            lf.write("%d,%s,%s,%s,%s,%s,0\n" % (i, r["time"], r["room"], r["x"], r["y"], r["heading"]))
            tf.write("%06d.png,%s\n" % (i, times[name]))
PY
