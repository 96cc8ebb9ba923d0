// program_store_bench: library-level throughput of the program store (no DDS), with the sqlite3 CLI doing
// the same durable inserts as the baseline in the same run.
//
//   put_10k_2KB       10,000 puts of distinct 2 KB KT-APL programs, each its own committed transaction
//   put_20MB          one 20 MB program in a single Put
//   put_20MB_chunked  the same through BeginPut / 60 KB PutChunk (the DDS chunk size) / CommitPut
//   sqlite3_cli_*     the sqlite3 shell inserting the same rows into a bare table: WAL, synchronous=FULL,
//                     one BEGIN/COMMIT per program (skipped with a message when sqlite3 is not installed)
//
// After the run it prints the ratios store/CLI. CELL_BENCH_PROGRAMS overrides the 10,000 for quick runs.
// Not a test: run it by hand or via `./cell bench`.
#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "cell/program_store/program_store.h"

namespace {

namespace fs = std::filesystem;
using cell::program_store::ProgramStore;
using cell::program_store::PutRequest;
using cell::program_store::StoreOptions;

std::map<std::string, double> g_seconds;

StoreOptions Options(const fs::path& dir) {
  StoreOptions o;
  o.data_dir = dir;
  o.namespaces = {"KT01"};
  return o;
}  // benchmark family -> wall seconds of its last iteration

int ProgramCount() {
  const char* env = std::getenv("CELL_BENCH_PROGRAMS");
  return env != nullptr ? std::max(1, std::atoi(env)) : 10000;
}

fs::path FreshDir(const std::string& tag) {
  fs::path dir = fs::temp_directory_path() / fmt::format("cell-ps-bench-{}-{}", getpid(), tag);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// A KT-APL program of about `bytes` bytes, distinct per `seed`.
std::string Program(int seed, std::size_t bytes) {
  std::string s = fmt::format("%\n(NAM,P{})\n(UTL,{},{},{})\n(UCY,{})\n", seed, seed % 97 + 1,
                              seed % 13 + 100, seed % 7 + 2000, 60 + seed % 600);
  int n = 0;
  while (s.size() + 16 < bytes) {
    ++n;
    s += fmt::format("N{} G1 X{}.{:03} Y{}. F250\n", n * 10, (seed + n) % 500, n % 1000, n % 300);
  }
  s += "N99999 M30\n";
  return s;
}

std::string SqlQuote(const std::string& text) {
  std::string out = "'";
  for (char c : text) {
    out += c;
    if (c == '\'') out += '\'';
  }
  return out + "'";
}

bool HaveSqlite3() {
  return std::system("command -v sqlite3 >/dev/null 2>&1") == 0;
}

double TimeShell(const std::string& command) {
  auto start = std::chrono::steady_clock::now();
  int rc = std::system((command + " > /dev/null").c_str());
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (rc != 0) throw std::runtime_error("command failed: " + command);
  return seconds;
}

void Record(benchmark::State& state, const std::string& family, double seconds, double items, double bytes) {
  state.SetIterationTime(seconds);
  g_seconds[family] = seconds;
  state.counters["items_per_s"] = benchmark::Counter(items / seconds);
  state.counters["MB_per_s"] = benchmark::Counter(bytes / seconds / 1e6);
}

void BM_put_10k_2KB(benchmark::State& state) {
  const int count = ProgramCount();
  std::vector<std::string> programs;
  for (int i = 0; i < count; ++i) programs.push_back(Program(i, 2048));
  for (auto _ : state) {
    state.PauseTiming();
    fs::path dir = FreshDir("10k");
    auto store = std::make_unique<ProgramStore>(Options(dir));
    state.ResumeTiming();
    auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < count; ++i) {
      PutRequest r;
      r.node = "KT01";
      r.name = fmt::format("P{}", i);
      r.content = programs[static_cast<std::size_t>(i)];
      benchmark::DoNotOptimize(store->Put(r));
    }
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    Record(state, "10k", seconds, count, 2048.0 * count);
    store.reset();
    fs::remove_all(dir);
  }
}

const std::string& Big() {
  static const std::string big = Program(7, 20u << 20);
  return big;
}

void BM_put_20MB(benchmark::State& state) {
  for (auto _ : state) {
    fs::path dir = FreshDir("20mb");
    ProgramStore store(Options(dir));
    PutRequest r;
    r.name = "BIG";
    r.content = Big();
    auto start = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(store.Put(r));
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    Record(state, "20MB", seconds, 1, static_cast<double>(Big().size()));
    fs::remove_all(dir);
  }
}

void BM_put_20MB_chunked(benchmark::State& state) {
  const std::size_t chunk = 61440;  // ProgramRequest.data bound
  for (auto _ : state) {
    fs::path dir = FreshDir("20mbc");
    ProgramStore store(Options(dir));
    PutRequest r;
    r.name = "BIG";
    auto start = std::chrono::steady_clock::now();
    store.BeginPut("bench", r);
    std::uint32_t index = 0;
    for (std::size_t off = 0; off < Big().size(); off += chunk) {
      store.PutChunk("bench", index++, std::string_view(Big()).substr(off, chunk));
    }
    benchmark::DoNotOptimize(store.CommitPut("bench"));
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    Record(state, "20MB chunked", seconds, 1, static_cast<double>(Big().size()));
    fs::remove_all(dir);
  }
}

constexpr const char* kCliSetup =
    "PRAGMA journal_mode=WAL;\nPRAGMA synchronous=FULL;\n"
    "CREATE TABLE programs(name TEXT PRIMARY KEY, content BLOB NOT NULL);\n";

void BM_sqlite3_cli_10k_2KB(benchmark::State& state) {
  if (!HaveSqlite3()) {
    state.SkipWithError("sqlite3 CLI not found: baseline skipped (apt-get install sqlite3)");
    return;
  }
  const int count = ProgramCount();
  for (auto _ : state) {
    fs::path dir = FreshDir("cli10k");
    {
      std::ofstream script(dir / "insert.sql");
      script << kCliSetup;
      for (int i = 0; i < count; ++i) {
        script << "BEGIN;\nINSERT INTO programs VALUES ('P" << i << "', " << SqlQuote(Program(i, 2048))
               << ");\nCOMMIT;\n";
      }
    }
    double seconds = TimeShell(
        fmt::format("sqlite3 '{}' < '{}'", (dir / "cli.db").string(), (dir / "insert.sql").string()));
    Record(state, "10k cli", seconds, count, 2048.0 * count);
    fs::remove_all(dir);
  }
}

void BM_sqlite3_cli_20MB(benchmark::State& state) {
  if (!HaveSqlite3()) {
    state.SkipWithError("sqlite3 CLI not found: baseline skipped (apt-get install sqlite3)");
    return;
  }
  for (auto _ : state) {
    fs::path dir = FreshDir("cli20mb");
    {
      std::ofstream(dir / "big.nc", std::ios::binary) << Big();
      std::ofstream script(dir / "insert.sql");
      script << kCliSetup << "BEGIN;\nINSERT INTO programs VALUES ('BIG', readfile('"
             << (dir / "big.nc").string() << "'));\nCOMMIT;\n";
    }
    double seconds = TimeShell(
        fmt::format("sqlite3 '{}' < '{}'", (dir / "cli.db").string(), (dir / "insert.sql").string()));
    Record(state, "20MB cli", seconds, 1, static_cast<double>(Big().size()));
    fs::remove_all(dir);
  }
}

BENCHMARK(BM_put_10k_2KB)->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_sqlite3_cli_10k_2KB)->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_put_20MB)->Iterations(3)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_put_20MB_chunked)->Iterations(3)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_sqlite3_cli_20MB)->Iterations(3)->UseManualTime()->Unit(benchmark::kMillisecond);

void PrintRatio(const char* what, const std::string& store, const std::string& cli) {
  if (g_seconds.count(store) == 0) return;
  if (g_seconds.count(cli) == 0) {
    std::printf("%-34s store %.3f s; no sqlite3 CLI baseline (skipped)\n", what, g_seconds[store]);
    return;
  }
  std::printf("%-34s store %.3f s, sqlite3 CLI %.3f s, ratio store/CLI = %.2f\n", what, g_seconds[store],
              g_seconds[cli], g_seconds[store] / g_seconds[cli]);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  std::printf("\n");
  PrintRatio(fmt::format("{} x 2 KB puts:", ProgramCount()).c_str(), "10k", "10k cli");
  PrintRatio("1 x 20 MB put:", "20MB", "20MB cli");
  PrintRatio("1 x 20 MB put, 60 KB chunks:", "20MB chunked", "20MB cli");
  return 0;
}
