#!/usr/bin/env bash
# DNC drip feed (services/dnc/bench/drip_bench.cpp, docs/dnc.md "Benchmark"): 10 MB through a pseudo-terminal
# into the simulated control's 256-byte buffer at 9600 baud 7E1, time-scaled x25 (24,000 bytes/s; about
# 7 minutes; CELL_DNC_DRIP_MB=1 for a short run). Target: 0 bytes lost or changed, at least 90% of the line rate.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BENCH="${CELL_BUILD_DIR:-$ROOT/build}/bin/dnc_drip_bench"
if [ ! -x "$BENCH" ]; then
  echo "dnc-drip: $BENCH not built (cmake --build build --target dnc_drip_bench)" >&2
  exit 1
fi
"$BENCH" --mb "${CELL_DNC_DRIP_MB:-10}" --scale 25 | sed 's/^/  /'
exit "${PIPESTATUS[0]}"
