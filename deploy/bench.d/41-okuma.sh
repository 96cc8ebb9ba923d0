#!/usr/bin/env bash
# Okuma OSP-E100L interpreter throughput against LinuxCNC's standalone RS-274/NGC interpreter (rs274), same run,
# same toolpath: one generator writes a 1,000,000-block Okuma turning program (G01, G02/G03 with I/K,
# common-variable arithmetic, an expression X=V2+100, a subprogram CALL with a local argument) and the same
# program as NGC (#parameters, o-word sub), with the same block count and the same mix of lines. Both write
# their canonical output to /dev/null. Figures: blocks/s of each (CPU time), the ratio (target >= 10x), and peak
# RSS of cell-interp for 100,000 and 1,000,000 blocks (target < 64 MB, flat). Missed targets are printed as
# TARGET MISSED; the script fails only when a run fails. rs274 comes from 40-interpreter.sh's install.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BENCH=41-okuma
# shellcheck source=lib/interp-bench.sh
source "$ROOT/deploy/bench.d/lib/interp-bench.sh"
bench_init

# gen OKUMA|NGC BLOCKS DIR: writes DIR/bench.<kind> (and the Okuma subprogram DIR/lib/O1000.SUB). Groups of 8
# blocks; the subprogram is 7 blocks in both languages. X is a diameter in Okuma and a radius in NGC (G18, no
# lathe diameter mode), so the NGC numbers are halved: the same geometry.
gen() {
  awk -v kind="$1" -v blocks="$2" -v dir="$3" 'BEGIN {
    groups = int((blocks - 12) / 8); if (groups < 1) groups = 1
    if (kind == "OKUMA") {
      out = dir "/bench.okuma"
      sub_file = dir "/lib/O1000.SUB"
      print "O1000" > sub_file
      print "N1 G91 G01 X=-DP" > sub_file
      print "N2 Z=-DP" > sub_file
      print "N3 X=DP" > sub_file
      print "N4 Z=DP" > sub_file
      print "N5 G90" > sub_file
      print "N6 RTS" > sub_file
      print "%" > out
      print "O9000" > out
      print "N1 G00 X120 Z60" > out
      print "N2 G94 G01 F500" > out
      print "N3 V1=0" > out
      for (g = 0; g < groups; g++) {
        print "V1=V1+0.001" > out
        print "V2=V1*2+1" > out
        print "G01 X60 Z50" > out
        print "G02 X80 Z40 I10" > out
        print "G03 X100 Z30 K-10" > out
        print "G01 X=V2+100 Z=V1" > out
        print "CALL O1000 DP=1" > out
        print "G00 X120 Z60" > out
      }
      print "M02" > out
    } else {
      out = dir "/bench.ngc"
      print "%" > out
      print "o100 sub" > out
      print "G91 G01 X[-#1/2]" > out
      print "Z[-#1]" > out
      print "X[#1/2]" > out
      print "Z#1" > out
      print "G90" > out
      print "o100 endsub" > out
      print "G18 G21 G90 G94 G00 X60 Z60" > out
      print "G01 F500" > out
      print "#101=0" > out
      for (g = 0; g < groups; g++) {
        print "#101=[#101+.001]" > out
        print "#102=[#101*2+1]" > out
        print "G01 X30 Z50" > out
        print "G02 X40 Z40 I10 K0" > out
        print "G03 X50 Z30 I0 K-10" > out
        print "G01 X[[#102+100]/2] Z#101" > out
        print "o100 call [1]" > out
        print "G00 X60 Z60" > out
      }
      print "M2" > out
      print "%" > out
    }
  }'
}

mkdir -p "$work/big/lib" "$work/small/lib"
small=$((BLOCKS / 10))
gen OKUMA "$BLOCKS" "$work/big"
gen OKUMA "$small" "$work/small"
gen NGC "$BLOCKS" "$work/big"
ok_blocks=$(($(wc -l <"$work/big/bench.okuma") + $(wc -l <"$work/big/lib/O1000.SUB")))
ngc_blocks=$(wc -l <"$work/big/bench.ngc")
moves=$("$INTERP" --dialect okuma --lib "$work/big/lib" "$work/big/bench.okuma" | grep -c '"op":"\(linear\|arc\|rapid\)"')

read -r ok_cpu ok_wall ok_rss < <(measure ok "$INTERP" --dialect okuma --lib "$work/big/lib" "$work/big/bench.okuma")
read -r _ _ small_rss < <(measure small "$INTERP" --dialect okuma --lib "$work/small/lib" "$work/small/bench.okuma")
bench_figure interp.okuma.peak_rss_mb "$((ok_rss / 1024))" lower
ok_bps=$(per_s "$ok_blocks" "$ok_cpu")
echo "cell-interp: $ok_blocks Okuma blocks ($moves moves) in ${ok_cpu} s CPU (${ok_wall} s wall) = $ok_bps blocks/s"
echo "cell-interp peak RSS: $((ok_rss / 1024)) MB at $ok_blocks blocks, $((small_rss / 1024)) MB at one tenth (target < 64 MB, flat)"
rc=0
[ "$ok_rss" -lt $((64 * 1024)) ] || echo "41-okuma: TARGET MISSED: peak RSS >= 64 MB"
[ "$ok_rss" -le $((small_rss + 2048)) ] || echo "41-okuma: TARGET MISSED: peak RSS grows with program length"

have_rs274 || exit $rc
read -r ngc_cpu ngc_wall ngc_rss < <(measure_rs274 "$work/big/bench.ngc")
ngc_bps=$(per_s "$ngc_blocks" "$ngc_cpu")
echo "rs274 (LinuxCNC $(rs274_version)): $ngc_blocks NGC lines, same toolpath, in ${ngc_cpu} s CPU (${ngc_wall} s wall) = $ngc_bps blocks/s, peak RSS $((ngc_rss / 1024)) MB"
ratio=$(awk -v a="$ngc_cpu" -v b="$ok_cpu" -v na="$ngc_blocks" -v nb="$ok_blocks" \
  'BEGIN {printf "%.1f", (nb / (b > 0 ? b : 0.001)) / (na / (a > 0 ? a : 0.001))}')
echo "ratio: cell-interp (Okuma) is ${ratio}x rs274 in blocks/s on the same toolpath (target >= 10x)"
bench_figure interp.okuma.vs_rs274 "$ratio" higher
awk -v r="$ratio" 'BEGIN {exit !(r >= 10)}' || echo "41-okuma: TARGET MISSED: ratio ${ratio}x < 10x"
exit $rc
