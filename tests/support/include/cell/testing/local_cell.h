// A local cell for multi-process tests: `cellctl up` on the test's domain (CELL_DOMAIN from CTest)
// with a private data dir, `cellctl` calls, and `cellctl down` (plus a kill of leftovers) at the end.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cell/testing/process.h"

namespace cell::testing {

// One process as `cellctl up` recorded it (cell-up.json).
struct RecordedProcess {
  std::string service;  // "cell-scheduler", "cell-interpreter/KT01"
  int pid = 0;
  std::uint64_t start_time = 0;  // as cell::proc::StartTime(pid) read it at the start; 0 if not recorded
  std::string log;               // its stdout and stderr
};

class LocalCell {
 public:
  // Starts nothing; call Up(). `prefix` names the temp data dir.
  explicit LocalCell(const std::string& prefix = "cell-test-");
  ~LocalCell();
  LocalCell(const LocalCell&) = delete;
  LocalCell& operator=(const LocalCell&) = delete;

  // An environment variable for cellctl and, through `cellctl up`, every process of the cell (CELL_DDS,
  // CELL_CONFIG_DIR, ...); set before Up().
  void SetEnv(const std::string& name, const std::string& value) { env_[name] = value; }
  // `cellctl up --stations S --clock C`; the result for the caller to assert on.
  RunResult Up(const std::string& stations = "KT01,KT02", const std::string& clock = "virtual",
               const std::vector<std::string>& more = {});
  RunResult Down();
  bool is_up() const { return up_; }  // Up succeeded and Down was not called
  RunResult Ctl(std::vector<std::string> args, std::chrono::seconds timeout = std::chrono::seconds(60)) const;
  // Runs a cellctl verb that must succeed and print JSON: a non-zero exit or output that is not JSON is a
  // test failure (reported here) and yields a null or discarded JSON value.
  nlohmann::json Json(std::vector<std::string> args) const;
  const std::string& data_dir() const { return data_; }
  const std::map<std::string, std::string>& env() const { return env_; }
  // The pids `cellctl up` recorded, by service id ("cell-scheduler", "cell-interpreter/KT01").
  std::map<std::string, int> Pids() const;
  std::vector<RecordedProcess> Record() const;

 private:
  std::string data_;
  std::map<std::string, std::string> env_;
  bool up_ = false;
};

}  // namespace cell::testing
