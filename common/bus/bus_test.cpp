// Bus unit tests: two participants in one process on the test's private domain (CELL_DOMAIN,
// set by CTest). Every wait is for a condition (matched, a sample), never a fixed sleep. The tests that
// exchange samples run for every pair of stacks (Fast DDS and Cyclone DDS, each way round): the backends
// must give the same semantics, and across vendors.
#include "cell/bus/bus.h"

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <string_view>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "cell/idl/health.h"
#include "cell/idl/program_store.h"
#include "cell/idl/run.h"
#include "cell/idl/station.h"
#include "src/fastdds_lease_check.h"
#include "src/slots.h"

namespace cell::bus {
namespace {

constexpr Millis kMatch(5000);

// The stacks of participant A and of participant B.
struct Stacks {
  const char* a;
  const char* b;
};

class BusTest : public ::testing::TestWithParam<Stacks> {
 protected:
  static ParticipantOptions A(const std::string& name) { return Named(name, GetParam().a); }
  static ParticipantOptions B(const std::string& name) { return Named(name, GetParam().b); }
};

std::string StacksName(const ::testing::TestParamInfo<Stacks>& info) {
  auto word = [](const std::string& v) {
    return v == "fastdds" ? std::string("Fast") : std::string("Cyclone");
  };
  return word(info.param.a) + "To" + word(info.param.b);
}

INSTANTIATE_TEST_SUITE_P(Stacks, BusTest,
                         ::testing::Values(Stacks{"fastdds", "fastdds"}, Stacks{"cyclonedds", "cyclonedds"},
                                           Stacks{"fastdds", "cyclonedds"}, Stacks{"cyclonedds", "fastdds"}),
                         StacksName);

cell::StationStatus Status(const std::string& id, int line) {
  cell::StationStatus s;
  s.station(id);
  s.line(line);
  s.execution(cell::EXECUTION_ACTIVE);
  return s;
}

TEST_P(BusTest, PublishSubscribeAcrossParticipants) {
  Participant a(A("bus-test-a")), b(B("bus-test-b"));
  Writer<cell::StationStatus> w(a, "test/pubsub", QosKind::kCommand);
  Reader<cell::StationStatus> r(b, "test/pubsub", QosKind::kCommand);
  ASSERT_TRUE(w.WaitForMatched(1, kMatch));
  ASSERT_TRUE(r.WaitForMatched(1, kMatch));
  w.Write(Status("KT01", 7));
  auto got = r.Take(kMatch);
  ASSERT_TRUE(got);
  EXPECT_EQ(got->station(), "KT01");
  EXPECT_EQ(got->line(), 7);
  EXPECT_EQ(got->execution(), cell::EXECUTION_ACTIVE);
}

// docs/security.md, "Partitions": a sample names its writer's identity (claimed here, unsecured; the
// permissions make it authenticated), and a reader drops a station identity's sample about another station.
TEST_P(BusTest, ASampleNamesItsWriterAndNoStationWritesAnothersKey) {
  ParticipantOptions kt02 = A("bus-test-kt02"), sched = A("bus-test-sched");
  kt02.identity = "interpreter-KT02";
  sched.identity = "scheduler";
  Participant a(kt02), s(sched), b(B("bus-test-b"));
  std::mutex mu;
  std::vector<std::pair<std::string, std::string>> got;  // (station, writer)
  Reader<cell::StationStatus> r(b, "test/partitions", QosKind::kState,
                                [&](const cell::StationStatus& v, const SampleInfo& info) {
                                  std::lock_guard lk(mu);
                                  got.emplace_back(v.station().to_string(), info.writer);
                                });
  Writer<cell::StationStatus> w(a, "test/partitions", QosKind::kState);
  Writer<cell::StationStatus> ws(s, "test/partitions", QosKind::kState);
  ASSERT_TRUE(w.WaitForMatched(1, kMatch));
  ASSERT_TRUE(ws.WaitForMatched(1, kMatch));
  w.Write(Status("KT01", 1));   // another station's key: dropped
  w.Write(Status("KT02", 2));   // its own
  ws.Write(Status("KT01", 3));  // the control: a cell service may write any station's key
  auto has = [&](const std::string& station, const std::string& writer) {
    std::lock_guard lk(mu);
    return std::find(got.begin(), got.end(), std::make_pair(station, writer)) != got.end();
  };
  ASSERT_TRUE(WaitUntil([&] { return has("KT02", "interpreter-KT02") && has("KT01", "scheduler"); }, kMatch));
  w.Write(
      Status("KT02", 4));  // written after the KT01 sample: once it is here, that one was not dropped late
  ASSERT_TRUE(WaitUntil(
      [&] {
        std::lock_guard lk(mu);
        return std::count(got.begin(), got.end(),
                          std::make_pair(std::string("KT02"), std::string("interpreter-KT02"))) >= 2;
      },
      kMatch));
  std::lock_guard lk(mu);
  for (const auto& [station, writer] : got)
    EXPECT_FALSE(station == "KT01" && writer == "interpreter-KT02")
        << "a station wrote another station's key";
}

TEST_P(BusTest, LateJoinerGetsLastSampleOfEveryKey) {
  Participant a(A("bus-test-a")), b(B("bus-test-b"));
  Writer<cell::StationStatus> w(a, "test/state", QosKind::kState);
  for (int i = 1; i <= 3; ++i)
    for (const char* id : {"KT01", "KT02", "KT03"}) w.Write(Status(id, i));
  Reader<cell::StationStatus> r(b, "test/state", QosKind::kState);
  ASSERT_TRUE(r.WaitForMatched(1, kMatch));
  std::map<std::string, int> last;
  while (last.size() < 3) {
    auto s = r.Take(kMatch);
    ASSERT_TRUE(s) << "late joiner got only " << last.size() << " keys";
    last[s->station().to_string()] = s->line();
  }
  EXPECT_EQ(last, (std::map<std::string, int>{{"KT01", 3}, {"KT02", 3}, {"KT03", 3}}));
  EXPECT_FALSE(r.Take(Millis(200))) << "keep-last 1 per key: no older samples";
}

TEST_P(BusTest, CallbackRunsOnTheDispatchThread) {
  Participant a(A("bus-test-a")), b(B("bus-test-b"));
  std::mutex mu;
  std::condition_variable cv;
  std::vector<int> seen;
  std::thread::id cb_thread;
  Reader<cell::RunStatus> r(b, "test/runs", QosKind::kEvent,
                            [&](const cell::RunStatus& s, const SampleInfo&) {
                              std::lock_guard lk(mu);
                              cb_thread = std::this_thread::get_id();
                              seen.push_back(s.dispatch_id());
                              cv.notify_all();
                            });
  Writer<cell::RunStatus> w(a, "test/runs", QosKind::kEvent);
  ASSERT_TRUE(w.WaitForMatched(1, kMatch));
  ASSERT_TRUE(r.WaitForMatched(1, kMatch));
  for (int id : {17, 18}) {
    cell::RunStatus s;
    s.dispatch_id(id);
    w.Write(s);
  }
  std::unique_lock lk(mu);
  ASSERT_TRUE(cv.wait_for(lk, kMatch, [&] { return seen.size() >= 2; }));
  EXPECT_EQ(seen, (std::vector<int>{17, 18}));  // in arrival order
  EXPECT_NE(cb_thread, std::this_thread::get_id());
}

TEST(Bus, WriteRejectsSequenceOverItsBound) {
  Participant a("bus-test-a");
  Writer<cell::ToolTable> w(a, "test/tools", QosKind::kState);
  cell::ToolTable t;
  t.station("KT01");
  t.tools().resize(513);
  try {
    w.Write(t);
    FAIL() << "no error for 513 tools in sequence<ToolEntry, 512>";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("ToolTable.tools: 513 elements, bound 512"), std::string::npos)
        << e.what();
  }
}

using Req = cell::StationRequest;
using Rep = cell::StationReply;

TEST_P(BusTest, RequestReplyCarriesResultAndErrors) {
  Participant a(A("bus-test-server")), b(B("bus-test-client"));
  int calls = 0;
  Server<Req, Rep> server(a, "test/svc", [&](const Req& r) {
    ++calls;
    if (r.station() == "NOPE") throw Error(Errc::kNotFound, "unknown station NOPE");
    Rep rep;
    rep.station(r.station());
    rep.revision(42);
    return rep;
  });
  Client<Req, Rep> client(b, "test/svc");
  Req req;
  req.station("KT01");
  Rep rep = client.Call(req, kMatch);
  EXPECT_EQ(rep.hdr().code(), 0);
  EXPECT_EQ(rep.station(), "KT01");
  EXPECT_EQ(rep.revision(), 42u);
  EXPECT_EQ(rep.hdr().client(), b.id());

  req.station("NOPE");
  Rep bad = client.Call(req, kMatch);
  try {
    ThrowIfError(bad);
    FAIL() << "error reply not raised";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kNotFound);
    EXPECT_STREQ(e.what(), "unknown station NOPE");
  }
  EXPECT_EQ(calls, 2);
}

