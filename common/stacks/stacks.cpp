#include "cell/stacks/stacks.h"

#include <dirent.h>
#include <execinfo.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

namespace cell::stacks {
namespace {

// Only async-signal-safe work in the handler: backtrace (its unwinder loaded beforehand), write, and a
// lock-free atomic for the writer, which sends one signal at a time and waits for it.
std::atomic<int> g_fd{-1};  // -1: not asked (a late answer after the writer gave up writes nothing)
std::atomic<bool> g_done{false};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<int>::is_always_lock_free);

extern "C" void OnStackSignal(int) {
  const int fd = g_fd.load();
  if (fd < 0) return;
  const int saved = errno;
  void* frames[64];
  const int n = backtrace(frames, 64);
  backtrace_symbols_fd(frames, n, fd);
  g_done.store(true);
  errno = saved;
}

void WriteAll(int fd, const std::string& s) {
  std::size_t off = 0;
  while (off < s.size()) {
    const ssize_t w = write(fd, s.data() + off, s.size() - off);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return;
    off += static_cast<std::size_t>(w);
  }
}

std::string ThreadName(long tid) {
  const int fd = open(("/proc/self/task/" + std::to_string(tid) + "/comm").c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return "?";
  char buf[64];
  const ssize_t n = read(fd, buf, sizeof buf);
  close(fd);
  std::string s(buf, n > 0 ? static_cast<std::size_t>(n) : 0);
  while (!s.empty() && s.back() == '\n') s.pop_back();
  return s;
}

std::vector<long> Threads() {
  std::vector<long> tids;
  DIR* d = opendir("/proc/self/task");
  if (!d) return tids;
  while (dirent* e = readdir(d)) {
    char* end = nullptr;
    const long tid = std::strtol(e->d_name, &end, 10);
    if (end != e->d_name && *end == '\0') tids.push_back(tid);
  }
  closedir(d);
  return tids;
}

}  // namespace

void Prepare() {
  void* warm[1];
  backtrace(warm, 1);
}

long ThisThread() {
  return syscall(SYS_gettid);
}

bool WriteThreadStack(int fd, long tid) {
  Prepare();
  const int sig = SIGRTMIN + 5;
  // The handler stays installed afterwards (not asked, it does nothing): a thread that answers late must
  // not meet the signal's default action, which ends the process.
  struct sigaction sa {};
  sa.sa_handler = OnStackSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(sig, &sa, nullptr);
  WriteAll(fd, "thread " + std::to_string(tid) + " (" + ThreadName(tid) + "):\n");
  g_done.store(false);
  g_fd.store(fd);
  bool answered = false;
  if (syscall(SYS_tgkill, getpid(), tid, sig) == 0) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
    while (!g_done.load() && std::chrono::steady_clock::now() < until)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    answered = g_done.load();
  }
  g_fd.store(-1);
  if (!answered) WriteAll(fd, "  (no answer)\n");
  return answered;
}

int WriteThreadStacks(int fd) {
  const long self = ThisThread();
  int answered = 0;
  for (long tid : Threads()) {
    if (tid != self && WriteThreadStack(fd, tid)) ++answered;
  }
  return answered;
}

}  // namespace cell::stacks
