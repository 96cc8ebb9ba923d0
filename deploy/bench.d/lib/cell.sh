# A private cell for the benches that drive one through cellctl (sourced, not run; 70-dispatch-latency.sh,
# 90-memory.sh). The caller sets $ROOT.

# bench_cell NAME DOMAIN EXE...: BIN (CELL_BUILD_DIR's bin/), the named executables and every cell service
# checked as built, and $work, a scratch directory holding the cell's data; the cell runs on CELL_BENCH_DOMAIN
# (default DOMAIN) with its dashboard on any free port, and is taken down with $work at exit.
bench_cell() {
  local name=$1 domain=$2 exe
  shift 2
  BIN="${CELL_BUILD_DIR:-$ROOT/build}/bin"
  for exe in cellctl "$@" cell-scheduler cell-program-store cell-interpreter cell-axis-servo \
             cell-inspection-writer cell-dashboard; do
    [ -x "$BIN/$exe" ] || { echo "$name: $BIN/$exe not built" >&2; exit 1; }
  done
  work="$(mktemp -d "${TMPDIR:-/tmp}/cell-$name.XXXXXX")"
  export CELL_DATA_DIR="$work/data"
  export CELL_DOMAIN="${CELL_BENCH_DOMAIN:-$domain}"
  export CELL_HTTP="${CELL_HTTP:-127.0.0.1:0}"
  mkdir -p "$CELL_DATA_DIR"
  trap '"$BIN/cellctl" down >/dev/null 2>&1 || true; rm -rf "$work"' EXIT
}
