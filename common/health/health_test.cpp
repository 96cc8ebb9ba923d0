// Heartbeats on a private domain: announced, seen online, and the announcer stops promptly.
#include "cell/health/health.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace cell::health