// Two clients of one service in one process share the participant's client id: each must get its own
// replies, never the other's cached ones (a second Client counted request ids from 1 again).
TEST_P(BusTest, TwoClientsOfOneServiceGetTheirOwnReplies) {
  Participant a(A("bus-test-two-server")), b(B("bus-test-two-clients"));
  Server<Req, Rep> server(a, "test/two", [](const Req& r) {
    Rep rep;
    rep.station(r.station());
    return rep;
  });
  Client<Req, Rep> first(b, "test/two");
  Req req;
  req.station("KT01");
  ASSERT_EQ(first.Call(req, kMatch).station(), "KT01");
  Client<Req, Rep> second(b, "test/two");
  req.station("KT02");
  EXPECT_EQ(second.Call(req, kMatch).station(), "KT02");
}

// topics::kStationRun: one service every station serves. A station's server takes only the requests that
// name it (Server's accept), and the client drops a station identity's reply to a request for another
// station, error replies too (docs/security.md, "Partitions"; the identities are claimed here, the
// permissions make them authenticated). KT02 here answers everything at once; KT01 answers its own late.
TEST_P(BusTest, AServiceEveryStationServesIsAnsweredByTheStationNamedOnly) {
  ParticipantOptions o1 = A("bus-test-kt01"), o2 = A("bus-test-kt02"), os = B("bus-test-sched");
  o1.identity = "interpreter-KT01";
  o2.identity = "interpreter-KT02";
  os.identity = "scheduler";
  Participant kt01(o1), kt02(o2), sched(os);
  std::atomic<int> kt01_handled{0};
  Server<cell::RunRequest, cell::RunReply> own(
      kt01, "test/every_station",
      [&](const cell::RunRequest& r) {
        ++kt01_handled;
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        cell::RunReply rep;
        rep.station(r.station());
        rep.dispatch_id(1);
        return rep;
      },
      nullptr, [](const cell::RunRequest& r) { return r.station() == "KT01"; });
  Server<cell::RunRequest, cell::RunReply> forger(kt02, "test/every_station", [](const cell::RunRequest& r) {
    if (r.dispatch_id() == 3) throw Error(Errc::kInvalidArgument, "refused");
    cell::RunReply rep;
    rep.station(r.station());
    rep.dispatch_id(2);
    return rep;
  });
  Client<cell::RunRequest, cell::RunReply> client(sched, "test/every_station");
  ASSERT_TRUE(client.WaitForServer(kMatch));
  ASSERT_TRUE(WaitUntil([&] { return own.Matched() == 1 && forger.Matched() == 1; }, kMatch));
  cell::RunRequest req;
  req.station("KT01");
  req.dispatch_id(1);
  auto rep = client.Call(req, kMatch);
  EXPECT_EQ(rep.dispatch_id(), 1) << "KT02's answer about KT01 was taken";
  EXPECT_EQ(rep.hdr().code(), 0);
  req.dispatch_id(3);  // KT02 answers with an error at once: dropped as well
  rep = client.Call(req, kMatch);
  EXPECT_EQ(rep.hdr().code(), 0) << rep.hdr().error();
  EXPECT_EQ(rep.dispatch_id(), 1);
  req.station("KT03");  // nobody's: KT01 leaves it, KT02's answer is dropped
  EXPECT_THROW(client.Call(req, Millis(1500)), Error);
  req.station("KT02");  // KT02's own: taken
  req.dispatch_id(1);
  EXPECT_EQ(client.Call(req, kMatch).dispatch_id(), 2);
  EXPECT_EQ(kt01_handled.load(), 2);
}

