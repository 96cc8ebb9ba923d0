#!/usr/bin/env bash
# Resident memory of a cell's services as pallets go through it (issue 39 item 1: what a cell keeps per pallet
# must be bounded; it runs for months). Starts a two-station cell (cellctl up, virtual machine clock) on its
# own DDS domain and data directory with the demo's programs: routes PUMP and VALVE (either station) and PROBE
# (KT01 probes its part, writes the inspection file INSP7 and copies it to HOST by RCP), operated
# PUMP, VALVE, PUMP, PROBE in turn. memory_bench keeps 4 jobs live, asks `job show` of every finished job and
# one page of `job ls`, `program ls`, `inspect ls` every 10th, runs `cellctl job show` as a process every 25th,
# and prints every service's VmRSS (/proc/PID/status) at the checkpoints and after CELL_BENCH_MEMORY_IDLE
# seconds idle. Targets: the program store, the scheduler and the inspection writer each grow by less than
# 10 MB from pallet 50 to 450, and stay within 10% from pallet 1,000 to the last checkpoint.
# About 3 minutes for 1,000 pallets (CELL_BENCH_MEMORY_PALLETS=10000: about 30 minutes) on a 2-core machine.
# Env: CELL_BUILD_DIR (default build/), CELL_BENCH_DOMAIN (default 102), CELL_BENCH_MEMORY_PALLETS (1000 or
# 10000, default 1000), CELL_BENCH_MEMORY_IDLE (default 30).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# shellcheck source=lib/figures.sh
source "$ROOT/deploy/bench.d/lib/figures.sh"
# shellcheck source=lib/cell.sh
source "$ROOT/deploy/bench.d/lib/cell.sh"
bench_cell 90-memory 102 memory_bench  # outside the tests' domains (1-100)
case "${CELL_BENCH_MEMORY_PALLETS:-1000}" in
  1000) checkpoints=50,450,1000 ;;
  10000) checkpoints=50,450,1000,2000,5000,10000 ;;
  *) echo "90-memory: CELL_BENCH_MEMORY_PALLETS is 1000 or 10000" >&2; exit 2 ;;
esac

CTL="$BIN/cellctl"
DEMO="$ROOT/deploy/demo.d"
"$CTL" up --stations KT01,KT02 --clock virtual >/dev/null
for f in PUMP341 VALVE12; do "$CTL" program put "$DEMO/$f.apl" >/dev/null; done
"$CTL" program put "$DEMO/PROBE7.apl" >/dev/null
"$CTL" program put "$DEMO/KT01-p7.toml" --name PART7 --type part_model >/dev/null
"$CTL" tools load KT01 "$DEMO/T1-probe.tld" >/dev/null
"$CTL" route define PUMP --op "KT01,KT02:PUMP341" >/dev/null
"$CTL" route define VALVE --op "KT01,KT02:VALVE12" >/dev/null
"$CTL" route define PROBE --op "KT01:PART7,BORE7" >/dev/null
echo "RSS per service (MB), two stations on the virtual clock, checkpoints at pallets $checkpoints:"
"$BIN/memory_bench" --routes PUMP,VALVE,PUMP,PROBE --cellctl "$CTL" --checkpoints "$checkpoints" \
  --idle "${CELL_BENCH_MEMORY_IDLE:-30}" | tee "$work/memory.out"
# The guard's figures (lib/figures.sh): each of the three services' RSS at pallet 1,000 over its RSS at
# pallet 50 (a ratio: flat is 1.0; +10 MB on about 22 MB is 1.45).
for svc in cell-program-store cell-scheduler cell-inspection-writer; do
  bench_figure "memory.${svc#cell-}.rss_1000_vs_50" "$(awk -v svc="$svc" '
    function rss(line,   i, n, f) { n = split(line, f, " "); for (i = 1; i < n; i++) if (f[i] == svc) return f[i + 1] }
    /^pallet 50 / { a = rss($0) } /^pallet 1000 / { b = rss($0) }
    END { if (a > 0 && b > 0) printf "%.3f", b / a }' "$work/memory.out")" lower
done
