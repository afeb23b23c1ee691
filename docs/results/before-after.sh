#!/bin/bash
# Before/after figures of the real-image work (issues 13-14), each beside the plain ORB baseline of the
# same run: recognition on the samples and the corridor, localisation, `map` + `eval` on the samples, the
# corridor as one sequence and the simulated office (two laps).
# Usage: docs/results/before-after.sh NEW_TOPOSLAM OLD_TOPOSLAM OFFICE_DIR WORK_DIR
#   OLD_TOPOSLAM: a build of the commit to compare with (e.g. git worktree add /tmp/before 3966ef0)
#   OFFICE_DIR:   `toposlam sim office --route loop2 --out OFFICE_DIR`
set -u
repo="$(cd "$(dirname "$0")/../.." && pwd)"
NEW=$1 OLD=$2 O=$3 work=$4
S=$repo/tests/data/rtabmap-samples; C=$repo/tests/data/vprbench-corridor
mkdir -p "$work" && cd "$work"
echo "== recognition: samples (min-gap 10), corridor (query vs reference)"
for p in default thesis; do $NEW recognition images:$S/samples --truth $S/samples_GT_pairs.csv --preset $p --quiet | grep -E "toposlam \(|ORB baseline"; done
for p in default thesis; do $NEW recognition --reference images:$C/ref --query images:$C/query --truth $C/gt.csv --preset $p --quiet | grep -E "toposlam \(|ORB baseline"; done
echo "== localisation as recognition (query -> most similar place image; right place = top-1)"
python3 - $S > loc_pairs.csv <<'PY'
import csv,sys,os
S=sys.argv[1]
places=[r for r in csv.reader(open(S+'/places.csv')) if r and not r[0].startswith('#') and r[0]!='image']
queries=[r for r in csv.reader(open(S+'/queries.csv')) if r and not r[0].startswith('#') and r[0]!='image']
print("query,matches")
for q in queries:
    m=[os.path.basename(p[0]) for p in places if p[1]==q[1]]
    print("%s,%s"%(os.path.basename(q[0])," ".join(m)))
PY
mkdir -p locp locq
python3 - $S <<'PY'
import csv,sys,os
S=sys.argv[1]
for f,d in (('places.csv','locp'),('queries.csv','locq')):
    for r in csv.reader(open(S+'/'+f)):
        if not r or r[0].startswith('#') or r[0]=='image': continue
        src=os.path.join(S,r[0]) if not os.path.isabs(r[0]) else r[0]
        dst=os.path.join(d,os.path.basename(r[0]))
        if not os.path.exists(dst): os.symlink(src,dst)