// Issue 39 item 1: the reply cache keeps what a re-sent request needs, bounded in bytes as well as entries
// (4096 replies of 60 KB each grew the program store by a quarter of a gigabyte).
TEST_P(BusTest, TheReplyCacheIsBoundedInBytes) {
  Participant a(A("bus-test-cache")), b(B("bus-test-cache-client"));
  Server<cell::ProgramRequest, cell::ProgramReply> server(a, "test/cache", [](const cell::ProgramRequest&) {
    cell::ProgramReply rep;
    rep.data().assign(60000, 0x25);
    return rep;
  });
  using Big = Server<cell::ProgramRequest, cell::ProgramReply>;
  Client<cell::ProgramRequest, cell::ProgramReply> client(b, "test/cache");
  for (int i = 0; i < 100; ++i) {
    auto rep = client.Call(cell::ProgramRequest(), kMatch);
    ASSERT_EQ(rep.data().size(), 60000u);
  }
  const auto [entries, bytes] = server.CacheUse();
  EXPECT_LE(bytes, Big::kCacheBytes);
  EXPECT_GE(bytes, Big::kCacheBytes - 61000);  // full, with the newest replies
  EXPECT_LT(entries, 100u);
  EXPECT_GT(entries, 60u);
}

// A participant that rejoins (what its watch thread does after the process stood still past the lease)
// keeps every endpoint working: pub/sub both ways, a state reader gets the last sample again, a server and
// a client answer; TotalMatched counts the lost match.
TEST_P(BusTest, RejoinKeepsEveryEndpointWorking) {
  Participant a(A("bus-test-rejoin")), b(B("bus-test-peer"));
  Writer<cell::StationStatus> wa(a, "test/rejoin/out", QosKind::kCommand);
  Reader<cell::StationStatus> rb(b, "test/rejoin/out", QosKind::kCommand);
  Writer<cell::StationStatus> wb(b, "test/rejoin/state", QosKind::kState);
  Reader<cell::StationStatus> ra(a, "test/rejoin/state", QosKind::kState);
  Server<Req, Rep> server(a, "test/rejoin/svc", [](const Req& r) {
    Rep rep;
    rep.station(r.station());
    return rep;
  });
  Client<Req, Rep> client(a, "test/rejoin/svc2");
  Server<Req, Rep> server2(b, "test/rejoin/svc2", [](const Req& r) {
    Rep rep;
    rep.station(r.station());
    rep.revision(2);
    return rep;
  });
  Client<Req, Rep> peer_client(b, "test/rejoin/svc");
  wb.Write(Status("KT01", 1));
  ASSERT_TRUE(wa.WaitForMatched(1, kMatch));
  ASSERT_TRUE(ra.Take(kMatch));
  const uint64_t before = wa.TotalMatched();

  ASSERT_TRUE(a.Rejoin());
  EXPECT_EQ(a.rejoins(), 1u);
  ASSERT_TRUE(wa.WaitForMatched(1, kMatch));
  ASSERT_TRUE(rb.WaitForMatched(1, kMatch));
  EXPECT_GT(wa.TotalMatched(), before);
  wa.Write(Status("KT02", 5));
  auto got = rb.Take(kMatch);
  ASSERT_TRUE(got);
  EXPECT_EQ(got->line(), 5);
  auto again = ra.Take(kMatch);  // transient-local: the new reader gets the last sample
  ASSERT_TRUE(again);
  EXPECT_EQ(again->station(), "KT01");
  Req req;
  req.station("KT03");
  EXPECT_EQ(peer_client.Call(req, kMatch).station(), "KT03");  // the rejoined side serves
  EXPECT_EQ(client.Call(req, kMatch).revision(), 2u);          // and calls
}

