#include "cell/testing/process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace cell::testing {

namespace {
int DecodeStatus(int st) {
  if (WIFEXITED(st)) return WEXITSTATUS(st);
  if (WIFSIGNALED(st)) return 128 + WTERMSIG(st);
  return -1;
}
}  // namespace

Process::Process(std::vector<std::string> argv, const std::map<std::string, std::string>& env,
                 const std::string& stdout_path, const std::string& stderr_path) {
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    setpgid(0, 0);
    for (auto& [k, v] : env) setenv(k.c_str(), v.c_str(), 1);
    if (!stdout_path.empty()) {
      int fd = open(stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) dup2(fd, 1);
    }
    if (!stderr_path.empty()) {
      int fd = open(stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) dup2(fd, 2);
    }
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    execv(args[0], args.data());
    std::fprintf(stderr, "exec %s: %s\n", args[0], std::strerror(errno));
    _exit(127);
  }
  setpgid(pid_, pid_);
}

Process::~Process() {
  if (pid_ > 0 && !status_) {
    kill(-pid_, SIGKILL);
    kill(pid_, SIGKILL);
    int st;
    waitpid(pid_, &st, 0);
  }
}

std::optional<int> Process::Wait(std::chrono::milliseconds timeout) {
  if (status_) return status_;
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    int st;
    pid_t r = waitpid(pid_, &st, WNOHANG);
    if (r == pid_) {
      status_ = DecodeStatus(st);
      return status_;
    }
    if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

void Process::Signal(int sig) {
  if (pid_ > 0 && !status_) kill(pid_, sig);
}

bool Process::Running() {
  return !Wait(std::chrono::milliseconds(0)).has_value();
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string MakeTempDir(const std::string& prefix) {
  std::string tmpl =
      (std::getenv("TMPDIR") ? std::string(std::getenv("TMPDIR")) : "/tmp") + "/" + prefix + "XXXXXX";
  if (!mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
  return tmpl;
}

ScopedTempDir::~ScopedTempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

RunResult RunCommand(std::vector<std::string> argv, const std::map<std::string, std::string>& env,
                     std::chrono::milliseconds timeout, const std::string& stdin_text) {
  std::string dir = MakeTempDir("cell-run-");
  std::map<std::string, std::string> e = env;
  std::string in_path = dir + "/stdin";
  { std::ofstream(in_path) << stdin_text; }
  // stdin from a file: commands under test never wait on the terminal.
  std::vector<std::string> sh = {"/bin/sh", "-c", "exec \"$0\" \"$@\" < " + in_path};
  sh.insert(sh.end(), argv.begin(), argv.end());
  Process p(sh, e, dir + "/out", dir + "/err");
  RunResult r;
  auto code = p.Wait(timeout);
  r.code = code ? *code : -1;
  r.out = ReadFile(dir + "/out");
  r.err = ReadFile(dir + "/err");
  std::string rm = "rm -rf '" + dir + "'";
  if (std::system(rm.c_str()) != 0) { /* best effort */
  }
  return r;
}

std::string BinDir() {
  const char* v = std::getenv("CELL_BIN_DIR");
  return v ? v : "build/bin";
}
std::string SourceDir() {
  const char* v = std::getenv("CELL_SOURCE_DIR");
  return v ? v : ".";
}

namespace {
// The NUL-separated fields of a /proc file.
std::vector<std::string> NulFields(const std::string& path) {
  std::vector<std::string> out;
  std::string text = ReadFile(path);
  for (size_t i = 0; i < text.size();) {
    size_t e = text.find('\0', i);
    out.push_back(text.substr(i, e - i));
    i = e == std::string::npos ? text.size() : e + 1;
  }
  return out;
}
}  // namespace

std::vector<std::string> ProcessArgv(int pid) {
  return NulFields("/proc/" + std::to_string(pid) + "/cmdline");
}

std::map<std::string, std::string> ProcessEnvironment(int pid) {
  std::map<std::string, std::string> env;
  for (auto& kv : NulFields("/proc/" + std::to_string(pid) + "/environ"))
    if (auto eq = kv.find('='); eq != std::string::npos) env[kv.substr(0, eq)] = kv.substr(eq + 1);
  return env;
}

}  // namespace cell::testing
