#!/usr/bin/env bash
# EMCO interpreter throughput against LinuxCNC's standalone RS-274/NGC interpreter (rs274), same run, same
# toolpath: one generator writes a 1,000,000-block EMCOTRONIC TM02 program (G01, G02, G03 in the ZX plane,
# a G25 subroutine call per group, G00) and the same toolpath as NGC (G18, X as a radius, an o-word sub
# called once per group), with the same number of blocks in each main program and the same mix of moves.
# Both write their canonical output to /dev/null. Figures: blocks/s of each (CPU time), the ratio (target
# >= 10x), and peak RSS of cell-interp for 100,000 and 1,000,000 blocks (flat: at most 2 MB more for ten
# times the blocks). Missed targets are printed as TARGET MISSED; the script fails only when a run fails.
# linuxcnc-uspace is installed when apt has it (lib/interp-bench.sh); nothing of LinuxCNC is kept in the tree.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BENCH=42-emco
# shellcheck source=lib/interp-bench.sh
source "$ROOT/deploy/bench.d/lib/interp-bench.sh"
bench_init

# gen EMCO|NGC BLOCKS > file: groups of 6 blocks in both main programs (EMCO X is a diameter, NGC X a radius;
# EMCO's I is already a radius, as NGC's G18 I). The subroutine follows the main program in the EMCO file
# (after its M30, as programs are read in one after another) and precedes it in the NGC file.
gen() {
  awk -v kind="$1" -v blocks="$2" 'BEGIN {
    groups = int((blocks - 4) / 6); if (groups < 1) groups = 1
    if (kind == "EMCO") {
      print "%"
      print "G94 G71 G00 X20. Z0 F800"
      for (g = 0; g < groups; g++) {
        a = 20 + (g % 97) * 0.1; b = -10 - (g % 89) * 0.05
        print "G01 X20. Z-10."
        print "G02 X40. Z-20. I10. K0"
        print "G03 X60. Z-30. I0 K-10."
        printf "G01 X%.3f Z%.3f\n", a, b
        print "G25 L8101"
        print "G00 X20. Z0"
      }
      print "M30"
      print "O0081"
      print "G00 U-1."
      print "G00 U1."
      print "M17"
    } else {
      print "%"
      print "o100 sub"
      print "G91 G00 X-1"
      print "G00 X1"
      print "G90"
      print "o100 endsub"
      print "G18 G21 G90 G94 G00 X10 Z0 F800"
      for (g = 0; g < groups; g++) {
        a = 20 + (g % 97) * 0.1; b = -10 - (g % 89) * 0.05
        print "G01 X10 Z-10"
        print "G02 X20 Z-20 I10 K0"
        print "G03 X30 Z-30 I0 K-10"
        printf "G01 X%.4f Z%.3f\n", a / 2, b
        print "o100 call"
        print "G00 X10 Z0"
      }
      print "M2"
      print "%"
    }
  }'
}

small=$((BLOCKS / 10))
gen EMCO "$BLOCKS" >"$work/bench.emco"
gen EMCO "$small" >"$work/small.emco"
gen NGC "$BLOCKS" >"$work/bench.ngc"
em_blocks=$(($(wc -l <"$work/bench.emco") - 5))   # the main program (the subroutine's 4 lines not counted)
ngc_blocks=$(($(wc -l <"$work/bench.ngc") - 7))   # the same: without the sub's definition and the % lines
moves=$("$INTERP" --dialect emco "$work/bench.emco" | grep -c '"op":"\(linear\|arc\|rapid\)"')

read -r em_cpu em_wall em_rss < <(measure em "$INTERP" --dialect emco "$work/bench.emco")
read -r _ _ small_rss < <(measure small "$INTERP" --dialect emco "$work/small.emco")
bench_figure interp.emco.peak_rss_mb "$((em_rss / 1024))" lower
em_bps=$(per_s "$em_blocks" "$em_cpu")
echo "cell-interp: $em_blocks EMCO blocks ($moves moves) in ${em_cpu} s CPU (${em_wall} s wall) = $em_bps blocks/s"
echo "cell-interp peak RSS: $((em_rss / 1024)) MB at $em_blocks blocks, $((small_rss / 1024)) MB at $((small_rss > 0 ? $(wc -l <"$work/small.emco") - 5 : 0)) blocks (flat: at most 2 MB more)"
[ "$em_rss" -le $((small_rss + 2048)) ] || echo "42-emco: TARGET MISSED: peak RSS grows with program length"

have_rs274 || exit 0
read -r ngc_cpu ngc_wall ngc_rss < <(measure_rs274 "$work/bench.ngc")
ngc_bps=$(per_s "$ngc_blocks" "$ngc_cpu")
echo "rs274 (LinuxCNC $(rs274_version)): $ngc_blocks NGC blocks, same toolpath, in ${ngc_cpu} s CPU (${ngc_wall} s wall) = $ngc_bps blocks/s, peak RSS $((ngc_rss / 1024)) MB"
ratio=$(awk -v a="$ngc_cpu" -v b="$em_cpu" 'BEGIN {printf "%.1f", a / (b > 0 ? b : 0.001)}')
echo "ratio: cell-interp (EMCO) is ${ratio}x rs274 on the same toolpath (target >= 10x)"
bench_figure interp.emco.vs_rs274 "$ratio" higher
awk -v r="$ratio" 'BEGIN {exit !(r >= 10)}' || echo "42-emco: TARGET MISSED: ratio ${ratio}x < 10x"