// A state writer that rejoins writes each key's last sample again (Writer::Recreate): a reader that joins
// after the rejoin gets the state, though nothing was written since. A station's status goes out only when
// it changes: in a two-station Fast DDS cell a station that had rejoined stayed UNAVAILABLE to `cellctl
// station ls` and to a scheduler started afresh (docs/operations.md §9.6).
TEST_P(BusTest, AReaderThatJoinsAfterARejoinGetsTheLastStateOfEveryKey) {
  Participant a(A("bus-test-rejoin-state")), b(B("bus-test-late"));
  Writer<cell::StationStatus> w(a, "test/rejoin/late", QosKind::kState);
  w.Write(Status("KT01", 1));
  w.Write(Status("KT01", 2));
  w.Write(Status("KT02", 7));
  ASSERT_TRUE(a.Rejoin());
  Reader<cell::StationStatus> r(b, "test/rejoin/late", QosKind::kState);
  std::map<std::string, int> last;
  while (last.size() < 2) {
    auto s = r.Take(kMatch);
    ASSERT_TRUE(s) << "after the rejoin a late joiner got only " << last.size() << " keys";
    last[s->station().to_string()] = s->line();
  }
  EXPECT_EQ(last, (std::map<std::string, int>{{"KT01", 2}, {"KT02", 7}}));
}

// The writer of StateWriterThatStoodStillIsHeardAgain, in a process of its own (run by it with
// CELL_BUS_TEST_CHILD=<stack>; bus_test's own entry leaves it out): 50 samples, then, once it has
// rejoined the bus after standing still, line 1000.
TEST(BusChild, AStateWriterThatStandsStill) {
  const char* stack = std::getenv("CELL_BUS_TEST_CHILD");
  if (stack == nullptr) GTEST_SKIP() << "the writer of StateWriterThatStoodStillIsHeardAgain";
  Participant p(Named("bus-test-stood-still", stack));
  Writer<cell::StationStatus> w(p, "test/stood_still", QosKind::kState);
  for (int i = 1; i <= 50; ++i) w.Write(Status("KT01", i));
  ASSERT_TRUE(WaitUntil([&] { return p.rejoins() > 0; }, Millis(60000), Millis(20)));
  w.Write(Status("KT01", 1000));
  WaitUntil([] { return false; }, Millis(60000), Millis(100));  // until the test ends it
}

// A process that stood still past the lease (SIGSTOP) is dropped by its peers "by lease" and rejoins with
// the same writers on the same slot. Fast DDS 2.9 readers keep the last sequence number of a writer lost by
// lease under its persistence GUID, which it derived from the process and the slot, so the same again:
// the new writer's samples up to that number were dropped as duplicates. In a Fast DDS week the scheduler
// heard nothing of a station for the rest of the run (docs/operations.md §9.6). The backend now gives each
// writer a persistence GUID of its own.
class StoodStillTest : public ::testing::TestWithParam<const char*> {};

TEST_P(StoodStillTest, StateWriterThatStoodStillIsHeardAgain) {
  Participant me(Named("bus-test-reader", GetParam()));
  std::mutex mu;
  std::vector<int> lines;
  Reader<cell::StationStatus> r(me, "test/stood_still", QosKind::kState,
                                [&](const cell::StationStatus& s, const SampleInfo&) {
                                  std::lock_guard lk(mu);
                                  lines.push_back(s.line());
                                });
  auto got = [&](int line) {
    std::lock_guard lk(mu);
    return std::find(lines.begin(), lines.end(), line) != lines.end();
  };
  const std::string env = std::string("CELL_BUS_TEST_CHILD=") + GetParam();
  std::vector<std::string> envs{env};
  for (char** e = environ; *e != nullptr; ++e)
    if (std::string_view(*e).rfind("CELL_BUS_TEST_CHILD=", 0) != 0) envs.emplace_back(*e);
  std::vector<char*> envp;
  for (auto& e : envs) envp.push_back(e.data());
  envp.push_back(nullptr);
  std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  std::string filter = "--gtest_filter=BusChild.AStateWriterThatStandsStill";
  char* argv[] = {self.data(), filter.data(), nullptr};
  pid_t child = 0;
  ASSERT_EQ(posix_spawn(&child, self.c_str(), nullptr, nullptr, argv, envp.data()), 0);
  struct Reap {
    pid_t pid;
    ~Reap() {
      kill(pid, SIGCONT);
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
  } reap{child};

  ASSERT_TRUE(WaitUntil([&] { return got(50); }, Millis(20000))) << "the writer's 50th sample";
  ASSERT_EQ(kill(child, SIGSTOP), 0);
  // Dropped by lease (3 s), not by a goodbye: the reader keeps its record of the writer.
  const bool lost = WaitUntil([&] { return r.Matched() == 0; }, Millis(15000));
  ASSERT_EQ(kill(child, SIGCONT), 0);
  ASSERT_TRUE(lost) << "the reader never lost the stopped writer";
  EXPECT_TRUE(WaitUntil([&] { return got(1000); }, Millis(20000)))
      << "the writer's first sample after its rejoin never arrived (its samples 1..50 taken for the old "
         "ones)";
}

INSTANTIATE_TEST_SUITE_P(Stacks, StoodStillTest, ::testing::Values("fastdds", "cyclonedds"),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                           return std::string(info.param) == "fastdds" ? "Fast" : "Cyclone";
                         });

TEST(Bus, AStationOwnsItsNamespaceAndItsMemoriesOnly) {
  EXPECT_TRUE(StationOwns("BS01", "BS01"));
  EXPECT_TRUE(StationOwns("BS01", "BS01/MP3"));
  EXPECT_FALSE(StationOwns("BS01", "BS011"));
  EXPECT_FALSE(StationOwns("BS01", "BS02/MP3"));
  EXPECT_FALSE(StationOwns("BS01", "HOST"));
  EXPECT_EQ(StationOfIdentity("interpreter-KT01"), "KT01");
  EXPECT_EQ(StationOfIdentity("axis-servo-KT01"), "KT01");
  EXPECT_EQ(StationOfIdentity("scheduler"), "");
  EXPECT_EQ(StationOfIdentity("fms-test-observer"), "");
}

