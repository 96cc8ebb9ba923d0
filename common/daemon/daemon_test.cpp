#include "cell/daemon/daemon.h"

#include <gtest/gtest.h>
#include <signal.h>

#include <cstdio>

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>

#include "cell/daemon/notify_listener.h"
#include "cell/error/error.h"

using namespace std::chrono_literals;
using cell::daemon::testing::NotifyListener;
using cell::daemon::testing::Spawn;
using cell::daemon::testing::WaitExit;

namespace {

int CountLine(const std::vector<std::string>& msgs, const std::string& line) {
  int n = 0;
  for (const auto& m : msgs) n += NotifyListener::HasLine(m, line) ? 1 : 0;
  return n;
}

// Everything the child sends within `window`.
std::vector<std::string> Collect(NotifyListener& l, std::chrono::milliseconds window) {
  std::vector<std::string> out;
  auto deadline = std::chrono::steady_clock::now() + window;
  while (true) {
    auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    if (auto m = l.Receive(left)) out.push_back(*m);
  }
  return out;
}

TEST(DaemonInProcess, SignalStopsWaiterAndToken) {
  unsetenv("NOTIFY_SOCKET");
  unsetenv("WATCHDOG_USEC");
  cell::daemon::Daemon d;
  EXPECT_THROW(cell::daemon::Daemon second, cell::Error);
  EXPECT_FALSE(d.WatchdogEnabled());
  EXPECT_EQ(d.TickInterval(), 1s);
  EXPECT_FALSE(d.Tick());
  EXPECT_FALSE(d.NotifyReady("no socket: no-op"));
  std::atomic<bool> called{false};
  std::stop_callback cb(d.StopToken(), [&] { called = true; });
  EXPECT_FALSE(d.WaitForStop(20ms));
  EXPECT_FALSE(d.StopRequested());
  raise(SIGTERM);
  EXPECT_TRUE(d.WaitForStop(5s));
  EXPECT_TRUE(d.StopRequested());
  EXPECT_TRUE(called);
  EXPECT_EQ(d.StopSignal(), SIGTERM);
}

TEST(DaemonInProcess, RequestStopFromCode) {
  cell::daemon::Daemon d;  // the previous instance is gone: allowed again
  std::thread t([&] {
    std::this_thread::sleep_for(50ms);
    d.RequestStop();
  });
  d.WaitForStop();
  t.join();
  EXPECT_TRUE(d.StopRequested());
  EXPECT_EQ(d.StopSignal(), 0);
}

// What the Daemon logs on a SIGTERM during the start-up step "joining the bus", after NotifyReady if `ready`.
std::string SaidOnSigterm(bool ready) {
  auto sink = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(16);
  auto before = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("daemon-test", sink));
  std::string said;
  {
    cell::daemon::Daemon d;
    d.Starting("joining the bus");
    if (ready) d.NotifyReady("ready");
    raise(SIGTERM);
    EXPECT_TRUE(d.WaitForStop(5s));
    for (auto& line : sink->last_formatted()) said += line;  // the watcher logs, then requests the stop
  }
  spdlog::set_default_logger(before);
  return said;
}

// A start that hangs says where (the CI's "cell did not come up" of an interpreter that logged nothing).
TEST(DaemonInProcess, AStopBeforeReadyNamesTheStartupStep) {
  const std::string said = SaidOnSigterm(false);
  EXPECT_NE(said.find("SIGTERM received while joining the bus ("), std::string::npos) << said;
  EXPECT_NE(said.find(" s, not ready): stopping"), std::string::npos) << said;
}

TEST(DaemonInProcess, AStopAfterReadySaysOnlyStopping) {
  const std::string said = SaidOnSigterm(true);
  EXPECT_NE(said.find("SIGTERM received: stopping"), std::string::npos) << said;
}

// A step that lasts kSlowStep is named in a warning, and the main thread's stack shows where it waits
// (the probe sleeps in its start-up).
TEST(DaemonProbe, ASlowStartupStepShowsItsStack) {
  // Ready 1.5 s after the step reaches kSlowStep: the watcher wakes every 250 ms, a sanitizer build is slow.
  const std::string cmd = std::string("timeout -s TERM 14 ") + CELL_DAEMON_PROBE + " --startup-ms 11500 2>&1";
  FILE* f = popen(cmd.c_str(), "r");
  ASSERT_NE(f, nullptr);
  std::string out;
  char buf[4096];
  for (size_t n; (n = fread(buf, 1, sizeof buf, f)) > 0;) out.append(buf, n);
  pclose(f);
  EXPECT_NE(out.find("still starting after 10 s: not ready"), std::string::npos) << out;
  const auto stack = out.find("the start-up's stack (main thread):");
  ASSERT_NE(stack, std::string::npos) << out;
  EXPECT_NE(out.find("nanosleep", stack), std::string::npos) << out;
  EXPECT_LT(stack, out.find("ready; watchdog")) << out;  // before ready, once
  EXPECT_EQ(out.find("the start-up's stack", stack + 1), std::string::npos) << out;
}

