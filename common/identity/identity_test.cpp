// One process per identity, on a private domain: the younger of two claims refuses, a stopped process's
// announcement does not block a restart, and the scheduler's census (health::Liveness::Conflicts) tells two
// live processes from a dead one and its restart.
#include "cell/identity/identity.h"

#include <gtest/gtest.h>

#include <memory>
#include <thread>

#include "cell/bus/topics.h"

namespace cell::identity {
namespace {

using namespace std::chrono_literals;

struct Process {  // one announcing "process": its own participant and announcer
  explicit Process(const std::string& name)
      : bus(std::make_unique<bus::Participant>(name)),
        health(std::make_unique<health::Announcer>(*bus, "cell-interpreter", "KT09")) {}
  std::unique_ptr<bus::Participant> bus;
  std::unique_ptr<health::Announcer> health;
};

TEST(Claim, ASecondProcessForALiveIdentityRefusesWithinTheWindow) {
  Process first("identity-first");
  first.health->Set(cell::SERVICE_READY);
  Process second("identity-second");
  Claim claim(*second.bus, *second.health);
  const auto t0 = std::chrono::steady_clock::now();
  try {
    claim.Confirm();
    ADD_FAILURE() << "the second process was not refused";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kAlreadyExists);
    EXPECT_NE(std::string(e.what()).find("another live process is cell-interpreter/KT09"), std::string::npos)
        << e.what();
  }
  EXPECT_LE(std::chrono::steady_clock::now() - t0, kClaimWindow + 500ms);
}

TEST(Claim, OfTwoStartingTogetherTheYoungerRefuses) {
  Process a("identity-a");
  Process b("identity-b");  // started after a
  Claim ca(*a.bus, *a.health), cb(*b.bus, *b.health);
  EXPECT_THROW(cb.Confirm(), Error);
  EXPECT_NO_THROW(ca.Confirm());
}

TEST(Claim, AStoppedProcessDoesNotBlockItsSuccessor) {
  {
    Process old("identity-old");
    old.health->Set(cell::SERVICE_READY);
    old.health->Set(cell::SERVICE_STOPPING);  // its last word, and the sample a newcomer gets
    Process next("identity-next");
    Claim claim(*next.bus, *next.health);
    EXPECT_NO_THROW(claim.Confirm());
  }
}

// Announcements written by hand, each "process" with its own writer: a process "killed" simply stops
// speaking.
class Census : public ::testing::Test {
 protected:
  void Speak(uint64_t boot, int pid, int64_t started) {
    auto& w = boot == 1 ? w1 : w2;
    cell::ServiceHealth h;
    h.service_id("cell-axis-servo/KT09");
    h.kind("cell-axis-servo");
    h.station("KT09");
    h.state(cell::SERVICE_READY);
    h.pid(pid);
    h.boot_id(boot);
    h.started_ns(started);
    h.heartbeat_ns(health::WallNs());
    w.Write(h);
  }
  bool Conflict() {
    for (auto& c : live.Conflicts())
      if (c.service_id == "cell-axis-servo/KT09") {
        last = c.Describe();
        return true;
      }
    return false;
  }
  bus::Participant watcher{"identity-census"};
  health::Liveness live{watcher};
  bus::Participant speaker1{"identity-speaker-1"}, speaker2{"identity-speaker-2"};
  bus::Writer<cell::ServiceHealth> w1{speaker1, bus::topics::kHealth, bus::QosKind::kState};
  bus::Writer<cell::ServiceHealth> w2{speaker2, bus::topics::kHealth, bus::QosKind::kState};
  std::string last;
};

TEST_F(Census, ARestartAfterKillIsNoConflictButTwoLiveProcessesAre) {
  ASSERT_TRUE(w1.WaitForMatched(1, 5s));
  ASSERT_TRUE(w2.WaitForMatched(1, 5s));
  for (int i = 0; i < 3; ++i) {
    Speak(1, 100, 1);
    std::this_thread::sleep_for(100ms);
  }
  // Process 1 dies; process 2 takes over while 1's last heartbeat is still within the offline window.
  for (int i = 0; i < 5; ++i) {
    Speak(2, 200, 2);
    EXPECT_FALSE(Conflict()) << last;
    std::this_thread::sleep_for(100ms);
  }
  // Process 1 was only stopped, and speaks again: two live processes.
  Speak(1, 100, 1);
  Speak(2, 200, 2);
  ASSERT_TRUE(bus::WaitUntil([&] { return Conflict(); }, 3s));
  EXPECT_NE(last.find("pid 100"), std::string::npos) << last;
  EXPECT_NE(last.find("pid 200"), std::string::npos) << last;
  // One of them goes quiet for good: the conflict ends with its offline window.
  ASSERT_TRUE(bus::WaitUntil(
      [&] {
        Speak(2, 200, 2);
        return !Conflict();
      },
      6s));
}

}  // namespace
}  // namespace cell::identity
