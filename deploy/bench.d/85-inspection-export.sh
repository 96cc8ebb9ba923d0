#!/usr/bin/env bash
# Inspection file export (services/inspection-writer/bench/inspection_export_bench.cpp): `cellctl inspect export`
# without the bus on a KT-APL inspection file of 10,000 measurements: parse the text, export CSV or QIF 3.0,
# write it to /dev/null. Baseline in the same run: fprintf of 10,000 one-number lines to /dev/null.
# Figures: CPU ms per export, the ratio to the baseline, and the target (under 1 s per 10,000 measurements).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# shellcheck source=lib/exe.sh
source "$ROOT/deploy/bench.d/lib/exe.sh"
bench_exe inspection-export inspection_export_bench
out="$(mktemp)"
trap 'rm -f "$out"' EXIT
"$BENCH" --benchmark_min_time=0.5 >"$out" 2>&1 || { cat "$out" >&2; echo "inspection-export: bench failed" >&2; exit 1; }
sed 's/^/  /' "$out"
# Console rows: NAME TIME UNIT CPU UNIT ITERATIONS ...; every benchmark reports milliseconds.
awk '
  /^BM_/ { if ($5 != "ms") { print "inspection-export: unexpected unit " $5 > "/dev/stderr"; exit 1 } cpu[$1] = $4 }
  END {
    base = cpu["BM_FprintfBaseline"];
    if (base == "" || cpu["BM_CsvExport"] == "" || cpu["BM_QifExport"] == "") { print "inspection-export: rows missing" > "/dev/stderr"; exit 1 }
    printf "inspection export summary (10,000 measurements; target under 1000 ms each):\n";
    printf "  baseline fprintf of 10,000 lines: %.2f ms CPU\n", base;
    printf "  parse alone: %.2f ms (%.1fx baseline)\n", cpu["BM_Parse"], cpu["BM_Parse"] / base;
    n = split("BM_CsvExport BM_QifExport", names, " ");
    for (i = 1; i <= n; i++) {
      t = cpu[names[i]];
      printf "  %s (parse + export + write): %.2f ms CPU, %.1fx baseline, %s\n", (names[i] == "BM_CsvExport" ? "CSV" : "QIF 3.0"),
             t, t / base, (t < 1000 ? "meets the target" : "MISSES the target");
      if (t >= 1000) missed = 1;
      if (ENVIRON["CELL_BENCH_FIGURES"] != "")
        printf "{\"name\": \"inspection.%s_export.vs_fprintf\", \"value\": %.2f, \"better\": \"lower\"}\n",
               (names[i] == "BM_CsvExport" ? "csv" : "qif"), t / base >> ENVIRON["CELL_BENCH_FIGURES"];
    }
    exit missed;
  }' "$out"
