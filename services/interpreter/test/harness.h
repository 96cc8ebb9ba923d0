// A station core on a temporary database with the fakes of fakes.h, and helpers to feed it requests.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "fakes.h"

namespace cell::station::testing {

// A KT-APL program (metric): a rapid to X0 Y0 Z100, then n feed moves along X, M30: n + 2 segments.
inline std::string Moves(int n) {
  std::string p = "G71 G90\nG01 X0 Y0 Z100. F0\n";
  for (int i = 1; i <= n; ++i) p += "X" + std::to_string(i) + ". F1000.\n";
  return p + "M30\n";
}

class StationHarness : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("station-core-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    cfg_.id = "KT01";
    cfg_.dialect = "ktapl";
    cfg_.tools = {{"1001", 1, 152.4, 25.4, 240}, {"1002", 2, 171.45, 12.7, 180}};
    clock_.on_wait = [this] {
      servo_.Step();
      if (script_) script_();
    };
    Make();
  }
  void TearDown() override {
    station_.reset();
    std::filesystem::remove_all(dir_);
  }
  // A new core on the same database (a restarted process).
  void Make() {
    station_.reset();
    station_ = std::make_unique<Station>(cfg_, db(), io_, servo_, clock_, options_);
    servo_.Attach(station_.get());
    station_->Start();
  }
  std::filesystem::path db() const { return dir_ / "interpreter-KT01.db"; }

  void Put(const std::string& name, const std::string& text, const std::string& node = "KT01") {
    io_.programs[node + "/" + name] = text;
  }
  cell::RunRequest Request(std::int32_t dispatch, const std::vector<std::string>& programs, int pallet = 1,
                           int repeat = 1) {
    cell::RunRequest r;
    r.station(cfg_.id);
    r.dispatch_id(dispatch);
    r.job_id(100 + dispatch);
    r.pallet(pallet);
    for (const auto& p : programs) r.programs().push_back(p);
    r.repeat(repeat);
    return r;
  }
  cell::RunReply Dispatch(std::int32_t dispatch, const std::vector<std::string>& programs, int pallet = 1) {
    return station_->OnRun(Request(dispatch, programs, pallet));
  }
  cell::RunReply Cancel(std::int32_t dispatch) {
    auto r = Request(dispatch, {});
    r.cancel(true);
    return station_->OnRun(r);
  }
  cell::StationReply Command(cell::StationOp op, const std::string& text = "") {
    cell::StationRequest r;
    r.station("KT01");
    r.op(op);
    r.text(text);
    return station_->OnCommand(r);
  }
  cell::StationReply SetVariable(const std::string& name, double value) {
    return Assign(cell::STATION_SET_VARIABLES, name, value);
  }
  // The operator's discrete input (`cellctl station input`).
  cell::StationReply SetInput(const std::string& name, double value) {
    return Assign(cell::STATION_SET_INPUT, name, value);
  }
  // A command carrying one name=value.
  cell::StationReply Assign(cell::StationOp op, const std::string& name, double value) {
    cell::StationRequest r;
    r.station("KT01");
    r.op(op);
    cell::Variable v;
    v.name(name);
    v.value(value);
    r.variables().push_back(v);
    return station_->OnCommand(r);
  }
  // Runs the next dispatch to its end; its final run status.
  cell::RunStatus RunOne(std::int32_t dispatch) {
    EXPECT_TRUE(station_->RunNext());
    auto s = io_.LastRun(dispatch);
    EXPECT_TRUE(s.has_value()) << "no run status for dispatch " << dispatch;
    return s.value_or(cell::RunStatus{});
  }
  // Sets `flag` to `value` at the core's `waits`-th wait: a writer or a store that comes back while the run
  // waits for it.
  void SetAfter(int waits, bool& flag, bool value) {
    script_ = [&flag, value, waits, n = 0]() mutable {
      if (++n == waits) flag = value;
    };
  }
  std::map<std::string, double> Variables() const { return station_->MemoryState().image.variables; }
  const tooltable::ToolEntry* Tool(const std::string& t) const {
    tools_copy_ = station_->MemoryState().image.tools;
    return tools_copy_.Find(t);
  }

  std::filesystem::path dir_;
  config::StationConfig cfg_;
  StationOptions options_;
  FakeClock clock_;
  FakeServo servo_;
  FakeIo io_;
  std::function<void()> script_;  // runs in every wait of the core, after the servo's turn
  std::unique_ptr<Station> station_;
  mutable tooltable::ToolTable tools_copy_;
};

}  // namespace cell::station::testing
