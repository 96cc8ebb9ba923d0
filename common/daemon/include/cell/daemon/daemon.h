// The life cycle every cell service shares under systemd (Type=notify, WatchdogSec=) and under
// `cellctl up`: stop on SIGTERM/SIGINT, report readiness, prove liveness from the main loop, report
// stopping.
//
//   int main(int argc, char** argv) {
//     cell::log::Init("cell-scheduler");
//     cell::daemon::Daemon daemon;           // early: SIGTERM from now on requests a stop
//     Scheduler s(...);                       // open the database, join the bus, wait for matches
//     daemon.NotifyReady("scheduling; 4 stations");
//     daemon.RunUntilStop([&] { return s.Healthy(); });   // or your own loop, see below
//     daemon.NotifyStopping();
//     s.Shutdown();
//     return 0;
//   }
//
// Own loop: `while (!daemon.WaitForStop(daemon.TickInterval())) { if (healthy) daemon.Tick(); }`.
// Threads that block elsewhere can watch `daemon.StopToken()` (std::stop_callback) instead of polling.
//
// Watchdog: when systemd sets WATCHDOG_USEC (and WATCHDOG_PID, if set, is this process), Tick() sends
// WATCHDOG=1 at most every half interval. Nothing sends it behind the main loop's back: a wedged or
// unhealthy main loop stops ticking and systemd restarts the service (Restart=on-failure).
// Without NOTIFY_SOCKET (a shell, a test) every Notify* call is a no-op.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <stop_token>
#include <string>
#include <string_view>
#include <thread>

namespace cell::daemon {

class Daemon {
 public:
  // Installs SIGTERM and SIGINT handlers (a second signal while stopping exits at once with 128+signal)
  // and reads the watchdog settings. One Daemon per process: a second live instance throws
  // cell::Error(kFailedPrecondition).
  Daemon();
  // Restores the default signal dispositions.
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  // --- stop ---
  bool StopRequested() const noexcept { return stop_.stop_requested(); }
  std::stop_token StopToken() const noexcept { return stop_.get_token(); }
  // Blocks until a stop is requested or `timeout` passes; returns StopRequested().
  bool WaitForStop(std::chrono::milliseconds timeout);
  // Blocks until a stop is requested.
  void WaitForStop();
  // Requests a stop from code (e.g. a fatal error in a worker thread).
  void RequestStop();
  // The signal that requested the stop (SIGTERM, SIGINT), 0 if none.
  int StopSignal() const noexcept { return stop_signal_.load(); }

  // --- start-up ---
  // The step the start-up is in (e.g. "joining the bus"), until NotifyReady. A start that hangs says where:
  // once a step has lasted kSlowStep the watcher logs a warning and the main thread's stack to stderr
  // (cell_stacks; the Daemon must be made on the main thread); a stop signal before ready names the step
  // and how long it has lasted. A cell that "did not come up" then shows the call that never returned.
  void Starting(std::string_view step);
  static constexpr std::chrono::seconds kSlowStep{10};

  // --- sd_notify ---
  // READY=1 and STATUS=<status>; the start-up is over. Returns false when there is no NOTIFY_SOCKET or
  // sending failed.
  bool NotifyReady(std::string_view status);
  // STATUS=<status> (shown by systemctl status).
  bool NotifyStatus(std::string_view status);
  // STOPPING=1 and STATUS=<status>.
  bool NotifyStopping(std::string_view status = "stopping");

  // --- watchdog ---
  bool WatchdogEnabled() const noexcept { return watchdog_.count() > 0; }
  // The interval systemd expects (WATCHDOG_USEC), zero when disabled.
  std::chrono::microseconds WatchdogInterval() const noexcept { return watchdog_; }
  // How long the main loop may sleep between Tick() calls: a quarter of the watchdog interval (so a
  // tick goes out every half to three quarters of it), 1 s without a watchdog.
  std::chrono::milliseconds TickInterval() const noexcept;
  // The main loop is alive and healthy: sends WATCHDOG=1 if half the interval has passed since the last
  // one. Cheap; call it every loop iteration, from one thread (the main loop). Returns true when a
  // message was sent.
  bool Tick();

  // Loop until stopped: every TickInterval() calls `healthy` and Tick()s only when it returns true. A
  // health check that fails is logged (once per change) at error level, and the watchdog lapses.
  void RunUntilStop(const std::function<bool()>& healthy);

 private:
  void Watch();  // signal watcher thread body
  // Once per step that has lasted kSlowStep before ready: a warning, and the main thread's stack.
  void WarnIfSlow();
  // " while <step> (N s, not ready)" before NotifyReady, else empty: said with a stop signal.
  std::string StartupNote();

  std::stop_source stop_;
  std::atomic<int> stop_signal_{0};
  std::mutex mu_;
  std::condition_variable cv_;
  std::chrono::microseconds watchdog_{0};
  std::chrono::steady_clock::time_point last_tick_{};
  std::thread watcher_;
  long main_ = 0;  // the kernel id of the thread that made the Daemon: the one whose start-up steps these are
  std::atomic<bool> ready_{false};
  std::mutex start_mu_;  // guards the three below
  std::string step_ = "starting";
  std::chrono::steady_clock::time_point step_since_ = std::chrono::steady_clock::now();
  bool step_warned_ = false;
};

}  // namespace cell::daemon