TEST(DaemonProbe, ReadyWatchdogStopping) {
  NotifyListener l;
  pid_t pid =
      Spawn({CELL_DAEMON_PROBE, "--station", "KT01"},
            {{"NOTIFY_SOCKET", l.path().string()}, {"WATCHDOG_USEC", "200000"}, {"WATCHDOG_PID", "self"}});
  std::vector<std::string> seen;
  ASSERT_TRUE(l.WaitFor("READY=1", 10s, seen)) << "no READY=1";
  EXPECT_TRUE(NotifyListener::HasLine(seen.back(), "STATUS=probe ready")) << seen.back();
  ASSERT_TRUE(l.WaitFor("WATCHDOG=1", 3s, seen)) << "no first WATCHDOG=1";
  ASSERT_TRUE(l.WaitFor("WATCHDOG=1", 3s, seen)) << "no second WATCHDOG=1";
  // Half the interval (100 ms): about 10 per second; never a flood.
  auto second = Collect(l, 1s);
  int n = CountLine(second, "WATCHDOG=1");
  EXPECT_GE(n, 3) << "watchdog too slow for WATCHDOG_USEC=200000";
  EXPECT_LE(n, 12) << "watchdog faster than half the interval";
  ASSERT_EQ(kill(pid, SIGTERM), 0);
  ASSERT_TRUE(l.WaitFor("STOPPING=1", 5s, seen)) << "no STOPPING=1";
  auto status = WaitExit(pid, 5s);
  ASSERT_TRUE(status.has_value()) << "did not exit after SIGTERM";
  ASSERT_TRUE(WIFEXITED(*status));
  EXPECT_EQ(WEXITSTATUS(*status), 0);
}

TEST(DaemonProbe, UnhealthyMainLoopStopsFeedingTheWatchdog) {
  NotifyListener l;
  pid_t pid =
      Spawn({CELL_DAEMON_PROBE, "--unhealthy-after", "1"},
            {{"NOTIFY_SOCKET", l.path().string()}, {"WATCHDOG_USEC", "200000"}, {"WATCHDOG_PID", ""}});
  std::vector<std::string> seen;
  ASSERT_TRUE(l.WaitFor("READY=1", 10s, seen));
  ASSERT_TRUE(l.WaitFor("WATCHDOG=1", 3s, seen)) << "healthy at first";
  std::this_thread::sleep_for(400ms);  // the one healthy check is long over
  while (l.Receive(0ms)) {
  }
  EXPECT_EQ(CountLine(Collect(l, 600ms), "WATCHDOG=1"), 0) << "an unhealthy loop must not feed the watchdog";
  ASSERT_EQ(kill(pid, SIGINT), 0);
  auto status = WaitExit(pid, 5s);
  ASSERT_TRUE(status.has_value() && WIFEXITED(*status));
  EXPECT_EQ(WEXITSTATUS(*status), 0);
}

TEST(DaemonProbe, NoWatchdogForAnotherPid) {
  NotifyListener l;
  // WATCHDOG_PID names another process: the watchdog is not ours (sd_watchdog_enabled semantics).
  pid_t pid =
      Spawn({CELL_DAEMON_PROBE},
            {{"NOTIFY_SOCKET", l.path().string()}, {"WATCHDOG_USEC", "200000"}, {"WATCHDOG_PID", "1"}});
  std::vector<std::string> seen;
  ASSERT_TRUE(l.WaitFor("READY=1", 10s, seen));
  EXPECT_EQ(CountLine(Collect(l, 500ms), "WATCHDOG=1"), 0);
  ASSERT_EQ(kill(pid, SIGTERM), 0);
  ASSERT_TRUE(l.WaitFor("STOPPING=1", 5s, seen));
  auto status = WaitExit(pid, 5s);
  ASSERT_TRUE(status.has_value() && WIFEXITED(*status));
  EXPECT_EQ(WEXITSTATUS(*status), 0);
}

}  // namespace
