// Throughput of the KT-APL interpreter: a generated 1,000,000-block program (straight moves) and a
// parameter/loop-heavy program. The text is scanned block by block (the
// whole-process figures against rs274 are in deploy/bench.d/40-interpreter.sh).
#include <benchmark/benchmark.h>

#include <memory>
#include <string>

#include "cell/interp/interp.h"

namespace {

// Built once per benchmark and shared by every run (the text is not copied inside the timed loop).
std::shared_ptr<const cell::interp::ProgramText> StraightProgram(int blocks) {
  std::string text;
  text.reserve(static_cast<size_t>(blocks) * 26);
  text += "%\nN1 G0 G71 G90 X0 Y0 Z50. F0\nN2 G01 F500.\n";
  char buf[64];
  for (int i = 0; i < blocks; ++i) {
    std::snprintf(buf, sizeof buf, "N%d X%.3f Y%.3f\n", i + 3, (i % 1000) * 0.1, (i % 777) * 0.2);
    text += buf;
  }
  text += "M30\n";
  return cell::interp::ProgramText::FromString(std::move(text));
}

long RunAll(const std::shared_ptr<const cell::interp::ProgramText>& text) {
  cell::interp::RunOptions opt;
  opt.dialect = "ktapl";
  opt.program_name = "bench";
  opt.program = text;
  auto run = cell::interp::StartRun(opt);
  long n = 0;
  cell::interp::Step s;
  for (;;) {
    run->NextInto(s);
    if (s.kind != cell::interp::Step::kCanon) break;
    ++n;
  }
  return n;
}

void BM_MillionBlocks(benchmark::State& state) {
  auto text = StraightProgram(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(RunAll(text));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_MillionBlocks)->Arg(1000000)->Unit(benchmark::kMillisecond);

void BM_ParameterLoop(benchmark::State& state) {
  auto text = cell::interp::ProgramText::FromString(
      "G0 G90 F0 (PAR,L1=0)\n(LBL,1)(PAR,L1=L1+1.,L2=SIN(L1)*10.)\nXL2 Y,L1/100.\n"
      "(IFT,L1<" +
      std::to_string(state.range(0)) + ".,(GTO,1))\nM30\n");
  for (auto _ : state) benchmark::DoNotOptimize(RunAll(text));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_ParameterLoop)->Arg(100000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
