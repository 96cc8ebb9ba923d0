// inspection_export_bench: `cellctl inspect export` without the bus, on an inspection file of 10,000
// measurements (2,000 G27XY centres of 3 lines and 2,000 G26XY surfaces of 2): parse the text, export CSV or
// QIF, write it to /dev/null. Baseline in the same run: fprintf of 10,000 lines of one number each to
// /dev/null, the least a program writing those measurements does. deploy/bench.d/85-inspection-export.sh
// prints the figures and the ratios.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>

#include "cell/inspection/inspection_file.h"

using namespace cell::inspection;

namespace {

constexpr int kMeasurements = 10000;

const std::string& Text() {
  static const std::string text = [] {
    InspectionFile f;
    f.header = {"345879", "PUMP341", 10000, {2026, 11, 24, 9, 5}};
    for (int i = 0; i < 2000; ++i) {
      f.body.push_back(CentreXY(1000 + i, 2.135 + i * 1e-4, 5. + i * .01, 4. - i * .01));
      f.body.push_back(SurfaceXY(std::nullopt, -1. - i * 1e-3, 6.25 + i * 1e-3));
    }
    return Format(f);
  }();
  return text;
}

struct DevNull {
  FILE* f = std::fopen("/dev/null", "w");
  ~DevNull() { std::fclose(f); }
};

void BM_FprintfBaseline(benchmark::State& state) {
  DevNull out;
  for (auto _ : state) {
    for (int i = 0; i < kMeasurements; ++i) std::fprintf(out.f, "X CENTER = %.7f\n", 5. + i * .01);
    std::fflush(out.f);
  }
  state.SetItemsProcessed(state.iterations() * kMeasurements);
}

void BM_Parse(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(Parse(Text()));
  state.SetItemsProcessed(state.iterations() * kMeasurements);
}

template <bool kQif>
void BM_Export(benchmark::State& state) {
  DevNull out;
  std::size_t bytes = 0;
  for (auto _ : state) {
    InspectionFile f = Parse(Text());
    std::string s = kQif ? ToQif(f, LinearUnit::kInch, "KT01/PUMP341") : ToCsv(f, LinearUnit::kInch);
    std::fwrite(s.data(), 1, s.size(), out.f);
    std::fflush(out.f);
    bytes = s.size();
  }
  state.SetItemsProcessed(state.iterations() * kMeasurements);
  state.counters["out_bytes"] = static_cast<double>(bytes);
}

}  // namespace

BENCHMARK(BM_FprintfBaseline)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Parse)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Export, false)->Name("BM_CsvExport")->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Export, true)->Name("BM_QifExport")->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
