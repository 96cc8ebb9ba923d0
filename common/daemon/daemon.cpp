#include "cell/daemon/daemon.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>

#include "cell/error/error.h"
#include "cell/stacks/stacks.h"

namespace cell::daemon {
namespace {

// Signal handlers may only do async-signal-safe work: write the signal number into a pipe; the
// watcher thread does the rest.
int g_pipe[2] = {-1, -1};
std::atomic<bool> g_live{false};
constexpr unsigned char kQuit = 0;  // sent by ~Daemon to end the watcher

extern "C" void OnSignal(int sig) {
  int saved = errno;
  unsigned char b = static_cast<unsigned char>(sig);
  ssize_t n = write(g_pipe[1], &b, 1);
  (void)n;
  errno = saved;
}

// A supervisor that went away (e.g. a NOTIFY_SOCKET nobody listens on any more) must not flood the log:
// the first failure is a warning, later ones are debug lines.
std::atomic<bool> g_notify_warned{false};

// CELL_NOTIFY=ready: the NOTIFY_SOCKET is a `cellctl restart` waiting for READY=1 alone, gone once it has
// it; later messages (STATUS, STOPPING) would only fail into the log.
std::atomic<bool> g_notify_done{false};

bool Notify(const std::string& msg) {
  if (g_notify_done) return false;
  int r = sd_notify(0, msg.c_str());
  if (r < 0) {
    if (!g_notify_warned.exchange(true)) {
      spdlog::warn("sd_notify failed: {} (further failures are logged at debug level)", std::strerror(-r));
    } else {
      spdlog::debug("sd_notify failed: {}", std::strerror(-r));
    }
  }
  return r > 0;
}

}  // namespace

Daemon::Daemon() {
  if (g_live.exchange(true)) {
    throw Error(Errc::kFailedPrecondition, "cell::daemon::Daemon: only one instance per process");
  }
  if (pipe2(g_pipe, O_CLOEXEC) != 0) {
    g_live = false;
    throw Error(Errc::kInternal, std::string("cell::daemon::Daemon: pipe2: ") + std::strerror(errno));
  }
  main_ = stacks::ThisThread();
  stacks::Prepare();  // the unwinder loaded now, not in a signal handler
  watcher_ = std::thread([this] { Watch(); });
  struct sigaction sa {};
  sa.sa_handler = OnSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
  // A service writing to a closed socket or pipe gets EPIPE rather than dying.
  signal(SIGPIPE, SIG_IGN);

  uint64_t usec = 0;
  if (sd_watchdog_enabled(0, &usec) > 0 && usec > 0) watchdog_ = std::chrono::microseconds(usec);
}

Daemon::~Daemon() {
  signal(SIGTERM, SIG_DFL);
  signal(SIGINT, SIG_DFL);
  unsigned char b = kQuit;
  ssize_t n = write(g_pipe[1], &b, 1);
  (void)n;
  if (watcher_.joinable()) watcher_.join();
  close(g_pipe[0]);
  close(g_pipe[1]);
  g_pipe[0] = g_pipe[1] = -1;
  g_live = false;
}

void Daemon::Starting(std::string_view step) {
  std::lock_guard lock(start_mu_);
  step_ = step;
  step_since_ = std::chrono::steady_clock::now();
  step_warned_ = false;
}

void Daemon::WarnIfSlow() {
  {
    std::lock_guard lock(start_mu_);
    const auto lasted = std::chrono::steady_clock::now() - step_since_;
    if (ready_ || step_warned_ || lasted < kSlowStep) return;
    step_warned_ = true;
    spdlog::warn("still {} after {:.0f} s: not ready (its stack follows on stderr)", step_,
                 std::chrono::duration<double>(lasted).count());
  }
  spdlog::default_logger()->flush();
  static const char kHead[] = "the start-up's stack (main thread):\n";
  ssize_t w = write(2, kHead, sizeof kHead - 1);
  (void)w;
  stacks::WriteThreadStack(2, main_);
}

std::string Daemon::StartupNote() {
  std::lock_guard lock(start_mu_);
  if (ready_) return {};
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - step_since_).count();
  return fmt::format(" while {} ({:.1f} s, not ready)", step_, s);
}

void Daemon::Watch() {
  while (true) {
    // Wakes four times a second until ready, to say which start-up step is slow.
    pollfd pfd{g_pipe[0], POLLIN, 0};
    const int polled = poll(&pfd, 1, ready_ ? -1 : 250);
    if (polled == 0) {
      WarnIfSlow();
      continue;
    }
    if (polled < 0 && errno == EINTR) continue;
    unsigned char b = 0;
    ssize_t n = read(g_pipe[0], &b, 1);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0 || b == kQuit) return;
    int sig = b;
    if (StopRequested()) {
      // Second signal while stopping: the operator means it.
      spdlog::warn("{} again while stopping: exiting now", sigabbrev_np(sig) ? sigabbrev_np(sig) : "signal");
      spdlog::default_logger()->flush();
      _exit(128 + sig);
    }
    spdlog::info("SIG{} received{}: stopping", sigabbrev_np(sig) ? sigabbrev_np(sig) : "?", StartupNote());
    int expected = 0;
    stop_signal_.compare_exchange_strong(expected, sig);
    RequestStop();
  }
}

void Daemon::RequestStop() {
  {
    std::lock_guard lock(mu_);
    stop_.request_stop();
  }
  cv_.notify_all();
}

bool Daemon::WaitForStop(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mu_);
  cv_.wait_for(lock, timeout, [this] { return stop_.stop_requested(); });
  return stop_.stop_requested();
}

void Daemon::WaitForStop() {
  std::unique_lock lock(mu_);
  cv_.wait(lock, [this] { return stop_.stop_requested(); });
}

bool Daemon::NotifyReady(std::string_view status) {
  ready_ = true;
  const bool sent = Notify("READY=1\nSTATUS=" + std::string(status));
  if (const char* n = std::getenv("CELL_NOTIFY"); n && std::string_view(n) == "ready") g_notify_done = true;
  return sent;
}

bool Daemon::NotifyStatus(std::string_view status) {
  return Notify("STATUS=" + std::string(status));
}

bool Daemon::NotifyStopping(std::string_view status) {
  return Notify("STOPPING=1\nSTATUS=" + std::string(status));
}

std::chrono::milliseconds Daemon::TickInterval() const noexcept {
  if (!WatchdogEnabled()) return std::chrono::seconds(1);
  auto q = std::chrono::duration_cast<std::chrono::milliseconds>(watchdog_ / 4);
  return q.count() > 0 ? q : std::chrono::milliseconds(1);
}

bool Daemon::Tick() {
  if (!WatchdogEnabled()) return false;
  auto now = std::chrono::steady_clock::now();
  if (last_tick_ != std::chrono::steady_clock::time_point{} && now - last_tick_ < watchdog_ / 2) return false;
  last_tick_ = now;
  return Notify("WATCHDOG=1");
}

void Daemon::RunUntilStop(const std::function<bool()>& healthy) {
  bool was_healthy = true;
  while (!WaitForStop(TickInterval())) {
    bool ok = healthy();
    if (ok != was_healthy) {
      if (ok) {
        spdlog::info("health check passes again");
      } else {
        spdlog::error("health check failed: not feeding the watchdog");
      }
      was_healthy = ok;
    }
    if (ok) Tick();
  }
}

}  // namespace cell::daemon
