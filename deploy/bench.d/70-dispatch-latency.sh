#!/usr/bin/env bash
# End-to-end dispatch latency on loopback against a bare bus request/reply round trip, same run.
# Starts a two-station cell (cellctl up, virtual machine clock) on its own DDS domain and data directory,
# defines a one-operation route of a short KT-APL program, and runs dispatch_latency_bench: per pallet, the
# time from OPERATE (sent by the bench itself, and `cellctl route operate` started as a process) to the
# first motion segment of the new run arriving on the station's segment topic (the bench subscribes beside
# the axis servo), one pallet at a time. Figures: median and p99, and their ratio to the bus round trip.
# Then the supervisor verbs as a user runs them (issue 21): median wall of `station ls` (with five configured
# stations not running), `job ls`, `job show`, `program ls` against the bare start of `cellctl --help`.
# Env: CELL_BUILD_DIR (default build/), CELL_BENCH_DOMAIN (default 97), CELL_BENCH_PALLETS (default 30),
# CELL_BENCH_VERB_RUNS (default 15).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# shellcheck source=lib/figures.sh
source "$ROOT/deploy/bench.d/lib/figures.sh"
# shellcheck source=lib/cell.sh
source "$ROOT/deploy/bench.d/lib/cell.sh"
bench_cell 70-dispatch-latency 97 dispatch_latency_bench
PALLETS="${CELL_BENCH_PALLETS:-30}"

"$BIN/cellctl" up --stations KT01,KT02 --clock virtual
cat >"$work/lat1.apl" <<'APL'
%
(NAM,LAT1)
(UTL,1001)
(UCY,30)
N10 G71 G90 G01
N20 X0 Y0 Z100. F0
N30 X50. Y20. Z10. F2000.
N40 G00 X0 Y0 Z100. F0
N50 M30
%
APL
"$BIN/cellctl" program put "$work/lat1.apl" >/dev/null
"$BIN/cellctl" route define BENCH --op KT01,KT02:LAT1
"$BIN/dispatch_latency_bench" --route BENCH --cellctl "$BIN/cellctl" --stations KT01,KT02 --pallets "$PALLETS" |
  tee "$work/dispatch.out"
# ratio (median|p99) WHAT / bus round trip: N.Nx
ratio_of() { sed -n "s/^ratio ($1) $2 .*: \([0-9.]*\)x\$/\1/p" "$work/dispatch.out"; }
bench_figure dispatch.operate_p50.vs_round_trip "$(ratio_of median 'OPERATE request')" lower
bench_figure dispatch.cellctl_p50.vs_round_trip "$(ratio_of median cellctl)" lower

# median_ms RUNS CMD...: the median wall time of RUNS runs of CMD, in milliseconds.
median_ms() {
  local runs=$1 t0 t1
  shift
  for _ in $(seq "$runs"); do
    t0=$(date +%s%N)
    "$@" >/dev/null
    t1=$(date +%s%N)
    echo $(((t1 - t0) / 1000))
  done | sort -n | awk '{ v[NR] = $1 } END { printf "%.1f", (NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2) / 1000 }'
}
RUNS="${CELL_BENCH_VERB_RUNS:-15}"
job="$("$BIN/cellctl" job ls --json | sed -n 's/.*"id": *\([0-9]*\).*/\1/p' | head -1)"
base=$(median_ms "$RUNS" "$BIN/cellctl" --help)
echo "cellctl --help (bare process start): median ${base} ms over $RUNS runs"
for verb in "station ls" "job ls" "job show $job" "program ls"; do
  # shellcheck disable=SC2086
  m=$(median_ms "$RUNS" "$BIN/cellctl" $verb)
  awk -v v="$verb" -v m="$m" -v b="$base" 'BEGIN { printf "cellctl %-12s median %7.1f ms  (%.1fx --help)%s\n", v, m, m / b, (m > 150 ? "  TARGET MISSED (150 ms)" : "") }'
  bench_figure "cellctl.$(echo "$verb" | awk '{ print $1 "_" $2 }').vs_help" "$(awk -v m="$m" -v b="$base" 'BEGIN { printf "%.2f", m / b }')" lower
done
