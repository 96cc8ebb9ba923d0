// A scripted fake cell for the scheduler library: programs in memory, stations that record what they are
// handed and report runs back, and a controllable clock. No DDS.
#pragma once

#include <gtest/gtest.h>

#include <stdlib.h>

#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cell/scheduler/scheduler.h"
#include "cell/tooltable/tooltable.h"

namespace cell::scheduler::testing {

// A KT/FMS program heading (KT-APL seed lines 4146-4150): %, NAM, UTL, UCY.
inline std::string FmsProgram(const std::string& name, const std::vector<std::string>& tools, int ucy) {
  std::string utl;
  for (const auto& t : tools) utl += (utl.empty() ? "" : ",") + t;
  std::string text = "%\n(NAM," + name + ")\n";
  if (!utl.empty()) text += "(UTL," + utl + ")\n";
  if (ucy >= 0) text += fmt::format("(UCY,{})\n", ucy);
  return text + "N10G71\nN20M30\n";
}

// A tool table with the given tool numbers in sockets 1, 2, ... (length 100, diameter 10).
inline tooltable::ToolTable Tools(const std::vector<std::string>& tools) {
  tooltable::ToolTable table;
  int socket = 1;
  for (const auto& t : tools) {
    table.Upsert(tooltable::ToolEntry{
        .tool = tooltable::NormalizeToolNumber(t), .socket = socket++, .length = 100, .diameter = 10});
  }
  return table;
}

// A scheduler database directory of its own, removed at the end.
class TempDir {
 public:
  TempDir() {
    // A process crash (kill -9) is what these tests simulate, not a power cut: tmpfs keeps them fast.
    const std::filesystem::path base = std::filesystem::is_directory("/dev/shm")
                                           ? std::filesystem::path("/dev/shm")
                                           : std::filesystem::temp_directory_path();
    std::string pattern = (base / "cell-sched-test-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string db() const { return (path_ / "scheduler.db").string(); }

 private:
  std::filesystem::path path_;
};

class FakeCell {
 public:
  explicit FakeCell(std::string db_path = {}) : db_path_(std::move(db_path)) { Open(); }

  // Simulates a scheduler restart on the same database (the old object is dropped without any shutdown).
  void Restart() {
    sched.reset();
    Open();
  }

  void Program(const std::string& name, const std::vector<std::string>& tools, int ucy) {
    programs.Put(name, FmsProgram(name, tools, ucy), "ktapl");
  }

  void Online(const std::string& id, const std::vector<std::string>& tools = {}) {
    Take(sched->StationOnline(id, "ktapl"));
    Take(sched->StationTools(id, Tools(tools)));
  }

  RouteView Route(const std::string& name, const std::vector<std::string>& ops) {
    RouteSpec spec{name, {}};
    for (const auto& op : ops) spec.ops.push_back(ParseOpSpec(op));
    return sched->DefineRoute("define-" + name + "-" + std::to_string(++counter_), spec);
  }

  std::int64_t Operate(const std::string& route, int pallet, std::string key = {}) {
    if (key.empty()) key = fmt::format("operate-{}-{}", route, ++counter_);
    JobResult r = sched->Operate(key, route, pallet);
    Take(r.effects);
    return r.job_id;
  }

  void Take(const Effects& fx) {
    for (const auto& d : fx.dispatches) {
      received[d.station].push_back(d);
      all.push_back(d);
    }
    for (const auto& c : fx.cancels) cancels.push_back(c);
    for (const auto& n : fx.notes) notes.push_back(n);
  }

  // The dispatch a station holds now (the last it was handed), failing the test if none.
  DispatchAction InHand(const std::string& station) {
    auto v = sched->Station(station);
    EXPECT_TRUE(v && v->in_hand != 0) << station << " holds no dispatch";
    for (const auto& d : all) {
      if (v && d.dispatch_id == v->in_hand) return d;
    }
    return {};
  }

  // The station runs its dispatch to the end: accepted, started, each program, finished.
  void Complete(std::int64_t dispatch_id, std::optional<double> cycle = std::nullopt) {
    Take(sched->DispatchAcknowledged(dispatch_id));
    Take(sched->RunStarted(dispatch_id));
    int n = 0;
    for (const auto& d : all) {
      if (d.dispatch_id == dispatch_id) n = static_cast<int>(d.programs.size());
    }
    for (int i = 0; i < n; ++i) Take(sched->ProgramFinished(dispatch_id, i));
    Take(sched->RunFinished(dispatch_id, cycle));
  }

  JobState State(std::int64_t job) { return sched->Job(job).value().state; }
  std::string Reason(std::int64_t job) { return sched->Job(job).value().reason; }
  std::string StationOf(std::int64_t job) { return sched->Job(job).value().station; }
  std::int64_t Backlog(const std::string& st) { return sched->Station(st).value().backlog_s; }

  MemoryProgramSource programs;
  std::unique_ptr<Scheduler> sched;
  std::map<std::string, std::vector<DispatchAction>> received;
  std::vector<DispatchAction> all;
  std::vector<CancelAction> cancels;
  std::vector<std::string> notes;
  std::int64_t now_ms = 1'795'000'000'000;             // 2026-11-18
  std::size_t kept_ended = Options{}.kept_ended_jobs;  // applied at the next Restart()

 private:
  void Open() {
    Options o;
    o.db_path = db_path_;
    o.kept_ended_jobs = kept_ended;
    o.clock = [this] { return std::chrono::system_clock::time_point(std::chrono::milliseconds(now_ms)); };
    sched = std::make_unique<Scheduler>(o, programs);
  }
  std::string db_path_;
  int counter_ = 0;
};

}  // namespace cell::scheduler::testing
