#!/usr/bin/env bash
# Predicted against actual machine time per corpus program, all four dialects (issue 40 "Measured";
# docs/predict.md): a cell of KT01, OK01, EM01 and BS01 on the virtual clock (cellctl up) runs the positive
# conformance programs of each dialect that the scheduler predicts, in name order until CELL_BENCH_PREDICT_N
# (default 8; 0: the whole corpus, 17 minutes on a loaded 2-core machine) of a second or more have run, each as a pallet on its
# station, one after another; the prediction (`program show`, predicted_s) against the job's cycle_s
# (lib/predict_actual.py; CELL_BENCH_PREDICT_ONLY=NAME,NAME: those corpus programs alone). Target: within 1% each. A prediction and every run on a station start from the
# state a pallet arrives in (docs/predict.md, judgement call 4), so every program is like for like. About a
# minute.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# shellcheck source=lib/figures.sh
source "$ROOT/deploy/bench.d/lib/figures.sh"
# shellcheck source=lib/cell.sh
source "$ROOT/deploy/bench.d/lib/cell.sh"
bench_cell 48-predict 104  # outside the tests' domains (1-100)
"$BIN/cellctl" up --stations KT01,OK01,EM01,BS01 --clock virtual >/dev/null
python3 "$ROOT/deploy/bench.d/lib/predict_actual.py" "$ROOT" "$BIN/cellctl" "${CELL_BENCH_PREDICT_N:-8}" |
  tee "$work/predict.out"
for d in ktapl okuma emco balt; do
  bench_figure "predict.$d.worst_ratio" "$(awk -v n="predict.$d.worst_ratio" '$2 == n { print $3 }' "$work/predict.out")" lower
done
