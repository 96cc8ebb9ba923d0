// Heartbeats on a private domain: announced, seen online, and the announcer stops promptly.
#include "cell/health/health.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace cell::health {
namespace {

TEST(Health, AnnouncedServiceIsOnlineAndStopsPromptly) {
  bus::Participant watcher("health-test-watcher");
  Liveness live(watcher);
  auto t0 = std::chrono::steady_clock::now();
  {
    bus::Participant p("health-test-svc");
    Announcer a(p, "cell-interpreter", "KT07");
    EXPECT_EQ(a.service_id(), "cell-interpreter/KT07");
    EXPECT_FALSE(live.StationOnline("KT07"));  // STARTING is not online
    a.Set(cell::SERVICE_READY, "ready");
    ASSERT_TRUE(bus::WaitUntil([&] { return live.StationOnline("KT07"); }, bus::Millis(5000)));
    t0 = std::chrono::steady_clock::now();
  }  // ~Announcer: the heartbeat thread must stop, not spin
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(3));
  // Its last word is STOPPING: no longer online.
  EXPECT_TRUE(bus::WaitUntil([&] { return !live.StationOnline("KT07"); }, bus::Millis(5000)));
}

cell::ServiceHealth Beat(const std::string& id, int pid, cell::ServiceState state = cell::SERVICE_READY) {
  cell::ServiceHealth h;
  h.service_id(id);
  h.pid(pid);
  h.boot_id(static_cast<uint64_t>(pid));
  h.state(state);
  return h;
}

// Heartbeats every second from six other processes, until `until`, except those in `quiet` after `from`.
void Beats(Heartbeats& t, Heartbeats::Clock::time_point t0, int seconds, const std::vector<int>& quiet = {},
           int from = 0) {
  for (int s = 0; s <= seconds; ++s)
    for (int pid = 11; pid <= 16; ++pid) {
      if (s > from && std::find(quiet.begin(), quiet.end(), pid) != quiet.end()) continue;
      t.Heard(Beat("cell-interpreter/KT" + std::to_string(pid), pid), t0 + std::chrono::seconds(s));
    }
}

// Silent for topics::kOfflineAfterMs: offline, while most of the cell is still heard.
TEST(Heartbeats, AStationSilentWhileTheRestIsHeardGoesOfflineAfterThreeAndAHalfSeconds) {
  Heartbeats t(1);
  const auto t0 = Heartbeats::Clock::now();
  Beats(t, t0, 10, {12}, 2);
  EXPECT_TRUE(t.Online("cell-interpreter/KT12", t0 + std::chrono::milliseconds(5400)));  // heard at 2 s
  EXPECT_FALSE(t.Online("cell-interpreter/KT12", t0 + std::chrono::milliseconds(5600)));
  EXPECT_TRUE(t.Online("cell-interpreter/KT11", t0 + std::chrono::milliseconds(10500)));
}

// Four of six silent at once (a starved receive, or they all died): each keeps its last word for up to
// kOfflineWhenDeaf, then goes offline; the two still heard stay online.
TEST(Heartbeats, MostOfTheCellSilentAtOnceIsTheListenersDeafnessForTenSeconds) {
  Heartbeats t(1);
  const auto t0 = Heartbeats::Clock::now();
  Beats(t, t0, 20, {11, 12, 13, 14}, 2);
  EXPECT_TRUE(t.Online("cell-interpreter/KT11", t0 + std::chrono::milliseconds(8000)));
  EXPECT_TRUE(t.Online("cell-interpreter/KT11", t0 + std::chrono::milliseconds(12400)));
  EXPECT_FALSE(t.Online("cell-interpreter/KT11", t0 + std::chrono::milliseconds(12600)));
  EXPECT_TRUE(t.Online("cell-interpreter/KT16", t0 + std::chrono::milliseconds(20500)));
  // The burst after a stall: heard again, online again.
  t.Heard(Beat("cell-interpreter/KT11", 11), t0 + std::chrono::seconds(21));
  EXPECT_TRUE(t.Online("cell-interpreter/KT11", t0 + std::chrono::seconds(21)));
}

// This process's own heartbeats (delivered locally) are no sign of hearing the others; processes that said
// STOPPING are no silent peers; STARTING is never online.
TEST(Heartbeats, OwnBeatsAndGoodbyesDoNotCountAndStartingIsNotOnline) {
  Heartbeats t(1);
  const auto t0 = Heartbeats::Clock::now();
  for (int s = 0; s <= 10; ++s) t.Heard(Beat("cell-scheduler", 1), t0 + std::chrono::seconds(s));
  t.Heard(Beat("cell-interpreter/KT11", 11), t0);
  t.Heard(Beat("cell-interpreter/KT12", 12), t0);
  t.Heard(Beat("cell-program-store", 13), t0);
  for (int s = 1; s <= 10; ++s) t.Heard(Beat("cell-program-store", 13), t0 + std::chrono::seconds(s));
  // KT11 and KT12 silent, the store heard: two of three silent, so deaf: still online at 5 s, not at 11 s.
  EXPECT_TRUE(t.Online("cell-interpreter/KT11", t0 + std::chrono::seconds(5)));
  EXPECT_FALSE(t.Online("cell-interpreter/KT11", t0 + std::chrono::seconds(11)));
  // KT12 said goodbye: one silent, one heard, not deaf: KT11 offline at 5 s.
  t.Heard(Beat("cell-interpreter/KT12", 12, cell::SERVICE_STOPPING), t0);
  EXPECT_FALSE(t.Online("cell-interpreter/KT12", t0));
  EXPECT_FALSE(t.Online("cell-interpreter/KT11", t0 + std::chrono::seconds(5)));
  t.Heard(Beat("cell-interpreter/KT14", 14, cell::SERVICE_STARTING), t0 + std::chrono::seconds(10));
  EXPECT_FALSE(t.Online("cell-interpreter/KT14", t0 + std::chrono::seconds(10)));
}

}  // namespace
}  // namespace cell::health
