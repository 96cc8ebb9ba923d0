# The bench guard's half in each script (sourced, not run): `./cell bench --json FILE` and `--compare` set
# CELL_BENCH_FIGURES to a file; each bench appends its figures there, one JSON object per line. Figures are
# ratios, sizes and rates against real time, never wall times: the baseline (deploy/bench-baseline.json) must
# hold on another machine of the same kind.

# bench_figure NAME VALUE higher|lower: one figure and which way is better. A value that is not a number is
# reported on stderr and left out (a bench that could not measure it says so in its own output).
bench_figure() {
  [ -n "${CELL_BENCH_FIGURES:-}" ] || return 0
  if ! [[ "$2" =~ ^-?[0-9]+(\.[0-9]+)?$ ]]; then
    echo "bench figure $1: '$2' is not a number; left out" >&2
    return 0
  fi
  printf '{"name": "%s", "value": %s, "better": "%s"}\n' "$1" "$2" "$3" >>"$CELL_BENCH_FIGURES"
}
