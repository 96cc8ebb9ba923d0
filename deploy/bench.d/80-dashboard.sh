#!/usr/bin/env bash
# Dashboard benchmark (services/dashboard/bench/dashboard_bench.cpp, docs/dashboard.md "Benchmark"): a real
# cell-dashboard on its own DDS domain with four stations played on the bus by the bench:
#   (a) DDS station change -> DOM change in headless Chromium (median, p99; target p50 < 100 ms);
#   (b) GET /current for 4 stations against a static file from the same server;
#   (c) 50 live clients for a minute with no dropped updates.
# Env: CELL_BENCH_DOMAIN (default 96), CELL_BENCH_SECONDS (default 60), CELL_BENCH_CLIENTS (default 50).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BIN="${CELL_BUILD_DIR:-$ROOT/build}/bin"
for exe in dashboard_bench cell-dashboard; do
  [ -x "$BIN/$exe" ] || { echo "80-dashboard: $BIN/$exe not built" >&2; exit 1; }
done
export CELL_DOMAIN="${CELL_BENCH_DOMAIN:-96}"
export CELL_BIN_DIR="$BIN" CELL_SOURCE_DIR="$ROOT"
"$BIN/dashboard_bench"
