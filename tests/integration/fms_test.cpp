// FMS dispatch across real processes (issue 7): `cellctl up` starts the cell on this test's private DDS
// domain (virtual machine clock), and every step goes through `cellctl` verbs, as an operator would:
// backlog balancing between two stations, the UTL tool check (and a TLD load releasing a waiting pallet),
// a `kill -9` of the scheduler in the middle of a run, an axis servo stopped past the DDS lease, and bad
// input.
//
// Determinism without fixed sleeps: a pallet is held "in the middle of its run" by the station's feed hold
// (`cellctl station hold`, which returns once the servo reports the hold in effect); `station resume` lets
// the run finish. Conditions are waited for with deadlines (`job wait --timeout`, or polling `job show` /
// `inspect ls` until a predicate holds).
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <thread>

#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/idl/motion.h"
#include "cell/idl/station.h"
#include "cell/testing/local_cell.h"

using namespace cell::testing;
using nlohmann::json;

namespace {

// A short KT-APL program with the KT/FMS heading.
std::string Program(const std::string& name, const std::string& utl, int ucy) {
  return "%\n(NAM," + name + ")\n(UTL," + utl + ")\n(UCY," + std::to_string(ucy) +
         ")\nN10 G71 G90 G01\nN20 X0 Y0 Z100. F0\nN30 X50. Y20. Z10. F2000.\nN40 G00 X0 Y0 Z100. F0\nN50 "
         "M30\n%\n";
}

// A JSON scalar as MTConnect writes the value: strings bare, numbers in decimal.
std::string Str(const json& v) {
  return v.is_string() ? v.get<std::string>() : v.dump();
}

std::string FirstLine(const std::string& s) {
  return s.substr(0, s.find('\n'));
}

class Fms : public ::testing::Test {
 protected:
  void SetUp() override {
    auto r = cell_.Up("KT01,KT02", "virtual");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
  }
  void TearDown() override {
    for (pid_t pid : stopped_) kill(pid, SIGCONT);  // a stopped process would ignore SIGTERM
    if (restarted_) {                               // not in cell-up.json: stop it ourselves
      restarted_->Signal(SIGTERM);
      if (!restarted_->Wait(std::chrono::seconds(10))) restarted_->Signal(SIGKILL);
      restarted_.reset();
    }
    auto r = cell_.Down();  // LocalCell kills leftovers of a failed `down` and removes the data dir
    EXPECT_EQ(r.code, 0) << r.err;
  }

