#!/usr/bin/env bash
# Primary-surface solve: `spinvalence solve` against the paper's SciPy SLSQP method
# (../shared/bench/slsqp_baseline.py), whole process against whole process, on the same
# frames; then the 10,000-unit case (time and peak memory). Run by `make bench-primary`.
#
# Writes target/bench/primary.md (markdown table) and target/bench/primary.jsonl (raw).
#
# Environment:
#   UNITS=8 (or BENCH_N) baseline frames are BENCH_N x BENCH_N units (SLSQP with finite
#                      differences costs ~n^2 per iteration: 8 x 8 takes about 2 minutes)
#   BENCH_FULL=1       also run SLSQP on the 12 x 12 fixtures (about 15 minutes each)
#   BENCH_RUNS=5       runs of `spinvalence solve` per case (the median is reported)
#   SLSQP_BASELINE=... path of slsqp_baseline.py
#   PYTHON=...         interpreter with numpy + scipy (default: a venv in target/bench-venv)
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

N="${UNITS:-${BENCH_N:-8}}"
RUNS="${BENCH_RUNS:-5}"
MAXITER=60
BASELINE="${SLSQP_BASELINE:-$ROOT/../shared/bench/slsqp_baseline.py}"
OUT="$ROOT/target/bench"
WORK="$OUT/primary"
VENV="$ROOT/target/bench-venv"
BIN="$ROOT/target/release/spinvalence"

[ -f "$BASELINE" ] || { echo "error: baseline not found: $BASELINE" >&2; exit 2; }
export SLSQP_DIR="$(cd "$(dirname "$BASELINE")" && pwd)"

# --- Python with numpy and scipy --------------------------------------------------------
if [ -z "${PYTHON:-}" ]; then
    if [ ! -x "$VENV/bin/python" ] || ! "$VENV/bin/python" -c 'import numpy, scipy' 2>/dev/null; then
        echo "== creating $VENV (numpy, scipy)"
        python3 -m venv "$VENV"
        "$VENV/bin/pip" install --quiet --upgrade pip
        "$VENV/bin/pip" install --quiet numpy scipy
    fi
    PYTHON="$VENV/bin/python"
fi
UTIL=("$PYTHON" "$ROOT/bench/bench_util.py")

# --- build --------------------------------------------------------------------------------
echo "== cargo build --release"
cargo build --release --quiet
"$BIN" solve --help >/dev/null

# --- meshes -------------------------------------------------------------------------------
mkdir -p "$WORK"
rm -f "$OUT/primary.jsonl"
MESHES="$WORK/meshes"
mkdir -p "$MESHES"
# the surfaces of fixtures/sphere_cap.obj and fixtures/saddle.obj, N x N units
"$PYTHON" bench/make_meshes.py cap "$N" "$N" 3000 300 "$MESHES/cap_${N}.obj"
"$PYTHON" bench/make_meshes.py saddle "$N" "$N" 300 4000 "$MESHES/saddle_${N}.obj"
for f in sphere_cap saddle; do
    if [ -f "fixtures/$f.obj" ]; then
        cp "fixtures/$f.obj" "$MESHES/${f}_12.obj"
    elif [ "$f" = sphere_cap ]; then
        "$PYTHON" bench/make_meshes.py cap 12 12 3000 300 "$MESHES/${f}_12.obj"
    else
        "$PYTHON" bench/make_meshes.py saddle 12 12 300 4000 "$MESHES/${f}_12.obj"
    fi
done
"$PYTHON" bench/make_meshes.py cap 100 100 30000 300 "$MESHES/cap_100.obj"

json() { "$PYTHON" -c "import json,sys; d=json.loads(sys.argv[1]); print(d$2)" "$1"; }

# --- one comparison -----------------------------------------------------------------------
# compare NAME MESH WITH_SLSQP
compare() {
    local name="$1" mesh="$2" with_slsqp="$3" dir="$WORK/$1"
    echo "== $name: spinvalence solve ($RUNS runs)"
    local ours frame slsqp="" row
    ours="$("${UTIL[@]}" time "$RUNS" "$BIN" solve --mesh "$mesh" --objective sum --out "$dir" --quiet)"
    frame="$("${UTIL[@]}" frame "$dir/frame.json")"
    if [ "$with_slsqp" = 1 ]; then
        echo "== $name: slsqp_baseline.py --maxiter $MAXITER (one run, this takes a while)"
        slsqp="$("${UTIL[@]}" time 1 "$PYTHON" "$BASELINE" "$dir/frame.json" --maxiter "$MAXITER")"
    fi
    row="$("$PYTHON" - "$name" "$ours" "$frame" "$slsqp" <<'PY'
import json, sys
name, ours, frame, slsqp = sys.argv[1], json.loads(sys.argv[2]), json.loads(sys.argv[3]), sys.argv[4]
rec = {"case": name, "ours": ours, "frame": frame}
if slsqp:
    s = json.loads(slsqp)
    s["result"] = json.loads(s.pop("stdout").splitlines()[-1])
    rec["slsqp"] = s
print(json.dumps(rec))
PY
)"
    echo "$row" >> "$OUT/primary.jsonl"
    "$PYTHON" - "$row" <<'PY'
