#!/usr/bin/env bash
# Discovery time per pair of DDS stacks on loopback: a new process (Fast DDS or Cyclone DDS) against a
# running one (either), from main() to its first state sample (late joiner) and to its first reply. Ratios
# are to Fast DDS -> Fast DDS of the same run. Env: CELL_BUILD_DIR (default build/), CELL_BENCH_DOMAIN
# (default 96), CELL_BENCH_RUNS (default 10).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BIN="${CELL_BUILD_DIR:-$ROOT/build}/bin"
[ -x "$BIN/bus_discovery_bench" ] || { echo "80-discovery: $BIN/bus_discovery_bench not built" >&2; exit 1; }
CELL_DOMAIN="${CELL_BENCH_DOMAIN:-96}" "$BIN/bus_discovery_bench" --runs "${CELL_BENCH_RUNS:-10}"
