"""Machine-readable results of the peer benchmarks, for bench-peers/run_all.sh.

When NURBSPRING_BENCH_RESULTS names a file, every timed job is appended to it as one JSON line:
{"source": ..., "bench": ..., "times_s": [...], "min_s": ..., "median_s": ..., "info": {...}}.
bench-peers/tables.py reads that file (and criterion's estimates) to regenerate the tables of
docs/benchmarks.md. Without the variable nothing is written and the scripts only print.
"""
import json
import os
import statistics


def record(source, bench, times_s, **info):
    """Appends one timed job (its individual times in seconds) to the results file, if any."""
    path = os.environ.get("NURBSPRING_BENCH_RESULTS")
    if not path:
        return
    times = [float(t) for t in times_s]
    line = {
        "source": source,
        "bench": bench,
        "times_s": times,
        "min_s": min(times),
        "median_s": statistics.median(times),
        "load": os.getloadavg()[0],
        "info": info,
    }
    with open(path, "a", encoding="utf-8") as f:
        f.write(json.dumps(line) + "\n")
