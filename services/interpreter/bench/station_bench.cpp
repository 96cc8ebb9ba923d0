// What keeping a program's changes costs: the one transaction a station commits after each program (tool
// table, kept variables, the run's progress), against a transaction that writes one row of the same database
// (the baseline: the fsync of a commit, WAL and synchronous=FULL), for KT01's table and for the largest table
// the topics carry.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>

#include "cell/station/station_db.h"
#include "cell/store/sqlite.h"

namespace {

std::filesystem::path Db(const char* name) {
  auto p = std::filesystem::temp_directory_path() /
           (std::string("station-bench-") + name + "-" + std::to_string(::getpid()) + ".db");
  std::filesystem::remove(p);
  return p;
}

cell::station::MemoryImage Image(int tools, int variables) {
  std::vector<cell::tooltable::ToolEntry> entries;
  std::vector<cell::tooltable::ProcessComp> process;
  for (int i = 0; i < tools; ++i) {
    cell::tooltable::ToolEntry e;
    e.tool = std::to_string(1000 + i);
    e.socket = i % 60 + 1;
    e.length = 100.0 + i;
    e.diameter = 10.0 + i % 7;
    e.life_left_min = 120;
    entries.push_back(e);
    if (tools > 10) process.push_back({e.tool, i % 255 + 1, 0.5, 0.1});
  }
  cell::station::MemoryImage m{cell::tooltable::ToolTable(std::move(entries), std::move(process)), {}};
  for (int i = 0; i < variables; ++i) m.variables["L" + std::to_string(1000 + i)] = i * 0.5;
  return m;
}

void BM_OneRowCommit(benchmark::State& state) {
  auto path = Db("row");
  { cell::station::StationDb create(path); }
  auto db = cell::store::Database::Open(path);
  auto st = db.Prepare("INSERT OR REPLACE INTO variables(name, value) VALUES('L1500', ?)");
  int n = 0;
  for (auto _ : state) {
    cell::store::Transaction tx(db);
    st.BindDouble(1, ++n);
    st.Run();
    st.Reset();
    tx.Commit();
  }
  std::filesystem::remove(path);
}

void BM_CommitMemory(benchmark::State& state) {
  auto path = Db("memory");
  cell::station::StationDb db(path);
  auto image = Image(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  cell::station::RunProgress progress;
  progress.dispatch_id = 1;
  int n = 0;
  for (auto _ : state) {
    image.variables["L1500"] = ++n;
    progress.programs_done = n;
    db.SaveMemory(image, &progress);
  }
  std::filesystem::remove(path);
}

}  // namespace

BENCHMARK(BM_OneRowCommit)->Unit(benchmark::kMicrosecond)->UseRealTime();
// KT01's five config tools and a dozen parameters; the topic's bounds (512 data sets, 2048 variables).
BENCHMARK(BM_CommitMemory)->Args({5, 12})->Args({512, 2000})->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK_MAIN();
