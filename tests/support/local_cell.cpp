#include "cell/testing/local_cell.h"

#include <signal.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "cell/proc/proc.h"

namespace cell::testing {

LocalCell::LocalCell(const std::string& prefix)
    // The dashboard on any free port: tests run side by side (it writes its address to dashboard.url).
    : data_(MakeTempDir(prefix)), env_{{"CELL_DATA_DIR", data_}, {"CELL_HTTP", "127.0.0.1:0"}} {}

LocalCell::~LocalCell() {
  if (up_) Down();
  // Whatever `down` could not stop, if the pid is still the process `cellctl` started: a pid whose process
  // ended may already belong to another test's cell.
  for (auto& p : Record())
    if (p.start_time != 0 && cell::proc::StartTime(p.pid) == p.start_time) kill(p.pid, SIGKILL);
  if (const char* keep = std::getenv("CELL_TEST_KEEP");
      keep && *keep) {  // logs and databases, for a post-mortem
    std::fprintf(stderr, "CELL_TEST_KEEP: kept %s\n", data_.c_str());
    return;
  }
  if (::testing::Test::HasFailure()) {
    // A failure under load may not come again: its logs and databases stay, and the scheduler's log's end
    // (where most of a cell's failures show) goes into the test's output, which is all a CI run keeps.
    std::fprintf(stderr, "the test failed: kept %s\n", data_.c_str());
    std::string log = ReadFile(data_ + "/logs/cell-scheduler.service.log");
    std::size_t at = log.size();
    for (int lines = 0; at > 0 && lines < 80; --at)
      if (log[at - 1] == '\n') ++lines;
    if (!log.empty()) std::fprintf(stderr, "cell-scheduler's log ends:\n%s\n", log.substr(at).c_str());
    return;
  }
  std::error_code ec;
  std::filesystem::remove_all(data_, ec);
}

RunResult LocalCell::Up(const std::string& stations, const std::string& clock,
                        const std::vector<std::string>& more) {
  std::vector<std::string> args{"up", "--stations", stations, "--clock", clock};
  args.insert(args.end(), more.begin(), more.end());
  // 60 s unless the test says: the product's 30 s is for release builds, and the gate runs sanitizer builds
  // (2-3x slower) two tests at a time on 2 cores, where one interpreter of a one-station secured cell once
  // took over 30 s to start (stop 58's CI). Its log now names the step a slow start is in.
  if (std::find(more.begin(), more.end(), "--timeout") == more.end())
    args.insert(args.end(), {"--timeout", "60"});
  // `up` bounds its own wait; this bound only catches a hang.
  RunResult r = Ctl(args, std::chrono::seconds(600));
  up_ = r.code == 0;
  if (!up_) {
    // What each service said before `up` gave up on it: a cell that did not come up under load in a full run
    // (issue 44) left nothing else to read once the test's data directory was gone.
    std::error_code ec;
    for (const auto& f : std::filesystem::directory_iterator(data_ + "/logs", ec)) {
      std::ifstream in(f.path());
      std::deque<std::string> tail;
      for (std::string line; std::getline(in, line);) {
        tail.push_back(line);
        if (tail.size() > 40) tail.pop_front();  // a slow start's stack (about 25 lines) fits
      }
      std::fprintf(stderr, "--- %s (last %zu lines)\n", f.path().filename().c_str(), tail.size());
      for (auto& line : tail) std::fprintf(stderr, "%s\n", line.c_str());
    }
  }
  return r;
}

RunResult LocalCell::Down() {
  up_ = false;
  return Ctl({"down"});
}

RunResult LocalCell::Ctl(std::vector<std::string> args, std::chrono::seconds timeout) const {
  args.insert(args.begin(), BinDir() + "/cellctl");
  return RunCommand(args, env_, timeout);
}

nlohmann::json LocalCell::Json(std::vector<std::string> args) const {
  RunResult r = Ctl(args);
  std::string what = "cellctl";
  for (auto& a : args) what += " " + a;
  EXPECT_EQ(r.code, 0) << what << ": " << r.err;
  if (r.code != 0) return nullptr;
  auto j = nlohmann::json::parse(r.out, nullptr, false);
  EXPECT_FALSE(j.is_discarded()) << what << " printed no JSON: " << r.out;
  return j;
}

std::vector<RecordedProcess> LocalCell::Record() const {
  std::vector<RecordedProcess> out;
  std::ifstream in(data_ + "/cell-up.json");
  if (!in) return out;
  auto j = nlohmann::json::parse(in, nullptr, false);
  if (!j.is_array()) return out;
  for (auto& p : j)
    out.push_back({p["service"].get<std::string>(), p["pid"].get<int>(),
                   p.value("start_time", std::uint64_t{0}), p.value("log", std::string())});
  return out;
}

std::map<std::string, int> LocalCell::Pids() const {
  std::map<std::string, int> out;
  for (auto& p : Record()) out[p.service] = p.pid;
  return out;
}

}  // namespace cell::testing
