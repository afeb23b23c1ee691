#!/usr/bin/env python3
"""The growth curve of `toposlam-bench map-size --json` as a Markdown table (docs/performance.md).

    toposlam-bench map-size --places 20000 --checkpoint 2000 --json > map-size.json
    scripts/map-size-table.py map-size.json

One row per checkpoint: steps, stored representatives, ms per new place (median, p99) over the window
before it, resident MB, the candidate index's MB, exact comparisons per step, and decisions equal to
the exhaustive comparison's; then the totals and the map file's save and load. Standard library only.
"""
import json
import sys


def main(path):
    with open(path) as f:
        run = json.load(f)
    print("| places | stored | median ms | p99 ms | RSS MB | index MB | comparisons per step | same decision |")
    print("|---|---|---|---|---|---|---|---|")
    for c in run["checkpoints"]:
        same = f'{c["same"]} / {c["compared"]}' if c["compared"] else ""
        print(f'| {c["steps"]:,} | {c["stored"]:,} | {c["median_ms"]:.2f} | {c["p99_ms"]:.2f} | '
              f'{c["rss_mb"]:.1f} | {c["index_mb"]:.1f} | {c["comparisons_per_step"]:.0f} | {same} |')
    compared = run["decisions_compared"]
    print()
    print(f'Decisions equal to the exhaustive comparison\'s: {run["decisions_same"]} of {compared} '
          f'({100.0 * run["same_share"]:.1f} %); where it has p >= 0.5: {run["confident_same"]} of '
          f'{run["confident_compared"]}. Peak RSS {run["peak_rss_mb"]:.1f} MB.')
    m = run.get("map_file")
    if m:
        print(f'Map file of {m["loaded_observations"]:,} places: {m["megabytes"]:.1f} MB; snapshot '
              f'{m["snapshot_ms"]:.1f} ms (the frame path), encode {m["encode_ms"]:.0f} ms (CPU '
              f'{m["encode_cpu_ms"]:.0f}) and write {m["write_ms"]:.0f} ms (map writer thread); load '
              f'{m["load_ms"]:.0f} ms (CPU {m["load_cpu_ms"]:.0f}).')


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: map-size-table.py MAP_SIZE_JSON")
    main(sys.argv[1])
