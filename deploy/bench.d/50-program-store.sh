#!/usr/bin/env bash
# Program store through the bus against the sqlite3 command-line tool, same run.
# Starts cell-program-store on its own DDS domain and data directory, then program_store_bus_bench puts and
# gets N programs of 2 KB (one request and one committed transaction each) and one 20 MB file (chunked).
# Baseline: sqlite3 inserts the same N rows into a bare table, WAL mode, synchronous=FULL, one BEGIN/COMMIT
# per program, and the 20 MB file in one transaction. Figures: put ratio store/sqlite3 (target <= 3x), get
# time, and the 20 MB round trip.
# Env: CELL_BUILD_DIR (default build/), CELL_BENCH_DOMAIN_PS (default 96), CELL_BENCH_PROGRAMS (default 10000).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# shellcheck source=lib/figures.sh
source "$ROOT/deploy/bench.d/lib/figures.sh"
BIN="${CELL_BUILD_DIR:-$ROOT/build}/bin"
for exe in cell-program-store program_store_bus_bench; do
  [ -x "$BIN/$exe" ] || { echo "50-program-store: $BIN/$exe not built" >&2; exit 1; }
done
command -v sqlite3 >/dev/null || { echo "50-program-store: sqlite3 not installed (apt-get install sqlite3)" >&2; exit 1; }
PROGRAMS="${CELL_BENCH_PROGRAMS:-10000}"

work="$(mktemp -d "${TMPDIR:-/tmp}/cell-ps-bench.XXXXXX")"
store_pid=""
cleanup() {
  if [ -n "$store_pid" ] && kill -0 "$store_pid" 2>/dev/null; then
    kill -TERM "$store_pid" 2>/dev/null || true
    for _ in $(seq 50); do kill -0 "$store_pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$store_pid" 2>/dev/null || true
    wait "$store_pid" 2>/dev/null || true
  fi
  rm -rf "$work"
}
trap cleanup EXIT

now() { date +%s.%N; }

# Baseline first (the bench writes the rows it will put as a sqlite3 script).
mkdir -p "$work/data"
"$BIN/program_store_bus_bench" --programs "$PROGRAMS" --sql-out "$work/rows.sql" --big-out "$work/big.txt"
t0=$(now)
sqlite3 "$work/baseline.db" <"$work/rows.sql" >/dev/null
t1=$(now)
sqlite3 "$work/baseline.db" "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL;
  BEGIN; INSERT INTO programs VALUES('BIG', readfile('$work/big.txt')); COMMIT;" >/dev/null
t2=$(now)
rows=$(sqlite3 "$work/baseline.db" "SELECT count(*) FROM programs")
[ "$rows" -eq $((PROGRAMS + 1)) ] || { echo "50-program-store: baseline has $rows rows" >&2; exit 1; }
sqlite_s=$(echo "$t1 - $t0" | bc -l)
sqlite_big_s=$(echo "$t2 - $t1" | bc -l)

export CELL_DOMAIN="${CELL_BENCH_DOMAIN_PS:-96}"
CELL_DATA_DIR="$work/data" "$BIN/cell-program-store" 2>"$work/store.log" &
store_pid=$!
"$BIN/program_store_bus_bench" --programs "$PROGRAMS" >"$work/bench.out"
cat "$work/bench.out"
get() { awk -v k="$1" '$1 == k { print $2 }' "$work/bench.out"; }
put_s=$(get put_s); get_s=$(get get_s); big_put_s=$(get big_put_s); big_get_s=$(get big_get_s)

printf 'sqlite3 CLI: %d inserts (one commit each) %.2f s (%.0f/s); 20 MB insert %.2f s\n' \
  "$PROGRAMS" "$sqlite_s" "$(echo "$PROGRAMS / $sqlite_s" | bc -l)" "$sqlite_big_s"
printf 'program store over the bus: %d puts %.2f s (%.0f/s), %d gets %.2f s (%.0f/s)\n' \
  "$PROGRAMS" "$put_s" "$(echo "$PROGRAMS / $put_s" | bc -l)" "$PROGRAMS" "$get_s" "$(echo "$PROGRAMS / $get_s" | bc -l)"
ratio=$(echo "$put_s / $sqlite_s" | bc -l)
bench_figure program_store.put_vs_sqlite3 "$(printf %.2f "$ratio")" lower
printf 'ratio put/sqlite3: %.2fx (target <= 3x): %s\n' "$ratio" "$(echo "$ratio <= 3" | bc -l | sed 's/1/met/;s/0/MISSED/')"
printf '20 MB round trip: put %.2f s + get %.2f s = %.2f s (sqlite3 insert alone %.2f s)\n' \
  "$big_put_s" "$big_get_s" "$(echo "$big_put_s + $big_get_s" | bc -l)" "$sqlite_big_s"
