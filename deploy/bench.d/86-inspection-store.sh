#!/usr/bin/env bash
# A program's file close to its durable acknowledgement (issue 14): what the station waits for at CLF/G37
# before it sets L1050, i.e. STORE_FILE over the bus to a real cell-inspection-writer (write, fsync, rename,
# fsync of the folder), against a bare round trip to the same writer in the same run (CAT of a file that does
# not exist). Median and p99 over COUNT interleaved calls, and their ratio. The disk's fsync speed is
# most of the difference; the writer's data folder is a fresh temporary folder under TMPDIR.
# Env: CELL_BUILD_DIR (default build/), CELL_BENCH_DOMAIN (default 98), CELL_BENCH_COUNT (default 500).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BIN="${CELL_BUILD_DIR:-$ROOT/build}/bin"
for exe in inspection_store_bench cell-inspection-writer; do
  [ -x "$BIN/$exe" ] || { echo "86-inspection-store: $BIN/$exe not built" >&2; exit 1; }
done
export CELL_DOMAIN="${CELL_BENCH_DOMAIN:-98}"
work="$(mktemp -d "${TMPDIR:-/tmp}/cell-inspection-store.XXXXXX")"
writer=""
cleanup() {
  [ -n "$writer" ] && kill "$writer" 2>/dev/null && wait "$writer" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
CELL_DATA_DIR="$work" "$BIN/cell-inspection-writer" >"$work/writer.log" 2>&1 &
writer=$!
"$BIN/inspection_store_bench" "${CELL_BENCH_COUNT:-500}" >"$work/out" 2>&1 || {
  cat "$work/out" "$work/writer.log" >&2
  echo "86-inspection-store: bench failed" >&2
  exit 1
}
awk '
  $1 == "RESULT" { med[$2] = $3; p99[$2] = $4 }
  END {
    if (med["store"] == "" || med["bare"] == "") { print "86-inspection-store: results missing" > "/dev/stderr"; exit 1 }
    printf "inspection file close to durable acknowledgement (STORE_FILE over the bus, %s-byte file):\n", 330;
    printf "  bare round trip (CAT, no file): median %.0f us, p99 %.0f us\n", med["bare"], p99["bare"];
    printf "  close, fsync, reply:    median %.0f us, p99 %.0f us (%.1fx, %.1fx the bare round trip)\n",
           med["store"], p99["store"], med["store"] / med["bare"], p99["store"] / p99["bare"];
    if (ENVIRON["CELL_BENCH_FIGURES"] != "")
      printf "{\"name\": \"inspection.store_file.vs_round_trip\", \"value\": %.2f, \"better\": \"lower\"}\n",
             med["store"] / med["bare"] >> ENVIRON["CELL_BENCH_FIGURES"];
  }' "$work/out"