TEST(Bus, CallWithoutServerIsUnavailable) {
  Participant b("bus-test-client");
  Client<Req, Rep> client(b, "test/nobody");
  auto t0 = std::chrono::steady_clock::now();
  try {
    client.Call(Req(), Millis(300));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kUnavailable);
  }
  EXPECT_GE(std::chrono::steady_clock::now() - t0, Millis(300));
}

// A newcomer to a 32-station cell (68 other participants) heard its server only after seconds; the wait for
// one grows with the participants heard, within the call's own timeout.
TEST(Bus, TheWaitForAServerGrowsWithTheParticipantsHeard) {
  EXPECT_EQ(ServerWait(Millis(5000), 0, Millis(30000)), Millis(5000));
  EXPECT_EQ(ServerWait(Millis(5000), -1, Millis(30000)), Millis(5000));  // the backend cannot tell
  EXPECT_EQ(ServerWait(Millis(5000), 10, Millis(30000)), Millis(5000));
  EXPECT_EQ(ServerWait(Millis(5000), 68, Millis(30000)), Millis(10200));
  EXPECT_EQ(ServerWait(Millis(5000), 68, Millis(8000)), Millis(8000));
  EXPECT_EQ(ServerWait(Millis(15000), 68, Millis(30000)), Millis(15000));  // secured: its own 15 s
  EXPECT_EQ(ServerWait(Millis(5000), 400, Millis(30000)), Millis(30000));
}

// The deadlock seen in a 68-process cell's scheduler (Fast DDS 2.9.1, participant.cpp): one receive call that
// never returned. The watch thread ends the process once the same call has run 30 s of on-time ticks.
TEST(Bus, OneReceiveCallRunningThroughThirtySecondsIsStuck) {
  constexpr Millis kTick(250);
  StuckReceive w(Millis(30000));
  EXPECT_FALSE(w.Observe(1000, kTick, true));  // first seen
  for (int i = 1; i < 120; ++i) EXPECT_FALSE(w.Observe(1000, kTick, true)) << i;
  EXPECT_TRUE(w.Observe(1000, kTick, true));  // 120 ticks of 250 ms
  EXPECT_EQ(w.stuck_for(), Millis(30000));
}

TEST(Bus, ReceiveCallsThatEndAreNotStuck) {
  constexpr Millis kTick(250);
  StuckReceive w(Millis(30000));
  // Busy but moving: a new call each tick, or none running.
  for (int i = 0; i < 400; ++i) EXPECT_FALSE(w.Observe(i % 3 == 0 ? 0 : 1000 + i, kTick, true)) << i;
  // A call frozen by SIGSTOP: the tick after the stop is late, and the count starts again from there.
  for (int i = 0; i < 100; ++i) EXPECT_FALSE(w.Observe(5000, kTick, true));
  EXPECT_FALSE(w.Observe(5000, Millis(60000), false));
  EXPECT_EQ(w.stuck_for(), Millis(0));
  EXPECT_FALSE(w.Observe(0, kTick, true));  // it returned once the process ran again
}

// Fast DDS 2.9.1's lease check aborts on a peer whose leaving a receive thread is handling, and deadlocks
// against a receive thread that waits for the timer thread (docs/architecture.md, "Leaving"). The library
// must call the bus's replacement in every process that links the bus: the export in CMakeLists.txt is what
// makes it so.
TEST(Bus, FastDdsCallsTheBussLeaseCheck) {
  EXPECT_TRUE(FastDdsLeaseCheckMended());
}

TEST_P(BusTest, SlowServerTimesOutAndResendIsNotRunTwice) {
  Participant a(A("bus-test-server")), b(B("bus-test-client"));
  std::atomic<int> calls{0};
  std::mutex mu;
  std::condition_variable cv;
  bool release = false;
  Server<Req, Rep> server(a, "test/slow", [&](const Req&) {
    ++calls;
    std::unique_lock lk(mu);
    cv.wait(lk, [&] { return release; });
    return Rep();
  });
  Client<Req, Rep> client(b, "test/slow");
  // Discovery first: across vendors it can take a second (DESIGN §3), longer than this call's timeout.
  ASSERT_TRUE(client.WaitForServer(kMatch));
  ASSERT_TRUE(WaitUntil([&] { return server.Matched() >= 1; }, kMatch));
  try {
    // Resends every 50 ms while the handler blocks; the server must run it once.
    client.Call(Req(), Millis(600), Millis(50));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kTimeout);
  }
  {
    std::lock_guard lk(mu);
    release = true;
  }
  cv.notify_all();
  Rep rep = client.Call(Req(), kMatch);  // the server is healthy afterwards
  EXPECT_EQ(rep.hdr().code(), 0);
  EXPECT_EQ(calls.load(), 2);
}

TEST_P(BusTest, ReplyToVanishedRequesterIsHarmless) {
  Participant a(A("bus-test-server"));
  std::atomic<int> calls{0};
  Server<Req, Rep> server(a, "test/vanish", [&](const Req& r) {
    ++calls;
    Rep rep;
    rep.station(r.station());
    return rep;
  });
  {
    Participant gone(B("bus-test-gone"));
    Writer<Req> w(gone, RequestTopic("test/vanish"), QosKind::kCommand);
    // Both sides matched: a Fast DDS writer matches a Cyclone reader before that reader has discovered it,
    // and a volatile Cyclone reader drops what was written before (DESIGN §3).
    ASSERT_TRUE(w.WaitForMatched(1, kMatch));
    ASSERT_TRUE(WaitUntil([&] { return server.Matched() >= 1; }, kMatch));
    Req r;
    r.hdr().client("ghost");
    r.hdr().request_id(1);
    r.station("GHOST");
    w.Write(r);
    ASSERT_TRUE(WaitUntil([&] { return calls.load() == 1; }, kMatch));
  }  // the requester is gone before, or while, the reply is written
  Participant b(B("bus-test-client"));
  Client<Req, Rep> client(b, "test/vanish");
  Req r;
  r.station("KT02");
  Rep rep = client.Call(r, kMatch);
  EXPECT_EQ(rep.station(), "KT02");
  EXPECT_EQ(calls.load(), 2);
}