PY
$NEW recognition --reference images:$work/locp --query images:$work/locq --truth loc_pairs.csv --quiet | grep -E "toposlam \(|ORB baseline"
echo "-- localize before (session-start binary) / after default / after thesis preset"
$OLD localize --places $S/places.csv --queries $S/queries.csv 2>/dev/null | grep -E "^all|0.50 "
$NEW localize --places $S/places.csv --queries $S/queries.csv 2>/dev/null | grep -E "^all|0.50 "
$NEW localize --places $S/places.csv --queries $S/queries.csv --preset thesis 2>/dev/null | grep -E "^all|0.50 "
echo "-- along the route (--route): samples, then the corridor's localisation set (single images / route)"
$NEW localize --places $S/places.csv --queries $S/queries.csv --route 2>/dev/null | grep -E "^all|0.50 "
$NEW localize --places $C/places.csv --queries $C/queries.csv 2>/dev/null | grep -E "^all|0.50 "
$NEW localize --places $C/places.csv --queries $C/queries.csv --route --no-loop 2>/dev/null | grep -E "^all|0.50 "
echo "== recognition: corridor, sequences of 10 with 200 keypoints (beside the baseline with the same budget)"
$NEW recognition --reference images:$C/ref --query images:$C/query --truth $C/gt.csv --sequence 10 --max-keypoints 200 --quiet | grep -E "seq 10"
echo "== map samples"
$OLD map images:$S/samples --out before-s 2>&1 | tail -1
$NEW map images:$S/samples --out after-s 2>&1 | tail -1
$NEW map images:$S/samples --preset thesis --out thesis-s 2>&1 | tail -1
$NEW eval after-s --truth $S/samples_GT_pairs.csv --json > after-s.json 2>/dev/null
$NEW eval before-s --truth $S/samples_GT_pairs.csv --json > before-s.json 2>/dev/null
echo "-- map samples with a 5 s window (a second lap cut where the first was not)"
$OLD map images:$S/samples --window-s 5 --out before-s5 >/dev/null 2>&1
$NEW map images:$S/samples --window-s 5 --out after-s5 >/dev/null 2>&1
$NEW eval before-s5 --truth $S/samples_GT_pairs.csv --json > before-s5.json 2>/dev/null
$NEW eval after-s5 --truth $S/samples_GT_pairs.csv --json > after-s5.json 2>/dev/null
echo "-- frame-level baseline: each frame's best earlier frame at least 25 back (= eval's min gap)"
$NEW recognition images:$S/samples --truth $S/samples_GT_pairs.csv --min-gap 25 --quiet | grep -E "toposlam \(|ORB baseline"
echo "== map corridor as one sequence"
$OLD map images:$C/ref images:$C/query --out before-c 2>&1 | tail -1
$NEW map images:$C/ref images:$C/query --out after-c 2>&1 | tail -1
$NEW eval after-c --truth $C/gt.csv --json > after-c.json 2>/dev/null
$OLD eval before-c --truth $C/gt.csv --json > before-c.json 2>/dev/null
echo "-- with the filter's sequence evidence on (--sequence-evidence 0.99; off by default, docs/topology.md)"
$NEW map images:$S/samples --sequence-evidence 0.99 --out evid-s 2>&1 | tail -1
$NEW eval evid-s --truth $S/samples_GT_pairs.csv --json > evid-s.json 2>/dev/null
$NEW map images:$C/ref images:$C/query --sequence-evidence 0.99 --out evid-c 2>&1 | tail -1
$NEW eval evid-c --truth $C/gt.csv --json > evid-c.json 2>/dev/null
echo "== office two laps"
$OLD map images:$O/frames --out before-o 2>&1 | tail -1
$NEW map images:$O/frames --out after-o 2>&1 | tail -1
$NEW eval before-o --truth $O/labels.csv --json > before-o.json 2>/dev/null
$NEW eval after-o --truth $O/labels.csv --json > after-o.json 2>/dev/null
$NEW map images:$O/frames --sequence-evidence 0.99 --out evid-o 2>&1 | tail -1
$NEW eval evid-o --truth $O/labels.csv --json > evid-o.json 2>/dev/null
python3 - <<'PY'
import json
for n in ('before-s','after-s','evid-s','before-s5','after-s5','before-c','after-c','evid-c','before-o','after-o','evid-o'):
    try: d=json.load(open('%s.json'%n))
    except Exception as e: print(n,'no eval',e); continue
    out=[n]
    if 'frame_loop_closure' in d:
        f=d['frame_loop_closure']; out.append('frame R@100P %.3f right %d/%d det %d'%(f['recall_at_100_precision'],f['right_detections'],f['frames_with_match'],f['detections']))
    if 'loop_closure' in d: out.append('pair R@100P %.3f'%d['loop_closure']['recall_at_100_precision'])
    if 'topology' in d:
        t=d['topology']; out.append('nodes %d merged %d closures %d wrong %d missed %d'%(t['nodes'],t['merged_nodes'],t['loop_closures'],t['wrong_loop_closures'],t['missed_loop_closures']))
    if 'localisation' in d and d['localisation']:
        r=d['localisation'][0]; out.append('loc@0.5 %d imgs %.1f%%'%(r['images'],100*r['precision']))
    if 'segmentation' in d: out.append('F1 %.2f'%d['segmentation']['f1'])
    if d.get('best_topology_probability'): out.append('p_last %.2f'%d['best_topology_probability'][-1])
    r=d.get('place_revisits')
    if r: out.append('by pose %s'%{k: v for k, v in r.items() if k in ('revisits','closed_right','wrong_closures','missed')})
    print(' | '.join(out))
PY
