#!/usr/bin/env bash
# Axis servo benchmark (services/axis-servo/bench/servo_bench.cpp, docs/axis-servo.md "Benchmark"):
#   (a) simulated machine seconds per wall second and per CPU second on the virtual clock, against the
#       1000x real-time target;
#   (b) planned cycle time against the feed-limited lower bound and the closed-form optimum;
#   (c) contour error against the path tolerance.
# Then Google Benchmark's cost of one servo tick.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD="${CELL_BUILD_DIR:-$ROOT/build}"
BENCH="$BUILD/bin/servo_bench"
TARGET=1000   # simulated machine seconds per second
if [ ! -x "$BENCH" ]; then
  echo "servo: $BENCH not built (cmake --build $BUILD --target servo_bench)" >&2
  exit 1
fi
out="$(mktemp)"
trap 'rm -f "$out"' EXIT
"$BENCH" --benchmark_filter=BM_ServoTick --benchmark_min_time=0.2 >"$out" 2>&1 || {
  cat "$out" >&2
  echo "servo: servo_bench failed" >&2
  exit 1
}
sed 's/^/  /' "$out"
echo "servo summary (target ${TARGET}x real time):"
# The guard's figures (lib/figures.sh): x real time per CPU second and the (b)/(c) ratios, per scenario.
awk -v target="$TARGET" '
  function figure(what, value, better) {
    if (ENVIRON["CELL_BENCH_FIGURES"] == "" || value == "") return;
    printf "{\"name\": \"servo.%s.%s\", \"value\": %s, \"better\": \"%s\"}\n", slug, what, value, better \
      >> ENVIRON["CELL_BENCH_FIGURES"];
  }
  function ratio_of(line) { return (match(line, /ratio [0-9.]+/) ? substr(line, RSTART + 6, RLENGTH - 6) : "") }
  /^[^ ]/ && /:$/ {
    name = $0; sub(/:$/, "", name); sub(/ \(.*/, "", name);
    slug = (name ~ /contour/) ? "contour" : (name ~ /^drilling/) ? "drilling" : (name ~ /^long line/) ? "line" : \
           (name ~ /^circle/) ? "circle" : "other";
  }
  /\(a\)/ {
    wall = ""; cpu = "";
    for (i = 1; i <= NF; i++) {
      if ($i == "real" && $(i + 2) == "by" && $(i + 3) == "wall") wall = $(i - 1);
      if ($(i + 1) == "by" && $(i + 2) == "CPU") cpu = $i;
    }
    sub(/x$/, "", wall); sub(/x$/, "", cpu); sub(/,$/, "", cpu);
    if (wall == "") next;
    ok = (wall + 0 >= target) ? "meets" : "below";
    printf "  %s: %sx per wall second (%.1f x target, %s), %sx per CPU second (%.1f x target)\n",
           name, wall, wall / target, ok, cpu, cpu / target;
    if (wall + 0 < target) below = 1;
    figure("x_realtime_cpu", cpu, "higher");
  }
  /\(b\)/ {
    line = $0; sub(/^ *\(b\) */, "", line);
    printf "  %s: planned %s\n", name, line;
    figure("cycle_ratio", ratio_of(line), "lower");
  }
  /\(c\)/ {
    line = $0; sub(/^ *\(c\) */, "", line);
    printf "  %s: %s\n", name, line;
    figure("error_vs_tolerance", ratio_of(line), "lower");
  }
  /^BM_ServoTick/ { printf "  one servo tick: %s %s CPU\n", $4, $5 }
  END { if (below) print "  note: below the wall-clock target; on a shared, loaded machine compare the CPU figure" }
' "$out"
