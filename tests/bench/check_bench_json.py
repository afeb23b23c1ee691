#!/usr/bin/python3
"""Smoke test of `toposlam-bench pipeline --json` and `toposlam-bench map-size --json`, run tiny: the JSON
has every field with sane values (fps > 0, p99 >= median, max >= p99, peak RSS > 0). No speed threshold:
benchmarks print numbers, they fail no build.

usage: check_bench_json.py TOPOSLAM_BENCH pipeline|map-size"""
import json
import subprocess
import sys


def run(command):
    done = subprocess.run(command, capture_output=True, text=True, timeout=240)
    if done.returncode != 0:
        sys.exit(f"{' '.join(command)}: exit {done.returncode}\n{done.stderr}")
    return json.loads(done.stdout)


def check_stats(where, stats, samples_at_least):
    for key in ("median_ms", "p99_ms", "max_ms", "samples"):
        assert key in stats, f"{where}: no {key}"
    assert stats["samples"] >= samples_at_least, f"{where}: {stats['samples']} samples"
    assert 0 <= stats["median_ms"] <= stats["p99_ms"] <= stats["max_ms"], f"{where}: {stats}"


def check_pipeline(toposlam_bench):
    frames = 40
    out = run([toposlam_bench, "pipeline", "--json", "--sizes", "160x120", "--cores", "1", "2", "--frames",
               str(frames), "--distinct-frames", "20", "--rate", "400"])
    runs = out["runs"]
    modes = {(r["cores"], r["mode"]) for r in runs}
    # Two CPUs only where the machine lets the process use two (the note says so otherwise).
    assert (1, "throughput") in modes and (1, "paced") in modes, modes
    assert len(runs) in (2, 4), len(runs)
    for r in runs:
        where = f"{r['size']} {r['cores']} {r['mode']}"
        assert r["size"] == "160x120", where
        assert r["frames"] == frames or r["mode"] == "paced", f"{where}: {r['frames']} frames"
        assert 0 < r["frames"] <= frames, where
        assert r["fps"] > 0, f"{where}: fps {r['fps']}"
        check_stats(where + " latency", r["latency"], 1)
        check_stats(where + " place latency", r["place_frame_latency"], 0)
        for stage in ("fingerprint", "segmentation", "topology", "publish"):
            check_stats(f"{where} {stage}", r["stages"][stage], 1)
        assert r["peak_rss_mb"] > 0, where
        assert r["frames_mb"] > 0 and r["frames_mb"] < r["peak_rss_mb"], where
        assert "error" not in r, f"{where}: {r.get('error')}"
    print("pipeline JSON OK:", len(runs), "runs")


def check_map_size(toposlam_bench):
    out = run([toposlam_bench, "map-size", "--json", "--places", "120", "--particles", "50", "--checkpoint",
               "60", "--exhaustive-up-to", "40", "--candidates", "20", "--background-samples", "20",
               "--compare-every", "10", "--control"])
    assert out["steps"] == 120
    assert out["indexed_steps"] > 0, out["indexed_steps"]
    assert out["decisions_compared"] == 11, out["decisions_compared"]
    assert 0 <= out["decisions_same"] <= out["decisions_compared"]
    assert 0.0 <= out["same_share"] <= 1.0
    assert 0 <= out["confident_same"] <= out["confident_compared"] <= out["decisions_compared"]
    assert 0 <= out["control_same"] <= out["decisions_compared"]
    assert out["peak_rss_mb"] > 0
    steps = [c["steps"] for c in out["checkpoints"]]
    assert steps == [60, 120], steps
    for c in out["checkpoints"]:
        assert 0 < c["median_ms"] <= c["p99_ms"] <= c["max_ms"], c
        assert c["rss_mb"] > 0 and c["stored"] > 0, c
        assert 0 < c["comparisons_per_step"] <= c["stored"], c
    assert out["checkpoints"][-1]["index_mb"] > 0
    # The map saved and loaded again at the end: every observation came back.
    m = out["map_file"]
    assert m["loaded_observations"] == 120 and m["megabytes"] > 0, m
    assert all(m[k] >= 0 for k in ("snapshot_ms", "encode_ms", "encode_cpu_ms", "write_ms", "load_ms", "load_cpu_ms")), m
    print("map-size JSON OK")


if __name__ == "__main__":
    {"pipeline": check_pipeline, "map-size": check_map_size}[sys.argv[2]](sys.argv[1])
