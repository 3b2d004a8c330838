#!/usr/bin/env python3
"""Helpers of bench/primary_vs_slsqp.sh.

  bench_util.py time RUNS CMD...      run CMD RUNS times (whole process, wall clock);
                                      prints JSON: median/min seconds, peak RSS (kB)
  bench_util.py frame FRAME.json      prints JSON: gap sum and max from the file's solve
                                      summary, the sum of the links' primary_gap, and the
                                      same objective re-measured with the baseline's own
                                      segment distance and side matching
"""
import json
import os
import resource
import statistics
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.environ.get("SLSQP_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "shared", "bench")))


def cmd_time(runs, cmd):
    times, rss = [], 0
    gnu_time = "/usr/bin/time" if os.access("/usr/bin/time", os.X_OK) else None
    rss_file = os.path.join(os.environ.get("TMPDIR", "/tmp"), f"bench_rss_{os.getpid()}")
    for _ in range(runs):
        # peak RSS from GNU time (%M, kB): getrusage would count the forked Python too
        full = [gnu_time, "-f", "%M", "-o", rss_file] + cmd if gnu_time else cmd
        t0 = time.perf_counter()
        p = subprocess.run(full, stdout=subprocess.PIPE)
        times.append(time.perf_counter() - t0)
        if p.returncode != 0:
            sys.stderr.write(p.stdout.decode(errors="replace"))
            sys.exit(f"command failed ({p.returncode}): {' '.join(cmd)}")
        if gnu_time:
            with open(rss_file) as f:
                rss = max(rss, int(f.read().split()[-1]))
    if gnu_time:
        os.remove(rss_file)
    else:
        rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss  # kB, upper bound
    print(json.dumps({"runs": runs, "median_s": statistics.median(times), "min_s": min(times),
                      "max_rss_kb": rss, "stdout": p.stdout.decode(errors="replace").strip()}))


def cmd_frame(path):
    from slsqp_baseline import seg_dist  # the baseline's own distance
    fr = json.load(open(path))
    e = float(fr["params"]["expansion"])
    V = np.array(fr["mesh"]["vertices"], float)
    prim = [np.array(u["primary"], float) for u in fr["units"]]

    def facing(P, m):
        c = P.mean(0)
        Pe = c + e * (P - c)
        k = min(range(4), key=lambda k: np.linalg.norm((Pe[k] + Pe[(k + 1) % 4]) / 2 - m))
        return Pe[k], Pe[(k + 1) % 4]

    again = 0.0
    for L in fr["links"]:
        i, j = L["units"]
        m = (V[L["edge"][0]] + V[L["edge"][1]]) / 2
        p0, p1 = facing(prim[i], m)
        q0, q1 = facing(prim[j], m)
        again += seg_dist(p0, p1, q0, q1)
    s = fr.get("solve") or {}
    print(json.dumps({"units": len(fr["units"]), "links": len(fr["links"]),
                      "gap_sum": s.get("gap_sum"), "gap_max": s.get("gap_max"),
                      "iterations": s.get("iterations"),
                      "links_gap_sum": sum(L["primary_gap"] for L in fr["links"]),
                      "remeasured_gap_sum": again}))


if __name__ == "__main__":
    if len(sys.argv) >= 4 and sys.argv[1] == "time":
        cmd_time(int(sys.argv[2]), sys.argv[3:])
    elif len(sys.argv) == 3 and sys.argv[1] == "frame":
        cmd_frame(sys.argv[2])
    else:
        sys.exit(__doc__)
