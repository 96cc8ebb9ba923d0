#!/usr/bin/env bash
# DNC drip feed (services/dnc/bench/drip_bench.cpp, docs/dnc.md "Benchmark"): 10 MB through a pseudo-terminal
# into the simulated control's 256-byte buffer at 9600 baud 7E1, time-scaled x25 (24,000 bytes/s; about
# 7 minutes; CELL_DNC_DRIP_MB=1 for a short run). Target: 0 bytes lost or changed, at least 90% of the line rate.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# shellcheck source=lib/figures.sh
source "$ROOT/deploy/bench.d/lib/figures.sh"
# shellcheck source=lib/exe.sh
source "$ROOT/deploy/bench.d/lib/exe.sh"
bench_exe dnc-drip dnc_drip_bench
out="$(mktemp)"
trap 'rm -f "$out"' EXIT
rc=0
"$BENCH" --mb "${CELL_DNC_DRIP_MB:-10}" --scale 25 >"$out" || rc=$?
sed 's/^/  /' "$out"
# The guard's figures (lib/figures.sh): the share of the line rate the feed kept (0.957 = 95.7%), and 1 when
# 0 bytes were lost or changed (0 otherwise: a relative guard cannot watch a count whose baseline is 0).
bench_figure dnc.drip.line_rate_share \
  "$(sed -n 's/^drip: .* bytes\/s line (\([0-9.]*\)%.*/\1/p' "$out" | awk '{ printf "%.3f", $1 / 100 }')" higher
bench_figure dnc.drip.byte_exact \
  "$(grep -q ' 0 bytes lost, program byte-exact' "$out" && echo 1 || echo 0)" higher
exit "$rc"