TEST(Bus, EnvironmentIsValidated) {
  // CELL_DOMAIN parsing is cell::config::Domain()'s (tested in config_test); the bus must use it.
  const char* old = std::getenv("CELL_DOMAIN");
  std::string keep = old ? old : "";
  setenv("CELL_DOMAIN", "233", 1);
  EXPECT_THROW(Participant("x"), Error);
  setenv("CELL_DOMAIN", keep.c_str(), 1);
  setenv("CELL_DDS", "opendds", 1);
  try {
    Participant p("x");
    FAIL() << "CELL_DDS=opendds accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kInvalidArgument);
    EXPECT_STREQ(e.what(), "CELL_DDS=opendds: expected one of fastdds, cyclonedds");
  }
  unsetenv("CELL_DDS");
  for (const char* v : {"fastdds", "cyclonedds"}) {
    Participant p(Named("x", v));
    EXPECT_EQ(p.vendor(), v);
    EXPECT_EQ(p.backend().Name(), v);
  }
}

// Events (keep last 256, transient-local) reach a late joiner in full on every stack: Cyclone keeps for
// late joiners what the durability-service history says, which the backend sets to the history.
TEST_P(BusTest, LateJoinerGetsEveryRecentEvent) {
  Participant a(A("bus-test-a")), b(B("bus-test-b"));
  Writer<cell::RunStatus> w(a, "test/events", QosKind::kEvent);
  for (int id = 1; id <= 5; ++id) {
    cell::RunStatus s;
    s.dispatch_id(id);
    w.Write(s);
  }
  Reader<cell::RunStatus> r(b, "test/events", QosKind::kEvent);
  std::vector<int> got;
  while (got.size() < 5) {
    auto s = r.Take(kMatch);
    ASSERT_TRUE(s) << "late joiner got " << got.size() << " of 5 events";
    got.push_back(s->dispatch_id());
  }
  EXPECT_EQ(got, (std::vector<int>{1, 2, 3, 4, 5}));
}

// docs/operations.md §9.4, "A client of the host services": a client that calls the host services only
// announces itself to their reserved slots from a slot nobody else announces to, so it hears the scheduler
// and never a station (which never hears of it). The scheduler and the station are Fast DDS here: two
// Cyclone participants of one process share one slot (one Cyclone domain per process).
void ExpectHostServicesClientHearsNoStation(const std::string& client_stack) {
  Participant sched(Named("cell-scheduler", "fastdds")), station(Named("bus-test-station", "fastdds"));
  ParticipantOptions o = Named("bus-test-client", client_stack);
  o.host_services_only = true;
  Participant client(o);
  Writer<cell::StationStatus> ws(sched, "test/narrow/scheduler", QosKind::kState);
  Writer<cell::StationStatus> wst(station, "test/narrow/station", QosKind::kState);
  Reader<cell::StationStatus> rs(client, "test/narrow/scheduler", QosKind::kState);
  Reader<cell::StationStatus> rst(client, "test/narrow/station", QosKind::kState);
  // The station itself hears the scheduler (it announces to every slot): the cell is whole.
  Reader<cell::StationStatus> seen_by_station(station, "test/narrow/scheduler", QosKind::kState);
  ws.Write(Status("SCHED", 1));
  wst.Write(Status("KT01", 2));
  auto s = rs.Take(kMatch);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->station(), "SCHED");
  ASSERT_TRUE(seen_by_station.Take(kMatch));
  // Three announcement periods (1 s) after the client heard the scheduler, it has still not met the station.
  EXPECT_FALSE(rst.Take(Millis(3000)));
  EXPECT_EQ(rst.Matched(), 0);
  EXPECT_EQ(client.RemoteParticipants(), 1);
  EXPECT_EQ(station.RemoteParticipants(), 1);  // the scheduler, not the client
  // It waits for a server as one of the configured cell (config::DdsParticipants, at least 32), whom the
  // services answer too, though it hears only them; any other participant counts whom it hears.
  EXPECT_GE(client.cell_participants(), 32);
  EXPECT_EQ(station.cell_participants(), 0);
  EXPECT_EQ(sched.cell_participants(), 0);
}

TEST(Bus, AHostServicesClientHearsTheServicesAndNoStation) {
  for (const char* stack : {"fastdds", "cyclonedds"}) {
    SCOPED_TRACE(stack);
    ExpectHostServicesClientHearsNoStation(stack);
  }
}

