#!/usr/bin/env bash
# Primary-surface solve against the paper's method (SciPy SLSQP, finite differences),
# whole process against whole process, on the same hub mesh and starting point.
#
#   make bench-primary            # writes target/bench/primary.md
#   UNITS=12 make bench-primary   # a 12 x 12 sphere cap (SLSQP then takes ~15 min)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
root=$PWD
out=target/bench
mkdir -p "$out"
n=${UNITS:-8}
venv=target/bench-venv
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet numpy scipy
fi
cargo build --release --quiet -p spinvalence
bin=$root/target/release/spinvalence
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# an n x n sphere cap (R = 3000 mm, 300 mm units) meshed by its curvature lines
"$venv/bin/python" - "$n" "$work/cap.obj" <<'PY'
import math, sys
n, path = int(sys.argv[1]), sys.argv[2]
R, s = 3000.0, 300.0
step = s / R; u0 = v0 = n * step / 2
with open(path, "w") as f:
    for j in range(n + 1):
        for i in range(n + 1):
            lon, lat = i * step - u0, j * step - v0
            p = (math.cos(lat) * math.sin(lon), math.sin(lat), math.cos(lat) * math.cos(lon))
            f.write("v %r %r %r\n" % (p[0] * R, p[1] * R, p[2] * R - R))
    idx = lambda i, j: j * (n + 1) + i + 1
    for j in range(n):
        for i in range(n):
            f.write("f %d %d %d %d\n" % (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)))
PY

# ours: median of 11 whole-process runs
ours_s=$("$venv/bin/python" - "$bin" "$work" <<'PY'
import subprocess, sys, time
bin, work = sys.argv[1], sys.argv[2]
ts = []
for _ in range(11):
    t = time.perf_counter()
    subprocess.run([bin, "solve", "--mesh", f"{work}/cap.obj", "--out", f"{work}/ours", "--quiet"], check=True)
    ts.append(time.perf_counter() - t)
print(sorted(ts)[5])
PY
)
ours_gap=$("$venv/bin/python" -c "import json,sys; f=json.load(open(sys.argv[1])); print(sum(l['primary_gap'] for l in f['links']))" "$work/ours/frame.json")
start_gap=$("$venv/bin/python" -c "import json,sys; print(json.load(open(sys.argv[1]))['solve']['gap_sum_start'])" "$work/ours/frame.json")

# the baseline, one whole process, restarting from (theta, phi) = (alpha, 0) on our hubs
read -r slsqp_s slsqp_gap < <("$venv/bin/python" - "$venv/bin/python" "$work/ours/frame.json" <<'PY'
import json, subprocess, sys, time
t = time.perf_counter()
out = subprocess.run([sys.argv[1], "../shared/bench/slsqp_baseline.py", sys.argv[2], "--maxiter", "60"],
                     check=True, capture_output=True, text=True).stdout
print(time.perf_counter() - t, json.loads(out)["objective_end_mm"])
PY
)

# 10,000 units: wall time and peak memory of one whole process
"$venv/bin/python" - "$work/cap100.obj" <<'PY'
import math, sys
n, R, s = 100, 30000.0, 300.0
step = s / R; u0 = v0 = n * step / 2
with open(sys.argv[1], "w") as f:
    for j in range(n + 1):
        for i in range(n + 1):
            lon, lat = i * step - u0, j * step - v0
            p = (math.cos(lat) * math.sin(lon), math.sin(lat), math.cos(lat) * math.cos(lon))
            f.write("v %r %r %r\n" % (p[0] * R, p[1] * R, p[2] * R - R))
    idx = lambda i, j: j * (n + 1) + i + 1
    for j in range(n):
        for i in range(n):
            f.write("f %d %d %d %d\n" % (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)))
PY
big=$( { /usr/bin/time -f "%e %M" "$bin" solve --mesh "$work/cap100.obj" --out "$work/big" --quiet; } 2>&1 | tail -1)

{
  echo "| case | units | ours: s (whole process) | ours: gap sum mm | SLSQP maxiter 60: s | SLSQP: gap sum mm | start gap sum mm | speed-up |"
  echo "|---|---|---|---|---|---|---|---|"
  ratio=$("$venv/bin/python" -c "import sys; print(float(sys.argv[1]) / float(sys.argv[2]))" "$slsqp_s" "$ours_s")
  printf "| sphere cap R 3000 | %d | %.4f | %.1f | %.1f | %.1f | %.1f | %.0fx |\n" \
    $((n * n)) "$ours_s" "$ours_gap" "$slsqp_s" "$slsqp_gap" "$start_gap" "$ratio"
  set -- $big
  printf "\n10,000 units (100 x 100 sphere cap, R 30 m): %s s, peak RSS %d MB\n" "$1" "$(($2 / 1024))"
} | tee "$out/primary.md"
