#!/usr/bin/env bash
# Balt-System throughput against LinuxCNC's standalone RS-274/NGC interpreter (rs274), same run, same toolpath:
# one generator writes a 1,000,000-block Balt-System program (E parameter arithmetic, G01/G02/G03, a
# subroutine called three times in an (RPT,3) loop) and the same toolpath as NGC (#parameters, an o-word sub
# called in an o-word repeat), block for block: both have the same number of lines and the same mix of moves.
# Both write their canonical output to /dev/null. Figures: blocks/s of each (CPU time), the ratio (target
# >= 10x), and peak RSS of cell-interp for 100,000 and 1,000,000 blocks (target < 64 MB, flat). Missed
# targets are printed as TARGET MISSED; the script fails only when a run fails.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BENCH=43-balt
# shellcheck source=lib/interp-bench.sh
source "$ROOT/deploy/bench.d/lib/interp-bench.sh"
bench_init

# gen BALT|NGC BLOCKS > file: groups of 10 lines in both languages (the same moves in the same order).
gen() {
  awk -v kind="$1" -v blocks="$2" 'BEGIN {
    groups = int((blocks - 4) / 10); if (groups < 1) groups = 1
    if (kind == "BALT") {
      print "%"
      print "G71 G90 G94 G0 X0 Y0 Z5"
      print "E31=0"
      print "E35=2"
      for (g = 0; g < groups; g++) {
        print "E31=E31+.001"
        print "E32=E31*2+1"
        print "G1 G90 X10 Y5 F800"
        print "G2 X20 Y5 I15 J5"
        print "G3 X30 Y5 I25 J5"
        print "G1 XE32 YE31"
        print "(RPT,3)"
        print "(CLS,SQ)"
        print "(ERP)"
        print "G1 G90 X0 Y0"
      }
      print "M30"
    } else {
      print "o100 sub"
      print "G91 G01 X#1 F800"
      print "Y#1"
      print "X[-#1]"
      print "Y[-#1]"
      print "o100 endsub"
      print "G21 G90 G94 G0 X0 Y0 Z5"
      print "#101=0"
      for (g = 0; g < groups; g++) {
        print "#101=[#101+.001]"
        print "#102=[#101*2+1]"
        print "G01 G90 X10 Y5 F800"
        print "G02 X20 Y5 I5 J0"
        print "G03 X30 Y5 I5 J0"
        print "G01 X#102 Y#101"
        print "o" (1000 + g) " repeat [3]"
        print "o100 call [2]"
        print "o" (1000 + g) " endrepeat"
        print "G01 G90 X0 Y0"
      }
      print "M2"
      print "%"
    }
  }'
}

mkdir -p "$work/lib"
printf 'G1 G91 XE35 F800\nYE35\nX-E35\nY-E35\n' >"$work/lib/SQ"
small=$((BLOCKS / 10))
gen BALT "$BLOCKS" >"$work/bench.balt"
gen BALT "$small" >"$work/small.balt"
gen NGC "$BLOCKS" >"$work/bench.ngc"
balt_blocks=$(wc -l <"$work/bench.balt")
ngc_blocks=$(wc -l <"$work/bench.ngc")
moves=$("$INTERP" --dialect balt --lib "$work/lib" "$work/bench.balt" | grep -c '"op":"\(linear\|arc\|rapid\)"')

read -r b_cpu b_wall b_rss < <(measure balt "$INTERP" --dialect balt --lib "$work/lib" "$work/bench.balt")
read -r _ _ small_rss < <(measure small "$INTERP" --dialect balt --lib "$work/lib" "$work/small.balt")
bench_figure interp.balt.peak_rss_mb "$((b_rss / 1024))" lower
b_bps=$(per_s "$balt_blocks" "$b_cpu")
echo "cell-interp: $balt_blocks Balt-System blocks ($moves moves) in ${b_cpu} s CPU (${b_wall} s wall) = $b_bps blocks/s"
echo "cell-interp peak RSS: $((b_rss / 1024)) MB at $balt_blocks blocks, $((small_rss / 1024)) MB at $(wc -l <"$work/small.balt") blocks (target < 64 MB, flat)"
rc=0
[ "$b_rss" -lt $((64 * 1024)) ] || echo "43-balt: TARGET MISSED: peak RSS >= 64 MB"
[ "$b_rss" -le $((small_rss + 2048)) ] || echo "43-balt: TARGET MISSED: peak RSS grows with program length"

have_rs274 || exit $rc
read -r ngc_cpu ngc_wall ngc_rss < <(measure_rs274 "$work/bench.ngc")
ngc_bps=$(per_s "$ngc_blocks" "$ngc_cpu")
echo "rs274 (LinuxCNC $(rs274_version)): $ngc_blocks NGC lines, same toolpath, in ${ngc_cpu} s CPU (${ngc_wall} s wall) = $ngc_bps blocks/s, peak RSS $((ngc_rss / 1024)) MB"
ratio=$(awk -v a="$ngc_cpu" -v b="$b_cpu" 'BEGIN {printf "%.1f", a / (b > 0 ? b : 0.001)}')
echo "ratio: cell-interp (Balt-System) is ${ratio}x rs274 on the same toolpath (target >= 10x)"
bench_figure interp.balt.vs_rs274 "$ratio" higher
awk -v r="$ratio" 'BEGIN {exit !(r >= 10)}' || echo "43-balt: TARGET MISSED: ratio ${ratio}x < 10x"
exit $rc
