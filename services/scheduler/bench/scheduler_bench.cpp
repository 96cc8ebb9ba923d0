// Allocation decisions at library level (issue 7 item 9): 10,000 pallet operations over 100 stations whose
// tool tables hold 200 tools each. Floor: 100,000 decisions per second on the 2-core development machine.
//
//   BM_Allocate                the OPERATE rule alone (eligibility by tool table + shortest backlog)
//   BM_SchedulerOperate        the whole in-memory path: job, decision log, dispatch, queues, completions
//   BM_SchedulerOperateDurable the same with every decision committed to SQLite (synchronous=FULL)
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cell/scheduler/allocator.h"
#include "cell/scheduler/scheduler.h"

namespace cell::scheduler {
namespace {

constexpr int kStations = 100;
constexpr int kToolsPerStation = 200;
constexpr int kPallets = 10000;
constexpr double kFloor = 100000.0;

// 150 tools every station carries plus 50 of a pool of 500 specials; an operation needs 6 common tools and
// 2 specials, so on average a handful of the stations is eligible and the rest are logged with missing tools.
struct Cell {
  std::vector<tooltable::ToolTable> tables;
  std::vector<std::vector<std::string>> op_tools;  // per pallet operation
  explicit Cell(unsigned seed) {
    std::mt19937 rng(seed);
    for (int s = 0; s < kStations; ++s) {
      std::vector<tooltable::ToolEntry> entries;
      for (int t = 0; t < 150; ++t) entries.push_back({.tool = std::to_string(1000 + t), .socket = t + 1});
      std::vector<int> specials(500);
      for (int i = 0; i < 500; ++i) specials[static_cast<std::size_t>(i)] = 5000 + i;
      std::shuffle(specials.begin(), specials.end(), rng);
      for (int t = 0; t < kToolsPerStation - 150; ++t) {
        entries.push_back({.tool = std::to_string(specials[static_cast<std::size_t>(t)]), .socket = 151 + t});
      }
      tables.emplace_back(std::move(entries));
    }
    std::uniform_int_distribution<int> common(1000, 1149), special(5000, 5499);
    for (int p = 0; p < kPallets; ++p) {
      std::vector<std::string> tools;
      for (int i = 0; i < 6; ++i) tools.push_back(std::to_string(common(rng)));
      for (int i = 0; i < 2; ++i) tools.push_back(std::to_string(special(rng)));
      op_tools.push_back(std::move(tools));
    }
  }
};

const Cell& TheCell() {
  static const Cell cell(7);
  return cell;
}

void Counters(benchmark::State& state, std::int64_t decisions) {
  state.SetItemsProcessed(decisions);
  state.counters["decisions"] = static_cast<double>(decisions);
  state.counters["decisions_per_s"] =
      benchmark::Counter(static_cast<double>(decisions), benchmark::Counter::kIsRate);
  state.counters["ratio_vs_floor"] =
      benchmark::Counter(static_cast<double>(decisions) / kFloor, benchmark::Counter::kIsRate);
}

void BM_Allocate(benchmark::State& state) {
  const Cell& cell = TheCell();
  ToolIndex index;
  std::vector<StationState> stations(kStations);
  for (int s = 0; s < kStations; ++s) {
    stations[static_cast<std::size_t>(s)].online = true;
    stations[static_cast<std::size_t>(s)].SetTools(cell.tables[static_cast<std::size_t>(s)], index);
  }
  std::vector<int> listed(kStations);
  for (int s = 0; s < kStations; ++s) listed[static_cast<std::size_t>(s)] = s;
  std::vector<std::vector<int>> ops;
  for (const auto& tools : cell.op_tools) {
    std::vector<int> ids;
    for (const auto& t : tools) ids.push_back(index.Intern(t));
    ops.push_back(std::move(ids));
  }
  AllocationRec rec;
  std::int64_t decisions = 0, waited = 0;
  for (auto _ : state) {
    for (auto& st : stations) st.backlog_s = 0;
    for (const auto& op : ops) {
      Allocate(listed, op, stations, rec);
      if (rec.winner >= 0)
        stations[static_cast<std::size_t>(rec.winner)].backlog_s += 300;
      else
        ++waited;
      ++decisions;
    }
    benchmark::DoNotOptimize(rec.winner);
  }
  Counters(state, decisions);
  state.counters["waiting_share"] = static_cast<double>(waited) / static_cast<double>(decisions);
}

// One route per pallet operation is too many; the benchmark defines 100 routes (families) and cycles pallets
// 1-250 through them. Between batches of 250 (untimed) the stations finish every visit they hold and pallets
// that found no eligible station are cancelled, so that the pallet numbers are free again. Timed: the 10,000
// OPERATE calls, each a complete decision (job, allocation over 100 stations, decision log, dispatch or
// wait).
void RunScheduler(benchmark::State& state, bool durable, int pallets) {
  const Cell& cell = TheCell();
  std::int64_t decisions = 0;
  for (auto _ : state) {
    state.PauseTiming();
    MemoryProgramSource progs;
    std::vector<std::string> stations;
    for (int s = 0; s < kStations; ++s) stations.push_back(fmt::format("KT{:03}", s + 1));
    Options o;
    const std::string db = (std::filesystem::temp_directory_path() / "cell-scheduler-bench.db").string();
    if (durable) {
      std::filesystem::remove(db);
      std::filesystem::remove(db + "-wal");
      std::filesystem::remove(db + "-shm");
      o.db_path = db;
    }
    auto s = std::make_unique<Scheduler>(o, progs);
    for (int i = 0; i < kStations; ++i) {
      s->StationOnline(stations[static_cast<std::size_t>(i)], "ktapl");
      s->StationTools(stations[static_cast<std::size_t>(i)], cell.tables[static_cast<std::size_t>(i)]);
    }
    constexpr int kRoutes = 100;
    for (int r = 0; r < kRoutes; ++r) {
      std::string utl;
      for (const auto& t : cell.op_tools[static_cast<std::size_t>(r)]) utl += (utl.empty() ? "" : ",") + t;
      progs.Put(fmt::format("P{}", r), fmt::format("%\n(UTL,{})\n(UCY,300)\nN10M30\n", utl), "ktapl");
      OpSpec op{stations, {fmt::format("P{}", r)}};
      s->DefineRoute(fmt::format("define-{}", r), RouteSpec{fmt::format("R{}", r), {op}});
    }
    state.ResumeTiming();
    std::vector<std::int64_t> in_hand, batch_jobs;
    for (int p = 0; p < pallets; ++p) {
      const int pallet = p % 250 + 1;
      JobResult jr = s->Operate(fmt::format("op-{}", p), fmt::format("R{}", p % kRoutes), pallet);
      ++decisions;
      batch_jobs.push_back(jr.job_id);
      for (const auto& d : jr.effects.dispatches) in_hand.push_back(d.dispatch_id);
      if (pallet == 250 || p + 1 == pallets) {
        state.PauseTiming();  // not decisions: the cell's side of the batch
        // Batch end: the stations run everything they hold (and what their queues hand them next).
        while (!in_hand.empty()) {
          const auto id = in_hand.back();
          in_hand.pop_back();
          Effects fx = s->RunFinished(id, 300.0);
          for (const auto& d : fx.dispatches) in_hand.push_back(d.dispatch_id);
        }
        // Pallets still waiting (no eligible station) are cancelled so their numbers are free again.
        for (std::int64_t id : batch_jobs) {
          if (!IsTerminal(s->Job(id, false)->state)) s->Cancel(fmt::format("cancel-{}", id), id);
        }
        batch_jobs.clear();
        state.ResumeTiming();
      }
    }
    state.PauseTiming();
    s.reset();
    state.ResumeTiming();
  }
  Counters(state, decisions);
}

void BM_SchedulerOperate(benchmark::State& state) {
  RunScheduler(state, false, kPallets);
}
void BM_SchedulerOperateDurable(benchmark::State& state) {
  RunScheduler(state, true, 500);
}

BENCHMARK(BM_Allocate)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_SchedulerOperate)->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK(BM_SchedulerOperateDurable)->Unit(benchmark::kMillisecond)->Iterations(1);

// After the table: one line per benchmark with decisions per second of CPU time and of wall time (the machine
// is shared, so wall time includes waiting for a core) and the ratio against the floor.
class Summary : public benchmark::ConsoleReporter {
 public:
  Summary() : ConsoleReporter(OO_Tabular) {}
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const auto& r : runs) {
      auto it = r.counters.find("decisions");
      if (it == r.counters.end() || r.cpu_accumulated_time <= 0) continue;
      const double cpu = it->second.value / r.cpu_accumulated_time;
      const double wall = it->second.value / r.real_accumulated_time;
      lines_.push_back(fmt::format(
          "{:<28} {:>12.0f} decisions/s CPU ({:.2f}x the {:.0f}/s floor), {:>12.0f}/s wall ({:.2f}x)",
          r.run_name.function_name, cpu, cpu / kFloor, kFloor, wall, wall / kFloor));
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    std::printf("\n%d stations, %d tools per station, %d pallet operations per run\n", kStations,
                kToolsPerStation, kPallets);
    for (const auto& l : lines_) std::printf("%s\n", l.c_str());
  }

 private:
  std::vector<std::string> lines_;
};

}  // namespace
}  // namespace cell::scheduler

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  cell::scheduler::Summary summary;
  benchmark::RunSpecifiedBenchmarks(&summary);
  benchmark::Shutdown();
  return 0;
}
