# Shared by the interpreter benchmarks (40-interpreter.sh, 41-okuma.sh, 42-emco.sh, 43-balt.sh; sourced, not
# run): set-up, whole-process timing and the LinuxCNC rs274 baseline. The caller sets $ROOT and $BENCH (its name,
# for messages) and calls bench_init.

# shellcheck source=figures.sh
source "$ROOT/deploy/bench.d/lib/figures.sh"

# bench_init: what every interpreter bench starts with. INTERP (cell-interp of CELL_BUILD_DIR, default build/)
# and BLOCKS (CELL_INTERP_BENCH_BLOCKS, default 1,000,000), both checked with /usr/bin/time, and $work, a scratch
# directory removed at exit. The caller sets $ROOT and $BENCH first.
bench_init() {
  INTERP="${CELL_BUILD_DIR:-$ROOT/build}/bin/cell-interp"
  BLOCKS="${CELL_INTERP_BENCH_BLOCKS:-1000000}"
  [ -x "$INTERP" ] || { echo "$BENCH: $INTERP not built" >&2; exit 1; }
  [ -x /usr/bin/time ] || { echo "$BENCH: /usr/bin/time missing (apt-get install time)" >&2; exit 1; }
  work="$(mktemp -d "${TMPDIR:-/tmp}/cell-$BENCH.XXXXXX")"
  trap 'rm -rf "$work"' EXIT
}

# per_s COUNT CPU_SECONDS: a whole rate (blocks/s).
per_s() {
  awk -v b="$1" -v s="$2" 'BEGIN {printf "%.0f", b / (s > 0 ? s : 0.001)}'
}

# measure LABEL cmd...: CPU seconds (user+sys), wall seconds and peak RSS (kB) via /usr/bin/time -v.
# Throughput uses CPU time: the bench machine is shared, and wall time under load says little.
measure() {
  local tlog="$work/time.$1"; shift
  /usr/bin/time -v "$@" >/dev/null 2>"$tlog" || { echo "$BENCH: failed: $*" >&2; tail -5 "$tlog" >&2; return 1; }
  local wall cpu rss
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {n=split($2,a,":"); s=0; for(i=1;i<=n;i++) s=s*60+a[i]; print s}' "$tlog")
  cpu=$(awk -F': ' '/User time|System time/ {s+=$2} END {print s}' "$tlog")
  rss=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$tlog")
  echo "$cpu $wall $rss"
}

# have_rs274: LinuxCNC's rs274 (Debian linuxcnc-uspace) is installed, or installed now when apt has it.
have_rs274() {
  if ! command -v rs274 >/dev/null; then
    local cand
    cand=$(apt-cache policy linuxcnc-uspace 2>/dev/null | awk '/Candidate:/ {print $2}')
    if [ -n "$cand" ] && [ "$cand" != "(none)" ]; then
      echo "installing linuxcnc-uspace $cand for the baseline"
      local sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
      DEBIAN_FRONTEND=noninteractive $sudo apt-get -o DPkg::Lock::Timeout=600 -y -q install \
        --no-install-recommends linuxcnc-uspace >"$work/apt.log" 2>&1 || tail -5 "$work/apt.log"
    fi
  fi
  if ! command -v rs274 >/dev/null; then
    echo "LinuxCNC rs274 NOT AVAILABLE (apt has no linuxcnc-uspace here): only our own figures are reported"
    return 1
  fi
}

# measure_rs274 NGC_FILE: measure's figures for rs274 on the file, with the empty tool table and parameter
# file it reads from the current directory.
measure_rs274() {
  (
    cd "$work"
    : >tool.tbl
    : >rs274ngc.var
    # rs274 truncates and maps $HOME/.tool.mmap: two runs sharing a HOME (a bench beside the oracle's test)
    # die of SIGBUS. A HOME of its own.
    mkdir -p "$work/rs274-home"
    HOME="$work/rs274-home" measure ngc rs274 -g -t tool.tbl -v rs274ngc.var "$1" /dev/null
  )
}

rs274_version() {
  dpkg-query -W -f='${Version}' linuxcnc-uspace 2>/dev/null
}
