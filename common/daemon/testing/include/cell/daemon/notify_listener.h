// Test support: play systemd's part of the sd_notify protocol. A NotifyListener owns a unix datagram
// socket in a private temporary directory; a child started with Spawn() gets NOTIFY_SOCKET pointing at
// it (and whatever else the test adds, e.g. WATCHDOG_USEC), so the test sees every READY=1, WATCHDOG=1,
// STATUS= and STOPPING=1 the child sends.
#pragma once

#include <poll.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace cell::daemon::testing {

class NotifyListener {
 public:
  NotifyListener() {
    char tmpl[] = "/tmp/cell-notify-XXXXXX";
    if (mkdtemp(tmpl) == nullptr) throw std::runtime_error("mkdtemp failed");
    dir_ = tmpl;
    path_ = dir_ / "notify.sock";
    fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) throw std::runtime_error("socket failed");
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path_.c_str(), sizeof(addr.sun_path) - 1);
    if (bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      throw std::runtime_error(std::string("bind failed: ") + std::strerror(errno));
    }
  }
  ~NotifyListener() {
    close(fd_);
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  NotifyListener(const NotifyListener&) = delete;
  NotifyListener& operator=(const NotifyListener&) = delete;

  const std::filesystem::path& path() const { return path_; }

  // The next datagram, or nullopt after `timeout`.
  std::optional<std::string> Receive(std::chrono::milliseconds timeout) {
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, static_cast<int>(timeout.count())) <= 0) return std::nullopt;
    char buf[4096];
    ssize_t n = recv(fd_, buf, sizeof buf, 0);
    if (n < 0) return std::nullopt;
    return std::string(buf, static_cast<size_t>(n));
  }

  // Receives until a datagram contains `line` as one of its lines (e.g. "READY=1"); every datagram seen
  // is appended to `seen`. Returns false on timeout.
  bool WaitFor(const std::string& line, std::chrono::milliseconds timeout, std::vector<std::string>& seen) {
    auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
      auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return false;
      auto msg = Receive(left);
      if (!msg) return false;
      seen.push_back(*msg);
      if (HasLine(*msg, line)) return true;
    }
  }

  static bool HasLine(const std::string& msg, const std::string& line) {
    size_t pos = 0;
    while (pos <= msg.size()) {
      size_t end = msg.find('\n', pos);
      if (end == std::string::npos) end = msg.size();
      if (msg.compare(pos, end - pos, line) == 0) return true;
      pos = end + 1;
    }
    return false;
  }

 private:
  std::filesystem::path dir_;
  std::filesystem::path path_;
  int fd_ = -1;
};

// Starts argv with the extra environment (NAME -> value; an empty value unsets NAME); WATCHDOG_PID, if
// given as "self", is set to the child's own pid as systemd does. Returns the pid.
inline pid_t Spawn(const std::vector<std::string>& argv, const std::map<std::string, std::string>& env) {
  pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    for (const auto& [k, v] : env) {
      if (v.empty()) {
        unsetenv(k.c_str());
      } else if (k == "WATCHDOG_PID" && v == "self") {
        setenv(k.c_str(), std::to_string(getpid()).c_str(), 1);
      } else {
        setenv(k.c_str(), v.c_str(), 1);
      }
    }
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  return pid;
}

// Waits for pid up to `timeout`; returns the wait status, or nullopt (after SIGKILL) on timeout.
inline std::optional<int> WaitExit(pid_t pid, std::chrono::milliseconds timeout) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    int status = 0;
    pid_t r = waitpid(pid, &status, WNOHANG);
    if (r == pid) return status;
    usleep(10000);
  }
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  return std::nullopt;
}

}  // namespace cell::daemon::testing
