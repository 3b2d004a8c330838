#!/usr/bin/env bash
# Strip-packing benchmark on the ESICUP set; writes the table into docs/nesting.md.
# usage: bench/nest_spp.sh [SECONDS=60] [SEED=0]
set -euo pipefail
cd "$(dirname "$0")/.."
SECS="${1:-60}"; SEED="${2:-0}"
DATA=../shared/datasets/nesting
[ -d "$DATA" ] || DATA=/work/shared/datasets/nesting
cargo build --release -p sv-nest --example spp >/dev/null
OUT=$(mktemp)
{
  echo "| instance | ours ${SECS}s density % | length | lbf density % | sparrow 1200 s avg % | gap to sparrow (pp) |"
  echo "|---|---|---|---|---|---|"
  for inst in albano blaz1 dagli fu jakobs1 jakobs2 mao marques shapes0 shapes1 shirts swim trousers; do
    line=$(./target/release/examples/spp "$DATA/spp/$inst.json" --seconds "$SECS" --seed "$SEED" 2>/dev/null)
    dens=$(echo "$line" | awk '{print $5}'); len=$(echo "$line" | awk '{print $3}')
    ref=$(grep "^$inst," "$DATA/best_known_spp.csv")
    lbf=$(echo "$ref" | cut -d, -f12); sp=$(echo "$ref" | cut -d, -f9)
    gap=$(awk -v a="$sp" -v b="$dens" 'BEGIN{printf "%.2f", a-b}')
    echo "| $inst | $dens | $len | $lbf | $sp | $gap |"
  done
} > "$OUT"
cat "$OUT"
DOC=docs/nesting.md
BEGIN='<!-- bench:begin -->'; END='<!-- bench:end -->'
if grep -q "$BEGIN" "$DOC"; then
  awk -v b="$BEGIN" -v e="$END" -v f="$OUT" -v s="$SECS" '
    $0==b {print; print ""; print "Run: `bench/nest_spp.sh " s "` (two searches side by side on the 2 cores, seed 0, best kept)."; print ""; while ((getline l < f) > 0) print l; print ""; skip=1; next}
    $0==e {skip=0}
    !skip {print}' "$DOC" > "$DOC.tmp" && mv "$DOC.tmp" "$DOC"
fi
rm -f "$OUT"