// docs/operations.md §9.5, "Who meets whom": a station's processes sit above the shared slots (services and
// whole-cell clients) and announce themselves to another host's shared slots only, to every slot of their
// own host; a client of the host services announces itself to the services' slots everywhere.
TEST(Bus, AStationsProcessesSitAboveTheSharedSlotsAndSkipAnotherHostsStations) {
  EXPECT_TRUE(IsStationProcess("cell-interpreter/KT01"));
  EXPECT_TRUE(IsStationProcess("cell-axis-servo/OK07"));
  EXPECT_FALSE(IsStationProcess("cell-scheduler"));
  EXPECT_FALSE(IsStationProcess("cellctl"));
  EXPECT_FALSE(IsStationProcess("cell-dashboard"));
  EXPECT_EQ(slots::FirstSlot(32), kHostServiceSlots);
  EXPECT_EQ(slots::FirstSlot(32, true), kSharedSlots);
  EXPECT_EQ(slots::FirstSlot(24, true), kHostServiceSlots);  // no room for a zone of their own
  EXPECT_FALSE(slots::IsAnotherHost("127.0.0.1"));
  EXPECT_FALSE(slots::IsAnotherHost("127.0.1.1"));
  EXPECT_FALSE(slots::IsAnotherHost("localhost"));  // a name: never narrowed
  EXPECT_TRUE(slots::IsAnotherHost("192.0.2.1"));
  BackendOptions o;
  EXPECT_TRUE(slots::AnnouncedSlots(o, true).empty());
  EXPECT_TRUE(slots::AnnouncedSlots(o, false).empty());
  o.station_process = true;
  EXPECT_EQ(slots::AnnouncedSlots(o, true).size(), static_cast<size_t>(kSharedSlots));
  EXPECT_TRUE(slots::AnnouncedSlots(o, false).empty());
  // A Cyclone LAN profile's peers, this host and the cell host on another address (domain 105: slot 0's
  // discovery port is 7400 + 250 * 105 + 10 = 33660, RTPS 9.6.1.1): the other host's shrinks to its 16 shared
  // slots, this host's stays every slot, a peer with a port stays as written.
  o.domain = 105;
  const std::string peers =
      "<Peers><Peer address=\"127.0.0.1\"/><Peer address=\"192.0.2.1\"/>"
      "<Peer address=\"192.0.2.7:7400\"/></Peers>";
  std::string want = "<Peers><Peer address=\"127.0.0.1\"/>";
  for (int s = 0; s < kSharedSlots; ++s)
    want += "<Peer address=\"192.0.2.1:" + std::to_string(33660 + 2 * s) + "\"/>";
  want += "<Peer address=\"192.0.2.7:7400\"/></Peers>";
  EXPECT_EQ(slots::NarrowCyclonePeers(peers, o), want);
  o.station_process = false;
  EXPECT_EQ(slots::NarrowCyclonePeers(peers, o), peers);
  o = BackendOptions{};
  o.host_services_only = true;
  EXPECT_EQ(slots::AnnouncedSlots(o, true).size(), static_cast<size_t>(kHostServiceSlots));
  EXPECT_EQ(slots::AnnouncedSlots(o, false).size(), static_cast<size_t>(kHostServiceSlots));
  o.domain = 105;
  EXPECT_EQ(slots::NarrowCyclonePeers("<Peer address=\"127.0.0.1\"/>", o),
            "<Peer address=\"127.0.0.1:33660\"/><Peer address=\"127.0.0.1:33662\"/>"
            "<Peer address=\"127.0.0.1:33664\"/><Peer address=\"127.0.0.1:33666\"/>");
}

// docs/operations.md §9.5, "A station's partner": a slot is held by one process only; a station's two
// processes find each other through the marks they hold (abstract Unix sockets, listed in /proc/net/unix); of
// two started together at least one finds the other; a process of the same name is found too (the identity
// claim must reach it); another station's, another domain's and a released mark are not.
TEST(Bus, AStationsProcessesFindTheirPartnersSlotAndNoOtherStation) {
  const int domain = 200 + static_cast<int>(getpid() % 30);  // reservations and marks only: no port is bound
  BackendOptions interp, servo;
  interp.participant_name = "cell-interpreter/PT01";
  servo.participant_name = "cell-axis-servo/PT01";
  for (BackendOptions* o : {&interp, &servo}) {
    o->station_process = true;
    o->domain = domain;
  }
  auto first = slots::Slot::Take(interp, 21);
  ASSERT_EQ(first.number(), 21);
  ASSERT_TRUE(first.marked());
  EXPECT_TRUE(first.found().empty());                    // first: no partner yet
  EXPECT_EQ(slots::Slot::Take(servo, 21).number(), -1);  // reserved: no other process takes it
  {
    auto second = slots::Slot::Take(servo, 30);
    EXPECT_EQ(second.found(), std::vector<int>{21});
    // Its own host: the shared slots and the partner's; another host: the shared slots.
    std::vector<int> want;
    for (int s = 0; s < kSharedSlots; ++s) want.push_back(s);
    EXPECT_EQ(slots::AnnouncedSlots(servo, true, second), want);
    want.push_back(21);
    EXPECT_EQ(slots::AnnouncedSlots(servo, false, second), want);
    // A second interpreter of PT01 finds the first (and the servo): the identity claim reaches it.
    auto rival = slots::Slot::Take(interp, 22);
    auto found = rival.found();
    std::sort(found.begin(), found.end());
    EXPECT_EQ(found, (std::vector<int>{21, 30}));
    // Another station's process, or the same on another domain, finds none of these.
    BackendOptions other = servo;
    other.participant_name = "cell-axis-servo/PT02";
    EXPECT_TRUE(slots::Slot::Take(other, 40).found().empty());
    other = servo;
    other.domain = domain + 1;
    EXPECT_TRUE(slots::Slot::Take(other, 40).found().empty());
  }
  // The servo has gone (its mark with it): a restarted servo finds the interpreter, even in the slot the old
  // one held; a process that is no station's is reserved, not marked; one without a slot announces itself to
  // every slot of its host.
  EXPECT_EQ(slots::Slot::Take(servo, 30).found(), std::vector<int>{21});
  BackendOptions client = servo;
  client.station_process = false;
  const auto unmarked = slots::Slot::Take(client, 50);
  EXPECT_EQ(unmarked.number(), 50);
  EXPECT_FALSE(unmarked.marked());
  EXPECT_TRUE(slots::AnnouncedSlots(servo, false, slots::Slot{}).empty());
  // The listing's format (a line of /proc/net/unix ends in the path; '@' for an abstract socket's NUL).
  const std::string text =
      "Num       RefCount Protocol Flags    Type St Inode Path\n"
      "0000000000000000: 00000002 00000000 00000000 0002 01 1 @cell-name/7/cell-axis-servo/A1/17\n"
      "0000000000000000: 00000002 00000000 00000000 0002 01 2 @cell-name/7/cell-axis-servo/A1/x\n"
      "0000000000000000: 00000002 00000000 00000000 0002 01 3 @cell-name/70/cell-axis-servo/A1/18\n"
      "0000000000000000: 00000002 00000000 00000000 0002 01 4 /run/cell-name/7/cell-axis-servo/A1/19\n"
      "0000000000000000: 00000002 00000000 00000000 0002 01 5 @cell-name/7/cell-axis-servo/A1/20";
  EXPECT_EQ(slots::FindMarks(text, 7, {"cell-axis-servo/A1"}, -1), (std::vector<int>{17, 20}));
  EXPECT_EQ(slots::FindMarks(text, 7, {"cell-axis-servo/A1"}, 20), std::vector<int>{17});
  EXPECT_TRUE(slots::FindMarks(text, 7, {"cell-axis-servo/A"}, -1).empty());
}

