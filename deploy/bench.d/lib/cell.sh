# A private cell for the benches that drive one through cellctl (sourced, not run; 70-dispatch-latency.sh,
# 90-memory.sh, 96-scale.sh; make_config also deploy/hosts). The caller sets $ROOT.

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

# make_config N DIR [TEMPLATE...]: deploy/'s configuration with N stations, copies of the templates in turn
# (default KT01 OK01 EM01 BS01: KT01, OK01, EM01, BS01, KT02, ...), each under a new id of its template's
# prefix, with the template's tools file if it has one.
make_config() {
  local n=$1 dir=$2 i k id
  shift 2
  local tpl=("$@")
  [ ${#tpl[@]} -gt 0 ] || tpl=(KT01 OK01 EM01 BS01)
  rm -rf "$dir"
  mkdir -p "$dir/stations"
  cp -r "$ROOT/deploy/systemd" "$ROOT/deploy/dds" "$dir/"
  for ((i = 0; i < n; i++)); do
    k=$((i % ${#tpl[@]}))
    id=${tpl[$k]:0:2}$(printf '%02d' $((i / ${#tpl[@]} + 1)))
    sed "s/^id = \"${tpl[$k]}\"/id = \"$id\"/" "$ROOT/deploy/stations/${tpl[$k]}.toml" >"$dir/stations/$id.toml"
    [ ! -f "$ROOT/deploy/stations/${tpl[$k]}.tools" ] || cp "$ROOT/deploy/stations/${tpl[$k]}.tools" "$dir/stations/$id.tools"
  done
}
