#!/usr/bin/env bash
# The LinuxCNC differential at depth (issue 33 item 1, docs/testing.md): 100,000 generated blocks per dialect
# (CELL_ORACLE_BLOCKS), a new seed each run (CELL_ORACLE_SEED to repeat one), cell-interp against LinuxCNC's
# rs274 move by move. Figures: the agreement per dialect in percent of blocks (up to each 500-block program's
# first disagreement; higher is better). The first disagreements are printed with both blocks and both moves
# and kept under $CELL_ORACLE_KEEP (default: a scratch directory, removed). Fails only when a run cannot start.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# shellcheck source=lib/figures.sh
source "$ROOT/deploy/bench.d/lib/figures.sh"
BIN="${CELL_BUILD_DIR:-$ROOT/build}/bin"
for exe in cell-interp cell-oracle-gen; do
  [ -x "$BIN/$exe" ] || { echo "44-oracle: $BIN/$exe not built" >&2; exit 1; }
done
command -v rs274 >/dev/null || { echo "44-oracle: rs274 missing (deploy/install-deps installs linuxcnc-uspace)" >&2; exit 1; }
seed="${CELL_ORACLE_SEED:-$(od -An -N4 -tu4 /dev/urandom | tr -d ' ')}"
blocks="${CELL_ORACLE_BLOCKS:-100000}"
keep="${CELL_ORACLE_KEEP:-}"
echo "44-oracle: seed $seed, $blocks blocks per dialect (CELL_ORACLE_SEED=$seed repeats this run)"
out="$("$BIN/cell-oracle-gen" check --dialect all --seed "$seed" --blocks "$blocks" --chunk 500 --report \
  --interp "$BIN/cell-interp" ${keep:+--keep "$keep"})"
echo "$out"
while read -r dialect pct _; do
  bench_figure "oracle.${dialect%:}.agreement_pct" "${pct%\%}" higher
done < <(grep -E '^[a-z]+: [0-9.]+% agreement' <<<"$out")
# Under cutter radius compensation (check --comp, Balt-System and KT-APL) and tool-nose radius compensation
# (EMCO, Okuma): 3,000 contour blocks per dialect (CELL_ORACLE_COMP_BLOCKS), one program per contour, about
# two minutes. Figure: the programs that agree in percent of those rs274 accepts and the dialect does not
# refuse with its manual's alarm for that path (rs274 refuses some concave corners of its own accord, a lathe
# manual names alarms where LinuxCNC goes on; higher is better).
comp_blocks="${CELL_ORACLE_COMP_BLOCKS:-3000}"
out="$("$BIN/cell-oracle-gen" check --comp --dialect all --seed "$seed" --blocks "$comp_blocks" --report \
  --interp "$BIN/cell-interp" ${keep:+--keep "$keep"})"
echo "$out"
while read -r dialect agree programs refused alarms; do
  bench_figure "oracle.${dialect}.comp_agreement_pct" \
    "$(awk -v a="$agree" -v p="$programs" -v r="$refused" -v m="$alarms" \
      'BEGIN { printf "%.2f", 100 * a / (p - r - m) }')" higher
done < <(sed -nE 's/^([a-z]+) comp: ([0-9]+) of ([0-9]+) programs agree .* ([0-9]+) refused by rs274, [0-9]+ by cell-interp, ([0-9]+) by the manual.s alarm.*/\1 \2 \3 \4 \5/p' <<<"$out")