import json, sys
r = json.loads(sys.argv[1]); o, f = r["ours"], r["frame"]
msg = "   ours: %.3f s, gap sum %.2f mm" % (o["median_s"], f["gap_sum"])
if "slsqp" in r:
    s = r["slsqp"]; res = s["result"]
    msg += " | SLSQP: %.1f s, gap sum %.2f mm | %.0fx" % (
        s["median_s"], res["objective_end_mm"], s["median_s"] / o["median_s"])
print(msg)
PY
}

compare "sphere cap ${N}x${N}" "$MESHES/cap_${N}.obj" 1
compare "saddle ${N}x${N}" "$MESHES/saddle_${N}.obj" 1
full=0
[ "${BENCH_FULL:-0}" = 1 ] && full=1
compare "sphere cap 12x12 (fixture)" "$MESHES/sphere_cap_12.obj" "$full"
compare "saddle 12x12 (fixture)" "$MESHES/saddle_12.obj" "$full"

# --- 10,000 units: GNU time -v for the peak memory ----------------------------------------
big() {
    local name="$1" mesh="$2" dir="$WORK/$1"
    echo "== $name: /usr/bin/time -v spinvalence solve"
    local log="$WORK/$(echo "$name" | tr -c 'a-zA-Z0-9\n' _).time"
    /usr/bin/time -v "$BIN" solve --mesh "$mesh" --objective sum --out "$dir" --quiet 2> "$log"
    local wall rss
    wall="$(grep 'Elapsed (wall clock)' "$log" | awk '{print $NF}')"
    rss="$(grep 'Maximum resident set size' "$log" | awk '{print $NF}')"
    local frame
    frame="$("${UTIL[@]}" frame "$dir/frame.json")"
    "$PYTHON" - "$name" "$wall" "$rss" "$frame" >> "$OUT/primary.jsonl" <<'PY'
import json, sys
name, wall, rss, frame = sys.argv[1], sys.argv[2], int(sys.argv[3]), json.loads(sys.argv[4])
parts = [float(p) for p in wall.split(":")]
secs = sum(p * 60 ** i for i, p in enumerate(reversed(parts)))
print(json.dumps({"case": name, "big": {"wall_s": secs, "max_rss_kb": rss}, "frame": frame}))
PY
    echo "   $wall wall, $rss kB peak RSS"
}
big "sphere cap 100x100 (R 30 m)" "$MESHES/cap_100.obj"
if [ -f fixtures/grid_100x100.obj ]; then
    big "flat grid 100x100 (fixture)" fixtures/grid_100x100.obj
fi

# --- report -------------------------------------------------------------------------------
"$PYTHON" - "$OUT/primary.jsonl" "$MAXITER" "$N" > "$OUT/primary.md" <<'PY'
import json, os, platform, subprocess, sys, datetime
rows = [json.loads(l) for l in open(sys.argv[1])]
maxiter, n = sys.argv[2], sys.argv[3]
cpu = "?"
try:
    for line in open("/proc/cpuinfo"):
        if line.startswith("model name"):
            cpu = line.split(":", 1)[1].strip(); break
except OSError:
    pass
print(f"# Primary solve vs SLSQP baseline ({datetime.date.today()})\n")
print(f"Machine: {cpu}, {os.cpu_count()} logical cores, {platform.system()} {platform.release()}.")
print(f"Times are whole processes (wall clock): `spinvalence solve --objective sum --quiet` (the paper's objective) as the median of "
      f"several runs, `slsqp_baseline.py FRAME --maxiter {maxiter}` once, each on the frame "
      f"`spinvalence` wrote (the baseline restarts from theta = alpha, phi = 0 and keeps our sides).\n")
print("| case | units | links | ours: time (s) | ours: gap sum (mm) | ours: max gap (mm) "
      "| SLSQP: time (s) | SLSQP: gap sum start -> end (mm) | SLSQP iterations / evaluations | time ratio | ours <= SLSQP |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|:-:|")
for r in rows:
    if "ours" not in r:
        continue
    o, f = r["ours"], r["frame"]
    cells = [r["case"], f["units"], f["links"], f"{o['median_s']:.3f}", f"{f['gap_sum']:.2f}",
             f"{f['gap_max']:.2f}"]
    if "slsqp" in r:
        s = r["slsqp"]; res = s["result"]
        cells += [f"{s['median_s']:.1f}",
                  f"{res['objective_start_mm']:.1f} -> {res['objective_end_mm']:.2f}",
                  f"{res['iterations']} / {res['evaluations']}",
                  f"{s['median_s'] / o['median_s']:.0f}x",
                  "yes" if f["gap_sum"] <= res["objective_end_mm"] else "**no**"]
    else:
        cells += ["-", "-", "-", "-", "-"]
    print("| " + " | ".join(str(c) for c in cells) + " |")
print("\nOur gap sums re-measured with the baseline's own side matching and segment distance:")
for r in rows:
    f = r["frame"]
    print(f"- {r['case']}: {f['remeasured_gap_sum']:.4f} mm (file: {f['gap_sum']:.4f} mm)")
print("\n| large case | units | wall time (s) | peak RSS (MB) | gap sum (mm) | max gap (mm) |")
print("|---|---:|---:|---:|---:|---:|")
for r in rows:
    if "big" in r:
        b, f = r["big"], r["frame"]
        print(f"| {r['case']} | {f['units']} | {b['wall_s']:.2f} | {b['max_rss_kb'] / 1024:.0f} "
              f"| {f['gap_sum']:.1f} | {f['gap_max']:.3g} |")
PY
echo "== wrote $OUT/primary.md"
cat "$OUT/primary.md"
