#!/usr/bin/env bash
# The plan's figures (issue 40 "Measured", docs/scheduler.md §15; services/scheduler/bench/plan_bench.cpp):
# 30 pallets on routes of corpus programs of every dialect across KT01, KT02, OK01, EM01 and BS01, through
# the scheduler library on a virtual clock with stations whose programs last their prediction on the
# station's servo model. (a) the projected makespan (Scheduler::Plan() after operating) against the makespan
# the cell then takes (target within 3%); (b) that makespan balanced on 0 s for programs without UCY against
# balanced on the predictions. Deterministic: about a second.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# shellcheck source=lib/figures.sh
source "$ROOT/deploy/bench.d/lib/figures.sh"
# shellcheck source=lib/exe.sh
source "$ROOT/deploy/bench.d/lib/exe.sh"
bench_exe plan plan_bench
out="$(mktemp)"
trap 'rm -f "$out"' EXIT
"$BENCH" "$ROOT" | tee "$out"
# The guard's figures: "figure NAME VALUE" lines. projection_ratio is max(p/a, a/p), 1.0 when exact.
bench_figure plan.makespan.projection_ratio "$(awk '$2 == "plan.makespan.projection_ratio" { print $3 }' "$out")" lower
bench_figure plan.makespan.blind_vs_predicted "$(awk '$2 == "plan.makespan.blind_vs_predicted" { print $3 }' "$out")" higher
