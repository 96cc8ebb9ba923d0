#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace cell::testing {

// A child process in its own process group; the destructor SIGKILLs the group, so a failing
// test never leaves services running.
class Process {
 public:
  // argv[0] is a path. env entries are added to (or override) the test's environment.
  // stdout and stderr go to files (empty path: inherit).
  Process(std::vector<std::string> argv, const std::map<std::string, std::string>& env = {},
          const std::string& stdout_path = "", const std::string& stderr_path = "");
  ~Process();
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  pid_t pid() const { return pid_; }
  // Exit code (128+signal when killed), or nullopt when still running at the deadline.
  std::optional<int> Wait(std::chrono::milliseconds timeout);
  void Signal(int sig);
  bool Running();

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
};

// Runs a command to completion; returns {exit code, stdout, stderr}. (Not "Run": inside a gtest
// fixture that name is testing::Test::Run.)
struct RunResult {
  int code = -1;
  std::string out;
  std::string err;
};
RunResult RunCommand(std::vector<std::string> argv, const std::map<std::string, std::string>& env = {},
                     std::chrono::milliseconds timeout = std::chrono::seconds(60),
                     const std::string& stdin_text = "");

std::string ReadFile(const std::string& path);
// A running process's command line (/proc/PID/cmdline) and environment (/proc/PID/environ).
std::vector<std::string> ProcessArgv(int pid);
std::map<std::string, std::string> ProcessEnvironment(int pid);
std::string MakeTempDir(const std::string& prefix);
// MakeTempDir's directory, removed with what is in it when the object goes: a passing run leaves nothing.
class ScopedTempDir {
 public:
  explicit ScopedTempDir(const std::string& prefix) : path_(MakeTempDir(prefix)) {}
  ~ScopedTempDir();
  ScopedTempDir(const ScopedTempDir&) = delete;
  ScopedTempDir& operator=(const ScopedTempDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};
std::string BinDir();     // CELL_BIN_DIR (set by CTest)
std::string SourceDir();  // CELL_SOURCE_DIR

}  // namespace cell::testing