// The shipped LAN profiles (deploy/dds/lan.<stack>.xml, CELL_DDS_PROFILE=lan) load on both stacks and
// interoperate; here on 127.0.0.1 as the "LAN" address (tests/interop/two_host_test runs them across a veth).
TEST(Bus, ShippedLanProfilesInteroperate) {
  // The environment as it was, whatever fails below (the other tests use the built-in profile).
  struct Saved {
    std::vector<std::pair<std::string, std::optional<std::string>>> vars;
    ~Saved() {
      for (auto& [k, v] : vars) {
        if (v)
          setenv(k.c_str(), v->c_str(), 1);
        else
          unsetenv(k.c_str());
      }
    }
  } saved;
  for (const char* v : {"CELL_CONFIG_DIR", "CELL_DDS_PROFILE", "CELL_LAN_ADDRESS", "CELL_LAN_PEER"}) {
    const char* old = std::getenv(v);
    saved.vars.emplace_back(v, old ? std::optional<std::string>(old) : std::nullopt);
  }
  const char* src = std::getenv("CELL_SOURCE_DIR");
  ASSERT_NE(src, nullptr) << "CELL_SOURCE_DIR is set by CTest";
  setenv("CELL_CONFIG_DIR", (std::filesystem::path(src) / "deploy").c_str(), 1);
  setenv("CELL_DDS_PROFILE", "lan", 1);
  unsetenv("CELL_LAN_PEER");
  unsetenv("CELL_LAN_ADDRESS");
  try {
    Participant p(Named("x", "cyclonedds"));
    FAIL() << "the LAN profile without CELL_LAN_ADDRESS was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("CELL_LAN_ADDRESS is not set"), std::string::npos) << e.what();
  }
  setenv("CELL_LAN_ADDRESS", "127.0.0.1", 1);
  {
    Participant f(Named("bus-test-lan-fast", "fastdds"));
    Participant c(Named("bus-test-lan-cyclone", "cyclonedds"));
    Writer<cell::StationStatus> wf(f, "test/lan/f2c", QosKind::kState);
    Reader<cell::StationStatus> rc(c, "test/lan/f2c", QosKind::kState);
    Writer<cell::StationStatus> wc(c, "test/lan/c2f", QosKind::kState);
    Reader<cell::StationStatus> rf(f, "test/lan/c2f", QosKind::kState);
    wf.Write(Status("KT01", 1));
    wc.Write(Status("KT02", 2));
    auto a = rc.Take(kMatch);
    auto b = rf.Take(kMatch);
    EXPECT_TRUE(a && a->station() == "KT01");
    EXPECT_TRUE(b && b->station() == "KT02");
  }
  // The LAN profile's peers (this host, the cell host) narrowed to the host services' slots.
  for (const char* stack : {"fastdds", "cyclonedds"}) {
    SCOPED_TRACE(std::string("LAN profile, client on ") + stack);
    ExpectHostServicesClientHearsNoStation(stack);
  }
  // A station's processes, one with the cell host on another address (192.0.2.1, RFC 5737's TEST-NET-1: never
  // a host's own; Cyclone logs that it cannot send there): that peer is narrowed to its shared slots, this
  // host's is not, so the interpreter and the servo of a station still meet each other here. (The Fast DDS
  // one keeps the profile it loaded above: a process loads one Fast DDS profile.)
  {
    Participant interp(Named("cell-interpreter/BT01", "fastdds"));
    setenv("CELL_LAN_PEER", "192.0.2.1", 1);
    Participant servo(Named("cell-axis-servo/BT01", "cyclonedds"));
    Writer<cell::StationStatus> wi(interp, "test/lan/partner", QosKind::kState);
    Reader<cell::StationStatus> rs(servo, "test/lan/partner", QosKind::kState);
    wi.Write(Status("BT01", 3));
    auto got = rs.Take(kMatch);
    EXPECT_TRUE(got && got->station() == "BT01");
  }
}

}  // namespace
}  // namespace cell::bus
