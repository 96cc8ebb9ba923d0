# bench_exe NAME TARGET: sets BENCH to the built benchmark TARGET (CELL_BUILD_DIR, default build/), or says how
# to build it and exits (sourced by the scripts that run one benchmark binary; NAME is the script's name).
bench_exe() {
  BENCH="${CELL_BUILD_DIR:-$ROOT/build}/bin/$2"
  if [ ! -x "$BENCH" ]; then
    echo "$1: $BENCH not built (cmake --build build --target $2)" >&2
    exit 1
  fi
}