  RunResult Ctl(std::vector<std::string> args) { return cell_.Ctl(std::move(args)); }
  json CtlJson(std::vector<std::string> args) { return cell_.Json(std::move(args)); }
  void Put(const std::string& name, const std::string& text) {
    std::string path = data_ + "/" + name + ".apl";
    std::ofstream(path) << text;
    auto r = Ctl({"program", "put", path});
    ASSERT_EQ(r.code, 0) << r.err;
  }
  std::string Operate(const std::string& route, int pallet) {
    auto r = Ctl({"route", "operate", route, "--pallet", std::to_string(pallet)});
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.out, FirstLine(r.out) + "\n");  // only the job id
    return FirstLine(r.out);
  }
  json Job(const std::string& id) { return CtlJson({"job", "show", id, "--json"}); }
  // Polls `job show` until pred holds (deadline, not a fixed sleep).
  json WaitJob(const std::string& id, const std::function<bool(const json&)>& pred,
               std::chrono::seconds timeout = std::chrono::seconds(20)) {
    auto deadline = std::chrono::steady_clock::now() + timeout;
    json j;
    while (std::chrono::steady_clock::now() < deadline) {
      j = Job(id);
      if (!j.is_null() && pred(j)) return j;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    ADD_FAILURE() << "job " << id << " did not reach the expected state: " << j.dump();
    return j;
  }
  void ExpectCompleted(const std::string& id) {
    auto w = Ctl({"job", "wait", id, "--timeout", "30"});
    EXPECT_EQ(w.code, 0) << w.out << w.err;
    EXPECT_EQ(w.out, "COMPLETED\n");
  }
  pid_t Pid(const std::string& service) {
    auto pids = cell_.Pids();
    if (auto it = pids.find(service); it != pids.end()) return it->second;
    ADD_FAILURE() << "no " << service << " in cell-up.json";
    return -1;
  }
  void Freeze(const std::string& service) {
    pid_t pid = Pid(service);
    ASSERT_GT(pid, 0);
    ASSERT_EQ(kill(pid, SIGSTOP), 0);
    frozen_at_ = std::chrono::steady_clock::now();
    stopped_.push_back(pid);
  }
  // Continued no sooner than 3 s after Freeze: a process finds it stood still (and rejoins) after 2.5 s
  // (bus::Participant::Watch), and its peers' view of its lease can run out sooner than that when a loaded
  // machine had already delayed its last announcement before the stop (seen once under the sanitizers).
  void Thaw(const std::string& service) {
    std::this_thread::sleep_until(frozen_at_ + std::chrono::seconds(3));
    kill(Pid(service), SIGCONT);
  }
  void Hold(const std::string& station) {
    auto r = Ctl({"station", "hold", station});
    ASSERT_EQ(r.code, 0) << r.err;
  }
  // A pallet on a route of KT01 only, held in the middle of its run by KT01's feed hold; returns the job id.
  std::string HeldMidRun(const std::string& program, int ucy, int pallet) {
    Put(program, Program(program, "1001", ucy));
    EXPECT_EQ(Ctl({"route", "define", "R" + program, "--op", "KT01:" + program}).code, 0);
    Hold("KT01");
    const std::string job = Operate("R" + program, pallet);
    WaitJob(job, [](const json& j) { return j["state"] == "RUNNING"; });
    return job;
  }
  void Resume(const std::string& station) {
    auto r = Ctl({"station", "resume", station});
    ASSERT_EQ(r.code, 0) << r.err;
  }
  // Run records (`inspect ls` + `inspect cat`) of a pallet.
  std::vector<json> RunRecords(int pallet) {
    std::vector<json> out;
    for (auto& row : CtlJson({"inspect", "ls", "--json"})) {
      if (row["kind"] != "run") continue;
      auto c = Ctl({"inspect", "cat", row["name"].get<std::string>()});
      if (c.code != 0) continue;
      auto rec = json::parse(c.out);
      if (rec["pallet"] == pallet) out.push_back(rec);
    }
    return out;
  }

  LocalCell cell_{"cell-fms-"};
  const std::string& data_ = cell_.data_dir();
  std::vector<pid_t> stopped_;
  std::chrono::steady_clock::time_point frozen_at_;
  std::unique_ptr<Process> restarted_;
};

// (a) Two pallets on a route eligible on KT01,KT02 go one to each station: the first by the tie rule, the
// second by the shortest backlog, which `station ls` shows.
TEST_F(Fms, BacklogBalancesTwoPalletsAcrossStations) {
  Put("BAL1", Program("BAL1", "1001", 100));
  ASSERT_EQ(Ctl({"route", "define", "RB", "--op", "KT01,KT02:BAL1"}).code, 0);
  // Pallet 1 stays in the middle of its run on KT01 under feed hold.
  Hold("KT01");
  const std::string j1 = Operate("RB", 1);
  const std::string j2 = Operate("RB", 2);
  WaitJob(j1, [](const json& j) { return j["state"] == "RUNNING"; });
  EXPECT_EQ(Ctl({"job", "wait", j1, "--timeout", "1"}).code, 3);  // held: it does not finish
  // KT01 still holds pallet 1's 100 s; the scheduler publishes it.
  auto ls = CtlJson({"station", "ls", "--json"});
  Resume("KT01");
  ASSERT_TRUE(ls.is_array());
  json kt01;
  for (const auto& s : ls)
    if (s["id"] == "KT01") kt01 = s;
  ASSERT_TRUE(kt01.is_object()) << ls.dump();
  EXPECT_EQ(kt01["backlog_s"], 100.0);
  EXPECT_EQ(kt01["execution"], "FEED_HOLD");
  EXPECT_EQ(kt01["pallet"], 1);

  ExpectCompleted(j1);
  ExpectCompleted(j2);
  auto first = Job(j1);
  auto second = Job(j2);
  EXPECT_EQ(first["station"], "KT01");
  EXPECT_EQ(second["station"], "KT02");
  ASSERT_FALSE(first["decisions"].empty());
  auto d1 = first["decisions"][0];
  EXPECT_EQ(d1["trigger"], "operate");
  EXPECT_EQ(d1["winner"], "KT01");
  EXPECT_NE(d1["why"].get<std::string>().find("tie at backlog 0 s"), std::string::npos) << d1;
  EXPECT_NE(d1["why"].get<std::string>().find("KT01 is listed first"), std::string::npos) << d1;
  EXPECT_EQ(d1["added_backlog_s"], 100);
  ASSERT_FALSE(second["decisions"].empty());
  auto d2 = second["decisions"][0];
  EXPECT_EQ(d2["winner"], "KT02");
  EXPECT_NE(d2["why"].get<std::string>().find("shortest backlog"), std::string::npos) << d2;
  ASSERT_EQ(d2["considered"].size(), 2u);
  EXPECT_EQ(d2["considered"][0]["station"], "KT01");
  EXPECT_EQ(d2["considered"][0]["backlog_s"], 100);  // the input of the decision
  EXPECT_EQ(d2["considered"][1]["backlog_s"], 0);
  // Both visits ended: the backlog is gone.
  auto ls2 = CtlJson({"station", "ls", "--json"});
  EXPECT_EQ(ls2[0]["backlog_s"], 0.0);
  EXPECT_EQ(ls2[1]["backlog_s"], 0.0);
}

// (b) The UTL check: a route needing tool 2001 goes to KT02 (only KT02 holds it, deploy/stations) although
// KT01 is listed first; a route needing a tool no station holds waits naming it, until a TLD load adds it.
TEST_F(Fms, ToolCheckRejectsStationsWithoutTheToolsAndTldLoadReleases) {
  Put("T2001", Program("T2001", "1001,2001", 30));
  Put("T7777", Program("T7777", "7777", 30));
  ASSERT_EQ(Ctl({"route", "define", "R2001", "--op", "KT01,KT02:T2001"}).code, 0);
  ASSERT_EQ(Ctl({"route", "define", "R7777", "--op", "KT01,KT02:T7777"}).code, 0);

  const std::string j1 = Operate("R2001", 5);
  ExpectCompleted(j1);
  auto a = Job(j1);
  EXPECT_EQ(a["station"], "KT02");
  auto d = a["decisions"][0];
  EXPECT_EQ(d["winner"], "KT02");
  EXPECT_EQ(d["considered"][0]["station"], "KT01");
  EXPECT_EQ(d["considered"][0]["eligible"], false);
  EXPECT_EQ(d["considered"][0]["missing_tools"], json({"2001"}));

  const std::string j2 = Operate("R7777", 6);
  auto w = Ctl({"job", "wait", j2, "--timeout", "1"});
  EXPECT_EQ(w.code, 3) << w.out << w.err;  // still waiting
  auto b = Job(j2);
  EXPECT_EQ(b["state"], "WAITING");
  ASSERT_TRUE(b["reason"].is_string());
  const std::string reason = b["reason"];
  EXPECT_NE(reason.find("KT01 missing tools 7777"), std::string::npos) << reason;
  EXPECT_NE(reason.find("KT02 missing tools 7777"), std::string::npos) << reason;

  // The tool arrives on KT01 (TLD, as the control loads it): the pallet is released there.
  std::string tld = data_ + "/t7777.tld";
  std::ofstream(tld) << "%\n(TLD,S9T7777P120.D16.L200)\n%\n";
  auto load = Ctl({"tools", "load", "KT01", tld});
  ASSERT_EQ(load.code, 0) << load.err;
  auto tools = CtlJson({"station", "tools", "KT01", "--json"});
  bool has = false;
  for (auto& t : tools) has = has || t["tool"] == "7777";
  EXPECT_TRUE(has) << tools;
  ExpectCompleted(j2);
  auto c = Job(j2);
  EXPECT_EQ(c["station"], "KT01");
  EXPECT_TRUE(c["reason"].is_null());
  ASSERT_GE(c["decisions"].size(), 2u);
  auto last = c["decisions"].back();
  EXPECT_EQ(last["winner"], "KT01");
  EXPECT_NE(last["trigger"].get<std::string>().find("KT01"), std::string::npos) << last;
}

// (c) kill -9 of the scheduler while a pallet runs: the station finishes the run meanwhile, the scheduler
// is started again with the same command line and environment, and the job completes exactly once.
TEST_F(Fms, SchedulerKilledMidRunRestartsAndJobCompletesExactlyOnce) {
  const std::string job = HeldMidRun("KILL1", 40, 7);

  // The scheduler's command line and environment, as `cellctl up` started it.
  pid_t sched = Pid("cell-scheduler");
  ASSERT_GT(sched, 0);
  const std::vector<std::string> argv = ProcessArgv(sched);
  std::map<std::string, std::string> env = ProcessEnvironment(sched);
  ASSERT_FALSE(argv.empty());
  EXPECT_EQ(std::filesystem::path(argv[0]).filename(), "cell-scheduler");
  EXPECT_EQ(env["CELL_DATA_DIR"], data_);
  ASSERT_EQ(kill(sched, SIGKILL), 0);
  {  // The restarted scheduler is this test's child (TearDown stops it): `cellctl down` is not to wait for
     // it.
    json rest = json::array();
    for (auto& p : json::parse(ReadFile(data_ + "/cell-up.json")))
      if (p["service"] != "cell-scheduler") rest.push_back(p);
    std::ofstream(data_ + "/cell-up.json") << rest.dump(2);
  }

  // A `job wait` with a timeout while the scheduler is down waits for it to the end, then says so: exit 3
  // (DESIGN: 3 on timeout), not a failed command.
  {
    auto w = Ctl({"job", "wait", job, "--timeout", "2"});
    EXPECT_EQ(w.code, 3) << w.out << w.err;
    EXPECT_NE(w.err.find("still unknown (no answer from the scheduler yet) after 2"), std::string::npos)
        << w.err;
  }

  // While the scheduler is down the station finishes the run and stores its record.
  Resume("KT01");
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (RunRecords(7).empty() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ASSERT_EQ(RunRecords(7).size(), 1u);

  restarted_ = std::make_unique<Process>(argv, env, data_ + "/logs/cell-scheduler.restarted.out",
                                         data_ + "/logs/cell-scheduler.restarted.log");
  ExpectCompleted(job);
  auto j = Job(job);
  EXPECT_EQ(j["station"], "KT01");
  EXPECT_TRUE(j["cycle_s"].is_number());
  // Exactly once: one job for the pallet, one run record for it on the station, no backlog left.
  int jobs = 0;
  for (auto& row : CtlJson({"job", "ls", "--json"})) jobs += row["pallet"] == 7 ? 1 : 0;
  EXPECT_EQ(jobs, 1);
  auto recs = RunRecords(7);
  ASSERT_EQ(recs.size(), 1u);
  EXPECT_EQ(recs[0]["station"], "KT01");
  EXPECT_EQ(recs[0]["completed"], true);
  // The restarted scheduler goes on dispatching: the same pallet runs again as a new job.
  const std::string again = Operate("RKILL1", 7);
  EXPECT_NE(again, job);
  ExpectCompleted(again);
  EXPECT_EQ(RunRecords(7).size(), 2u);
}

// (e) An axis servo stopped (SIGSTOP) until the DDS lease has run out, then continued. Its peers dropped it
// meanwhile and Fast DDS 2.9 may not exchange endpoints again with a participant that kept its own view, so
// the servo, finding it stood still past the lease, joins the bus with a new participant; the interpreter
// sends again what the servo has not reported received (the segment stream is volatile), the servo drops
// what it already has, and the run completes once. The station then takes the next pallet. This test
// watches the lease through its own writer on the servo's segment topic (never written to). The servo is
// stopped in the middle of the run (held by the feed hold, so the run is on the machine and cannot end
// meanwhile): stopped before the dispatch, a dispatch delayed on a loaded machine found no servo and the
// station's own wait for one ran out first (issue 44, a flake).
TEST_F(Fms, ServoStoppedPastItsLeaseRejoinsAndFinishesTheRun) {
  cell::bus::Participant observer("fms-test/observer");
  cell::bus::Writer<cell::MotionSegment> watch(observer, cell::bus::topics::Segments("KT01"),
                                               cell::bus::QosKind::kStream);
  ASSERT_TRUE(watch.WaitForMatched(1, std::chrono::seconds(10)));
  const std::string job = HeldMidRun("LEASE1", 20, 9);

  Freeze("cell-axis-servo/KT01");
  ASSERT_TRUE(cell::bus::WaitUntil([&] { return watch.Matched() == 0; }, std::chrono::seconds(15)))
      << "the stopped servo's lease did not run out";
  Thaw("cell-axis-servo/KT01");
  Resume("KT01");
  ExpectCompleted(job);
  auto recs = RunRecords(9);
  ASSERT_EQ(recs.size(), 1u);
  EXPECT_EQ(recs[0]["completed"], true);
  EXPECT_GT(recs[0]["machine_s"].get<double>(), 0.0);
  const std::string log = ReadFile(data_ + "/logs/cell-axis-servo@KT01.service.log");
  EXPECT_NE(log.find("joining the bus anew"), std::string::npos) << log;
  ExpectCompleted(Operate("RLEASE1", 10));
}

// (e) The same for a station's interpreter stopped past its lease in the middle of a run: while it is stopped
// the scheduler takes the station for vanished and waits for its word on the pallet it holds (docs/
// scheduler.md §5), and the lease runs out (watched through a writer on the station's command topic).
// When it continues it rejoins the bus, the scheduler asks it about the pallet, and the run it never stopped
// completes: once, one record. Before stop 55 the pallet was failed at once ("needs an operator") although
// the station went on to finish it.
TEST_F(Fms, InterpreterStoppedPastItsLeaseRejoinsAndTheStationGoesOn) {
  cell::bus::Participant observer("fms-test/observer");
  cell::bus::Writer<cell::StationRequest> watch(
      observer, cell::bus::RequestTopic(cell::bus::topics::StationCommand("KT01")),
      cell::bus::QosKind::kCommand);
  ASSERT_TRUE(watch.WaitForMatched(1, std::chrono::seconds(10)));
  const std::string job = HeldMidRun("STOP1", 20, 13);
  Freeze("cell-interpreter/KT01");
  auto waiting = WaitJob(job, [](const json& j) { return j["reason"].is_string(); });
  EXPECT_EQ(waiting["state"], "RUNNING") << waiting;
  EXPECT_NE(
      waiting["reason"].get<std::string>().find("went offline holding pallet 13: waiting for its report"),
      std::string::npos)
      << waiting;
  ASSERT_TRUE(cell::bus::WaitUntil([&] { return watch.Matched() == 0; }, std::chrono::seconds(15)))
      << "the stopped interpreter's lease did not run out";
  Thaw("cell-interpreter/KT01");
  Resume("KT01");
  ExpectCompleted(job);
  ExpectCompleted(Operate("RSTOP1", 14));
  const std::string log = ReadFile(data_ + "/logs/cell-interpreter@KT01.service.log");
  EXPECT_NE(log.find("joining the bus anew"), std::string::npos) << log;
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (RunRecords(13).empty() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  auto recs = RunRecords(13);
  ASSERT_EQ(recs.size(), 1u) << "the held run's record was not filed";
  EXPECT_EQ(recs[0]["completed"], true);
}

// (e2) kill -9 of a station's interpreter in the middle of a run: the scheduler waits for the station's word
// (the station went offline holding the pallet); the restarted interpreter says the run was lost, so the job
// fails (the pallet needs an operator) and the lost run's record is filed, so there is one record per
// dispatch, failed ones included (docs/inspection-writer.md; issue 39 item 7: there was none).
TEST_F(Fms, InterpreterKilledMidRunLeavesOneFailedRunRecord) {
  const std::string job = HeldMidRun("KILL2", 20, 15);
  const pid_t interp = Pid("cell-interpreter/KT01");
  ASSERT_GT(interp, 0);
  ASSERT_EQ(kill(interp, SIGKILL), 0);
  auto waiting = WaitJob(job, [](const json& j) { return j["reason"].is_string(); });
  EXPECT_EQ(waiting["state"], "RUNNING") << waiting;
  auto restart = Ctl({"restart", "cell-interpreter/KT01"});
  ASSERT_EQ(restart.code, 0) << restart.err;
  auto failed = WaitJob(job, [](const json& j) { return j["state"] == "FAILED"; });
  EXPECT_EQ(
      failed["reason"],
      "station KT01 went offline while running pallet 15 (program 1 of 1): station restarted during the "
      "run; the pallet needs an operator")
      << failed;
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (RunRecords(15).empty() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  auto recs = RunRecords(15);
  ASSERT_EQ(recs.size(), 1u) << "the killed run left no record";
  EXPECT_EQ(recs[0]["completed"], false);
  EXPECT_EQ(recs[0]["reason"], "station restarted during the run");
  EXPECT_EQ(recs[0]["station"], "KT01");
  Resume("KT01");  // the panel's hold outlives the restart
  ExpectCompleted(Operate("RKILL2", 16));
  EXPECT_EQ(RunRecords(15).size(), 1u);
}

// (f) `job cancel` of a pallet in the middle of its run (held by the feed hold) stops it on the machine
// as well: the job ends CANCELLED, the servo aborts the run, and the station takes the next pallet.
TEST_F(Fms, CancelStopsARunningPalletOnTheMachine) {
  const std::string job = HeldMidRun("CAN1", 30, 11);
  ASSERT_EQ(Ctl({"job", "cancel", job}).code, 0);
  auto w = Ctl({"job", "wait", job, "--timeout", "30"});
  EXPECT_EQ(w.code, 1) << w.out << w.err;
  EXPECT_EQ(w.out, "CANCELLED\n");
  Resume("KT01");
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (RunRecords(11).empty() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  auto recs = RunRecords(11);
  ASSERT_EQ(recs.size(), 1u);
  EXPECT_EQ(recs[0]["completed"], false);
  const std::string log = ReadFile(data_ + "/logs/cell-axis-servo@KT01.service.log");
  EXPECT_NE(log.find("cancelled: aborting it"), std::string::npos) << log;
  ExpectCompleted(Operate("RCAN1", 12));
}

// (d) Bad input: one-line reasons and the documented exit codes.
TEST_F(Fms, BadInput) {
  auto one_line = [](const RunResult& r) { return !r.err.empty() && r.err.find('\n') == r.err.size() - 1; };
  Put("GOOD1", Program("GOOD1", "1001", 10));
  // Unknown station.
  for (auto args : std::vector<std::vector<std::string>>{{"pallet", "run", "3", "--station", "KT99"},
                                                         {"tools", "load", "KT99", "/dev/null"},
                                                         {"route", "define", "RX", "--op", "KT99:GOOD1"}}) {
    auto r = Ctl(args);
    EXPECT_NE(r.code, 0) << args[0];
    EXPECT_TRUE(one_line(r)) << r.err;
    EXPECT_NE(r.err.find("KT99"), std::string::npos) << r.err;
  }
  // Missing program in route define.
  auto m = Ctl({"route", "define", "RM", "--op", "KT01,KT02:GOOD1,NOSUCH"});
  EXPECT_NE(m.code, 0);
  EXPECT_TRUE(one_line(m)) << m.err;
  EXPECT_NE(m.err.find("NOSUCH"), std::string::npos) << m.err;
  EXPECT_NE(Ctl({"route", "show", "RM"}).code, 0);  // nothing was defined
  // Malformed --op.
  for (std::string op : {"KT01", "KT01:", ":GOOD1", "KT01,:GOOD1"}) {
    auto r = Ctl({"route", "define", "RO", "--op", op});
    EXPECT_NE(r.code, 0) << op;
    EXPECT_TRUE(one_line(r)) << op << ": " << r.err;
  }
  // Unknown route.
  auto u = Ctl({"route", "operate", "NOROUTE", "--pallet", "1"});
  EXPECT_NE(u.code, 0);
  EXPECT_NE(u.err.find("NOROUTE"), std::string::npos) << u.err;
  // A route naming no eligible station: KT03 is configured but not running. The pallet waits with a reason.
  ASSERT_EQ(Ctl({"route", "define", "R3", "--op", "KT03:GOOD1"}).code, 0);
  const std::string job = Operate("R3", 9);
  auto w = Ctl({"job", "wait", job, "--timeout", "0.5"});
  EXPECT_EQ(w.code, 3) << w.out << w.err;
  EXPECT_EQ(w.out, "WAITING\n");
  auto j = Job(job);
  EXPECT_EQ(j["state"], "WAITING");
  EXPECT_NE(j["reason"].get<std::string>().find("KT03 offline"), std::string::npos) << j["reason"];
  // The same pallet cannot be in two live jobs.
  auto twice = Ctl({"route", "operate", "R3", "--pallet", "9"});
  EXPECT_NE(twice.code, 0);
  EXPECT_TRUE(one_line(twice)) << twice.err;
  // Unknown job id: exit 2 for wait and show.
  for (std::string verb : {"wait", "show"}) {
    auto r = Ctl({"job", verb, "4242"});
    EXPECT_EQ(r.code, 2) << verb << ": " << r.err;
    EXPECT_TRUE(one_line(r)) << r.err;
  }
  EXPECT_EQ(Ctl({"job", "cancel", "4242"}).code, 2);
  // The panel verbs: unknown or unstarted stations, overrides out of range or missing.
  for (auto args : std::vector<std::vector<std::string>>{{"station", "hold", "KT99"},
                                                         {"station", "resume", "KT03"},
                                                         {"station", "override", "KT01", "--feed", "250"},
                                                         {"station", "override", "KT01", "--rapid", "-5"},
                                                         {"station", "override", "KT01"}}) {
    auto r = Ctl(args);
    EXPECT_NE(r.code, 0) << args[1] << " " << args[2];
    EXPECT_TRUE(one_line(r)) << r.err;
  }
}

// Okuma schedule program through the scheduler service: VSET goes to the station's common variables before
// the dispatches, and PSELECT Q=2 runs the main program twice, one run after another. A KT-APL station runs
// it here, with a KT-APL program stored under the main program file's name (the scheduler does not tie
// schedules to a dialect); okuma_cell_test runs the manual's own schedule on OK01.
TEST_F(Fms, ScheduleProgramSetsVariablesAndRunsPselectRepeats) {
  std::string main_prog = data_ + "/a.apl";
  std::ofstream(main_prog) << Program("AMIN", "1001", 5);
  auto put = Ctl({"program", "put", main_prog, "--name", "A.MIN"});
  ASSERT_EQ(put.code, 0) << put.err;
  std::string sdf = data_ + "/S1.SDF";
  std::ofstream(sdf) << "N001 VSET V5=7\nN002 PSELECT A.MIN,O100,,Q=2\nEND\n";
  auto run = Ctl({"schedule", "run", sdf, "--station", "KT01"});
  ASSERT_EQ(run.code, 0) << run.err;
  const std::string job = FirstLine(run.out);
  ASSERT_EQ(run.out, job + "\n");
  // DESIGN §6: the local file was stored first in the station's namespace.
  auto stored = CtlJson({"program", "ls", "S1.SDF", "--node", "KT01", "--json"});
  ASSERT_TRUE(stored.is_array());
  ASSERT_EQ(stored.size(), 1u) << stored;
  EXPECT_EQ(stored[0]["type"], "schedule") << stored;
  ExpectCompleted(job);
  auto vars = CtlJson({"station", "vars", "KT01", "--json"});
  EXPECT_EQ(vars["V5"], 7) << vars;
  auto j = Job(job);
  EXPECT_EQ(j["station"], "KT01");
  auto count_runs = [&] {
    int n = 0;
    for (auto& row : CtlJson({"inspect", "ls", "--json"})) n += row["kind"] == "run" ? 1 : 0;
    return n;
  };
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (count_runs() < 2 && std::chrono::steady_clock::now() < deadline)  // records are stored after the run
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(count_runs(), 2);
  // A schedule that does not parse is refused with the alarm.
  std::string bad = data_ + "/BAD.SDF";
  std::ofstream(bad) << "N001 G01 X10\nEND\n";
  auto r = Ctl({"schedule", "run", bad, "--station", "KT01"});
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("BAD.SDF:1:"), std::string::npos) << r.err;
}

}  // namespace

// Issue 37: one rendering per record. KT01 holds a pallet mid-run (FEED_HOLD), KT02 runs idle (READY), KT03
// is configured but not started: `station ls --json`, the dashboard's /api/state and its MTConnect /current
// say the same of each, field by field, and `job show --json` is the page's job.
TEST_F(Fms, EveryViewRendersTheSameStationRowsAndJob) {
  const std::string job = HeldMidRun("ONE37", 60, 37);
  std::string url = ReadFile(data_ + "/dashboard.url");
  url = url.substr(0, url.find('\n'));
  ASSERT_NE(url.find("http://127.0.0.1:"), std::string::npos) << url;
  httplib::Client http("127.0.0.1", std::stoi(url.substr(url.rfind(':') + 1)));
  auto get = [&](const std::string& path) {
    auto r = http.Get(path);
    if (!r) ADD_FAILURE() << path << ": " << httplib::to_string(r.error());
    return r && r->status == 200 ? r->body : std::string();
  };
  const json ls = CtlJson({"station", "ls", "--json"});
  ASSERT_TRUE(ls.is_array());
  std::map<std::string, json> rows;
  for (const auto& r : ls) rows[r["id"].get<std::string>()] = r;
  ASSERT_TRUE(rows.count("KT01") && rows.count("KT02") && rows.count("KT03")) << ls.dump();
  EXPECT_EQ(rows["KT01"]["execution"], "FEED_HOLD");
  EXPECT_EQ(rows["KT01"]["pallet"], 37);
  EXPECT_EQ(rows["KT02"]["execution"], "READY");
  EXPECT_EQ(rows["KT02"]["condition"], "NORMAL");
  EXPECT_EQ(rows["KT03"]["online"], false);
  EXPECT_EQ(rows["KT03"]["execution"], "UNAVAILABLE");
  EXPECT_EQ(rows["KT03"]["condition"], "UNAVAILABLE");  // not announced (DESIGN §3 and §6)

  // The page follows the topics on its own: poll until it has caught up (deadline, no fixed sleep), then
  // every key of every `station ls` row must be the page's.
  auto page_rows = [&] {
    std::map<std::string, json> out;
    auto text = get("/api/state");
    if (text.empty()) return out;
    const json state = json::parse(text);  // kept: a range over a temporary's member dangles
    for (const auto& r : state["stations"]) out[r["id"].get<std::string>()] = r;
    return out;
  };
  auto same = [&](const std::map<std::string, json>& page) {
    for (const auto& [id, row] : rows) {
      if (!page.count(id)) return false;
      for (const auto& [k, v] : row.items())
        if (page.at(id).value(k, json("<missing>")) != v) return false;
    }
    return true;
  };
  std::map<std::string, json> page;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
  while (!same(page = page_rows()) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  for (const auto& [id, row] : rows) {
    ASSERT_TRUE(page.count(id)) << id;
    for (const auto& [k, v] : row.items())
      EXPECT_EQ(page[id].value(k, json("<missing>")), v) << id << " " << k;
  }

  // MTConnect says it in its own words: the Path's Execution, Program, LineNumber and PalletId, the System
  // condition's level, the Device's Availability.
  const std::string current = get("/current");
  ASSERT_FALSE(current.empty());
  // Plain string search (std::regex trips GCC 12's maybe-uninitialized warning in the sanitizer build).
  auto element = [](const std::string& doc, const std::string& tag) {
    const auto open = doc.find("<" + tag + " ");
    if (open == std::string::npos) return std::string("-");
    const auto text = doc.find('>', open);
    const auto close = doc.find("</" + tag + ">", text);
    if (text == std::string::npos || close == std::string::npos) return std::string("-");
    return doc.substr(text + 1, close - text - 1);
  };
  for (const auto& id : {"KT01", "KT02", "KT03"}) {
    const auto from = current.find(std::string("<DeviceStream name=\"") + id + "\"");
    ASSERT_NE(from, std::string::npos) << id;
    const std::string dev = current.substr(from, current.find("</DeviceStream>", from) - from);
    const json& row = rows[id];
    auto words = [](const json& v) { return v.is_null() ? std::string("UNAVAILABLE") : Str(v); };
    EXPECT_EQ(element(dev, "Availability"), row["online"] ? "AVAILABLE" : "UNAVAILABLE") << id;
    EXPECT_EQ(element(dev, "Execution"), row["execution"]) << id;
    EXPECT_EQ(element(dev, "Program"), words(row["program"])) << id;
    EXPECT_EQ(element(dev, "LineNumber"), words(row["line"])) << id;
    EXPECT_EQ(element(dev, "PalletId"), words(row["pallet"])) << id;
    // The first element inside <Condition>: its tag is the level (Normal, Warning, Fault, Unavailable).
    const auto cond_at = dev.find("<Condition>");
    ASSERT_NE(cond_at, std::string::npos) << dev;
    const auto tag_at = dev.find('<', cond_at + 11);
    ASSERT_NE(tag_at, std::string::npos) << dev;
    std::string cond = dev.substr(tag_at + 1, dev.find_first_of(" />", tag_at + 1) - tag_at - 1);
    for (auto& c : cond) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    EXPECT_EQ(cond, row["condition"]) << id;
  }

  // The job: `job show --json` and the page's (/api/state's row and /api/job/ID with its decisions).
  const json shown = Job(job);
  json row, detail;
  const auto job_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
  do {
    const json state = json::parse(get("/api/state"));
    for (const auto& j : state["jobs"])
      if (std::to_string(j["id"].get<int>()) == job) row = j;
    const std::string d = get("/api/job/" + job);
    detail = d.empty() ? json() : json::parse(d);
    if (row.value("state", "") == shown["state"] && detail.value("state", "") == shown["state"]) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  } while (std::chrono::steady_clock::now() < job_deadline);
  ASSERT_TRUE(row.is_object()) << "no job " << job << " on the page";
  // predicted_s is job show's alone (DESIGN §6b, docs/scheduler.md §14): the job state topic (JobInfo) the
  // page reads does not carry it.
  for (const auto& [k, v] : shown.items()) {
    if (k == "predicted_s") continue;
    if (k != "decisions") {
      EXPECT_EQ(row.value(k, json("<missing>")), v) << k;
    }
    EXPECT_EQ(detail.value(k, json("<missing>")), v) << k;
  }
  EXPECT_EQ(row.size() + 2, shown.size()) << row.dump() << "\n" << shown.dump();  // no key only the page has
  Resume("KT01");
  ExpectCompleted(job);
}
