#!/usr/bin/env bash
# Strip-packing benchmark on the 13 ESICUP instances, ours against sparrow side by side at
# equal time and threads (for each instance and seed our run, then sparrow's, so both see
# the same machine load), one column pair per time; writes the table into docs/nesting.md.
#
# usage: SPARROW=/path/to/sparrow bench/nest_spp.sh [SEEDS=0] [SECONDS...=15 60]
#   SEEDS: one seed or several separated by commas (0,1,2); a cell is the mean over them
#
# SPARROW is a sparrow binary built from its source with 2 separator workers (n_workers in
# its src/config.rs), so both sides use 2 threads, and with its `only_final_svg` feature, so
# that it spends no time drawing intermediate solutions. Without it the sparrow column is its
# published 1200 s average (best_known_spp.csv) and the ratio is against that. Sparrow reads
# the instances in its own format (the same shapes): SPARROW_INPUT, by default its source's
# data/input beside target/release.
# Raw results: target/bench/spp_SECONDS.csv (instance, seed, ours %, sparrow %, load average).
set -euo pipefail
cd "$(dirname "$0")/.."
SEEDS="${1:-0}"; shift || true
IFS=, read -r -a SEED_LIST <<< "$SEEDS"
TIMES=("${@:-15 60}")
read -r -a TIMES <<< "${TIMES[*]}"
DATA=../shared/datasets/nesting
[ -d "$DATA" ] || DATA=/work/shared/datasets/nesting
DATA=$(cd "$DATA" && pwd)
INSTANCES="albano blaz1 dagli fu jakobs1 jakobs2 mao marques shapes0 shapes1 shirts swim trousers"
cargo build --release -p sv-nest --example spp >/dev/null
OURS=${CARGO_TARGET_DIR:-$PWD/target}/release/examples/spp
mkdir -p target/bench
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
for secs in "${TIMES[@]}"; do
  csv=target/bench/spp_$secs.csv
  : > "$csv"
  for inst in $INSTANCES; do
    for seed in "${SEED_LIST[@]}"; do
      ours=$("$OURS" "$DATA/spp/$inst.json" --seconds "$secs" --seed "$seed" 2>/dev/null | awk '{print $5}')
      if [ -n "${SPARROW:-}" ]; then
        input=${SPARROW_INPUT:-$(dirname "$SPARROW")/../../data/input}
        (cd "$WORK" && "$SPARROW" -i "$input/$inst.json" -t "$secs" -s "$seed" >/dev/null 2>&1)
        sp=$(python3 -c "import json,sys; print(round(100 * json.load(open(sys.argv[1]))['solution']['density'], 2))" "$WORK/output/final_$inst.json")
      else
        sp=$(grep "^$inst," "$DATA/best_known_spp.csv" | cut -d, -f9)
      fi
      load=$(cut -d' ' -f1 /proc/loadavg)
      echo "$inst,$seed,$ours,$sp,$load" | tee -a "$csv"
    done
  done
done
TABLE=$WORK/table.md
python3 - "$TABLE" "${SPARROW:+side by side}" "${TIMES[@]}" <<'EOF'
import csv, statistics, sys
out, mode, times = sys.argv[1], sys.argv[2], sys.argv[3:]
rows, medians, loads, seeds = {}, {}, [], set()
for t in times:
    cells = {}
    for inst, seed, ours, sp, load in csv.reader(open(f"target/bench/spp_{t}.csv")):
        cells.setdefault(inst, []).append((float(ours), float(sp)))
        loads.append(float(load))
        seeds.add(seed)
    ratios = []
    for inst, runs in cells.items():
        o = statistics.mean(r[0] for r in runs)
        s = statistics.mean(r[1] for r in runs)
        ratios.append(o / s)
        rows.setdefault(inst, []).append((o, s, o / s))
    medians[t] = (statistics.median(ratios), sum(r >= 1.0 for r in ratios), len(ratios))
what = "sparrow" if mode else "sparrow 1200 s avg (published)"
head = "| instance | " + " | ".join(f"ours {t} s % | {what} {t} s % | ratio {t} s" for t in times) + " |"
with open(out, "w") as f:
    if len(seeds) > 1:
        print(f"Each cell is the mean of {len(seeds)} seeds; the ratio is of the means.\n", file=f)
    print(head, file=f)
    print("|---" * (1 + 3 * len(times)) + "|", file=f)
    for inst, cells in rows.items():
        print(f"| {inst} | " + " | ".join(f"{o:.2f} | {s:.2f} | {r:.3f}" for o, s, r in cells) + " |", file=f)
    print("| **median ratio** | " + " | ".join(
        f" | | **{m:.3f}** ({k} of {n} >= 1)" for m, k, n in medians.values()) + " |", file=f)
    print(f"\nLoad average during the runs: {min(loads):.1f}-{max(loads):.1f}.", file=f)
EOF
cat "$TABLE"
DOC=docs/nesting.md
BEGIN='<!-- bench:begin -->'; END='<!-- bench:end -->'
awk -v b="$BEGIN" -v e="$END" -v f="$TABLE" -v cmd="bench/nest_spp.sh $SEEDS ${TIMES[*]}" '
  $0==b {print; print ""; print "Run: `SPARROW=... " cmd "` (seeds as given; ours: one search on 2 workers; sparrow: 2 workers)."; print ""; while ((getline l < f) > 0) print l; print ""; skip=1; next}
  $0==e {skip=0}
  !skip {print}' "$DOC" > "$DOC.tmp" && mv "$DOC.tmp" "$DOC"
