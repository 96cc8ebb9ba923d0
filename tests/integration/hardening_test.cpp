// Issue 13, each reproduction through the real binaries (domain 71): commands that cannot be confused
// (idempotency keys bind the whole command), inputs that cannot slip through (names, read errors, empty
// input, numbers, sizes), one process per station identity, and a local cell's processes (`up` forks with no
// DDS participant and no descriptor of its own in the services, `restart`, `up` of a partly-down cell, `down`
// that only stops its own processes, owner-only data).
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/health/health.h"
#include "cell/idl/health.h"
#include "cell/idl/inspection.h"
#include "cell/idl/scheduler.h"
#include "cell/testing/local_cell.h"

using namespace cell::testing;
using namespace std::chrono_literals;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

std::string Program(const std::string& name, int ucy) {
  return "%\n(NAM," + name + ")\n(UTL,1001)\n(UCY," + std::to_string(ucy) +
         ")\nN10 G71 G90 G01\nN20 X0 Y0 Z100. F0\nN30 X50. Y20. Z10. F2000.\nN40 M30\n%\n";
}

std::string FirstLine(const std::string& s) {
  return s.substr(0, s.find('\n'));
}

// One line on stderr, and it is short: a bad name is echoed shortened and escaped.
void ExpectOneShortLine(const RunResult& r, const std::string& what) {
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << what << ": " << r.err;
  EXPECT_LT(r.err.size(), 400u) << what << ": " << r.err;
  EXPECT_EQ(r.err.find('\x1b'), std::string::npos) << what << ": a raw escape sequence reached the terminal";
}

json Record(const LocalCell& cell) {
  return json::parse(ReadFile(cell.data_dir() + "/cell-up.json"));
}

// ---------------------------------------------------------------------------------------------------------
// Without a cell: everything here is refused by cellctl itself, before anything is sent (no service runs).
class Offline : public ::testing::Test {
 protected:
  RunResult Ctl(std::vector<std::string> args, std::map<std::string, std::string> env = {}) {
    args.insert(args.begin(), BinDir() + "/cellctl");
    env["CELL_DATA_DIR"] = dir_;
    return RunCommand(args, env, 60s);
  }
  void Refused(std::vector<std::string> args, const std::string& needle, int code = -1,
               std::map<std::string, std::string> env = {}) {
    std::string what;
    for (auto& a : args) what += " " + (a.size() > 60 ? a.substr(0, 60) + "..." : a);
    auto r = Ctl(args, env);
    if (code >= 0)
      EXPECT_EQ(r.code, code) << what << ": " << r.err;
    else
      EXPECT_NE(r.code, 0) << what;
    EXPECT_NE(r.err.find(needle), std::string::npos) << what << ": " << r.err;
    EXPECT_EQ(r.err.find("no cell/"), std::string::npos) << what << ": it went to the bus: " << r.err;
    ExpectOneShortLine(r, what);
  }
  // The quickest of three runs of `args`: how long a verb took, with what the machine's load adds to it
  // spread thin.
  std::chrono::steady_clock::duration Quickest(const std::vector<std::string>& args,
                                               RunResult* last = nullptr) {
    auto took = std::chrono::steady_clock::duration::max();
    for (int attempt = 0; attempt < 3; ++attempt) {
      const auto t0 = std::chrono::steady_clock::now();
      RunResult r = Ctl(args);
      took = std::min(took, std::chrono::steady_clock::now() - t0);
      if (last) *last = std::move(r);
    }
    return took;
  }
  // A verb that is refused before it makes a participant (a missing file): cellctl's own start-up on this
  // machine now, which a sanitized build on a loaded host stretches to seconds. The bounds below are over it.
  std::chrono::steady_clock::duration StartUp() {
    return Quickest({"program", "put", dir_ + "/missing.apl"});
  }
  std::string dir_ = MakeTempDir("cell-hardening-offline-");
  ~Offline() override { fs::remove_all(dir_); }
};

// Item 3: read errors and empty input are errors.
TEST_F(Offline, ReadErrorsAndEmptyInputAreErrors) {
  fs::create_directories(dir_ + "/progs");
  Refused({"program", "put", dir_ + "/progs"}, "is a directory", 1);
  Refused({"program", "put", "/proc/self/mem"}, "cannot read /proc/self/mem", 1);
  std::ofstream(dir_ + "/empty.apl").close();
  Refused({"program", "put", dir_ + "/empty.apl"}, "is empty", 1);
  Refused({"program", "put", dir_ + "/missing.apl"}, "No such file", 1);
  Refused({"tools", "load", "KT01", dir_ + "/progs"}, "is a directory", 1);
  std::ofstream(dir_ + "/tools.bin", std::ios::binary) << std::string(
      "\x7f"
      "ELF\x02\x01\x01\0\0\0",
      10);
  Refused({"tools", "load", "KT01", dir_ + "/tools.bin"}, "content is not text", 1);
  std::ofstream(dir_ + "/notld.apl") << "%\nN10 G71\nN20 M30\n%\n";
  Refused({"tools", "load", "KT01", dir_ + "/notld.apl"}, "no TLD statement found", 1);
  Refused({"route", "define", "R", "--file", dir_ + "/progs"}, "is a directory", 1);
}

// Issue 39 item 6: against a cell that is not running, `station ls` printed a table of offline stations and
// exited 0, and the other verbs took 5.1 s to say "no service". Each says so in one line, non-zero, without
// waiting out the 5 s discovery bound (nothing else is on this test's domain).
TEST_F(Offline, ACellThatIsDownIsSaidSoAtOnce) {
  for (std::vector<std::string> verb : {std::vector<std::string>{"station", "ls"},
                                        {"job", "ls"},
                                        {"program", "ls"},
                                        {"route", "show", "R"}}) {
    // The old path waited out the 5 s discovery bound every time; under load the start-up alone once took
    // 4.8 s (issue 44), so the bound is over cellctl's start-up measured now, beside the verb.
    const auto start_up = StartUp();
    RunResult r;
    const auto took = Quickest(verb, &r);
    const std::string what = verb[0] + " " + verb[1];
    EXPECT_EQ(r.code, 1) << what << ": " << r.out << r.err;
    EXPECT_EQ(r.out, "") << what;
    EXPECT_TRUE(r.err.find("is the cell up?") != std::string::npos ||
                r.err.find("neither the scheduler nor the program store runs") != std::string::npos)
        << what << ": " << r.err;
    ExpectOneShortLine(r, what);
    // The old path waited 5 s for a server; this one 0.8 s for any participant, plus making one.
    EXPECT_LT(took - start_up, 4000ms)
        << what << " (cellctl's start-up alone: "
        << std::chrono::duration_cast<std::chrono::milliseconds>(start_up).count() << " ms)";
  }
}

// Issue 44: a service of another test on its way out (a zombie, its /proc files root's) made every verb
// wait out discovery, taking it for a service that may be on our domain. A zombie named cell-scheduler
// stands for it here.
TEST_F(Offline, AServiceOnItsWayOutIsNoCell) {
  const pid_t zombie = fork();
  ASSERT_GE(zombie, 0);
  if (zombie == 0) {
    prctl(PR_SET_NAME, "cell-scheduler");
    _exit(0);
  }
  // Not reaped until the verb has run: wait until it is a zombie.
  siginfo_t info{};
  ASSERT_EQ(waitid(P_PID, static_cast<id_t>(zombie), &info, WEXITED | WNOWAIT), 0);
  const auto start_up = StartUp();
  RunResult r;
  const auto took = Quickest({"route", "show", "R"}, &r);
  waitpid(zombie, nullptr, 0);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(r.err.find("cell-scheduler (pid"), std::string::npos) << r.err;
  EXPECT_TRUE(r.err.find("is the cell up?") != std::string::npos ||
              r.err.find("neither the scheduler nor the program store runs") != std::string::npos)
      << r.err;
  EXPECT_LT(took - start_up, 4000ms)
      << "cellctl's start-up alone: "
      << std::chrono::duration_cast<std::chrono::milliseconds>(start_up).count() << " ms";
}

// Item 10: integers are decimal; an over-size put is refused from the file's size, before streaming.
TEST_F(Offline, NumbersAreDecimalAndSizesAreCheckedFirst) {
  Refused({"route", "operate", "PUMP", "--pallet", "0x10"}, "expected a decimal integer", 2);
  Refused({"route", "operate", "PUMP", "--pallet", "010x"}, "expected a decimal integer", 2);
  Refused({"pallet", "run", "1e2", "--station", "KT01"}, "expected a decimal integer", 2);
  // A leading zero is still decimal (issue 39 item 5: 0256 was read as octal 174, a pallet in range).
  Refused({"pallet", "show", "0256"}, "pallet 256 is outside 1-255", 2);
  Refused({"route", "operate", "PUMP", "--pallet", "000"}, "pallet 0 is outside 1-255", 2);
  Refused({"job", "show", "-5"}, "", 2);
  Refused({"job", "wait", "7", "--timeout", "0x10"}, "expected a decimal number", 2);
  Refused({"station", "override", "KT01", "--feed", "1e2"}, "expected a decimal number", 2);
  Refused({"station", "vars", "KT01", "--set", "V1=0x10"}, "is not a decimal number", 2);
  // A 257 MiB sparse file: refused at once from its size (no store runs, nothing is read).
  const std::string big = dir_ + "/BIG.apl";
  { std::ofstream(big) << "%\n"; }
  fs::resize_file(big, (257ull << 20));
  auto t0 = std::chrono::steady_clock::now();
  Refused({"program", "put", big}, "is 269484032 bytes; the program store takes at most 268435456 bytes", 1);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 10s);
}

// Item 2: names are checked against their rule before they are sent; never cut, echoed short and escaped.
TEST_F(Offline, NamesAreCheckedBeforeTheyAreSent) {
  Refused({"route", "define", "../x", "--op", "KT01:P"}, "route name '../x': must begin with a letter", 2);
  Refused({"route", "define", "R\x1b[2J", "--op", "KT01:P"}, "'R\\x1b[2J'", 2);
  Refused({"route", "define", std::string(65, 'R'), "--op", "KT01:P"}, "is 65 characters long; at most 64",
          2);
  Refused({"route", "operate", std::string(5000, 'R'), "--pallet", "1"}, "is 5000 characters long", 2);
  Refused({"route", "define", "R", "--op", "KT01:../P"}, "no '/'", 2);
  Refused({"route", "define", "R", "--op", "KT 01:P"}, "station 'KT 01'", 2);
  Refused({"pallet", "set", "1", "A\x07"}, "'A\\x07'", 2);
  Refused({"program", "get", std::string(129, 'P')}, "at most 128", 2);
  Refused({"program", "put", "/etc/hostname", "--name", "a/b"}, "no '/'", 2);
  // Issue 39 item 5: "." and ".." were stored in HOST.
  Refused({"program", "put", "/etc/hostname", "--name", ".."}, "name directories, not programs", 2);
  Refused({"program", "put", "/etc/hostname", "--name", "."}, "name directories, not programs", 2);
  Refused({"program", "ls", "--node", "../KT01"}, "must be HOST, a station id or a station's memory", 2);
  Refused({"station", "tools", "KT01\n"}, "'KT01\\x0a'", 2);
  Refused({"inspect", "cat", "../../etc/passwd"}, "record name", 2);
  // CELLCTL_IDEMPOTENCY_KEY: refused when over its bound, never cut.
  Refused({"route", "operate", "PUMP", "--pallet", "1"}, "41 characters long; at most 40", 2,
          {{"CELLCTL_IDEMPOTENCY_KEY", std::string(41, 'k')}});
  Refused({"route", "operate", "PUMP", "--pallet", "1"}, "without spaces", 2,
          {{"CELLCTL_IDEMPOTENCY_KEY", "a key"}});
  // An empty key is an error, not "no key" (issue 39 item 4, DESIGN section 6).
  Refused({"route", "operate", "PUMP", "--pallet", "1"}, "CELLCTL_IDEMPOTENCY_KEY is set but empty", 2,
          {{"CELLCTL_IDEMPOTENCY_KEY", ""}});
}

// ---------------------------------------------------------------------------------------------------------
class Hardening : public ::testing::Test {
 protected:
  void SetUp() override {
    auto r = cell_.Up("KT01,KT02", "virtual");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
  }
  void TearDown() override {
    auto r = cell_.Down();
    EXPECT_EQ(r.code, 0) << r.err;
  }
  RunResult Ctl(std::vector<std::string> args, std::map<std::string, std::string> env = {}) {
    args.insert(args.begin(), BinDir() + "/cellctl");
    for (auto& [k, v] : cell_.env()) env.emplace(k, v);
    return RunCommand(args, env, 60s);
  }
  void Put(const std::string& name, int ucy = 10) {
    std::string path = cell_.data_dir() + "/" + name + ".apl";
    std::ofstream(path) << Program(name, ucy);
    auto r = Ctl({"program", "put", path});
    ASSERT_EQ(r.code, 0) << r.err;
  }
  int Pid(const std::string& service) { return cell_.Pids().at(service); }
  LocalCell cell_{"cell-hardening-"};
};

// Issue 39 item 2: after 400 `route operate`s `job ls` failed "reply too large; narrow the query". Every
// listing now pages (DESIGN §6: --limit, default 1000; --after, exclusive; job ls --state and --station):
// 400 jobs (operated and cancelled, unless already done, through the scheduler's request topic, the fastest
// way through real processes; 100,000 are paged in the scheduler's unit test job_listing_test) and 560
// inspection files with the longest names are each more than one 64 KiB reply, and cellctl joins the pages.
TEST_F(Hardening, ListingsPageThroughAnySize) {
  Put("PUMP1");
  ASSERT_EQ(Ctl({"route", "define", "PUMP", "--op", "KT01:PUMP1"}).code, 0);
  ASSERT_EQ(Ctl({"route", "define", "VALVE", "--op", "KT02:PUMP1"}).code, 0);
  constexpr int kJobs = 400, kFiles = 560;
  {
    cell::bus::Participant bus("hardening-paging");
    cell::bus::Client<cell::SchedulerRequest, cell::SchedulerReply> sched(bus, cell::bus::topics::kScheduler);
    for (int i = 1; i <= kJobs; ++i) {
      cell::SchedulerRequest op;
      op.op(cell::SCHED_ROUTE_OPERATE);
      op.name(i % 2 ? "PUMP" : "VALVE");
      op.pallet(i % 200 + 1);
      auto rep = sched.Call(op, 30000ms);
      ASSERT_EQ(rep.hdr().code(), 0) << i << ": " << rep.hdr().error();
      cell::SchedulerRequest cancel;
      cancel.op(cell::SCHED_JOB_CANCEL);
      cancel.job_id(rep.job_id());
      auto c = sched.Call(cancel, 30000ms);  // the virtual clock may have finished the job already
      ASSERT_TRUE(c.hdr().code() == 0 || c.hdr().error().to_string().find("is already") != std::string::npos)
          << rep.job_id() << ": " << c.hdr().error();
    }
    cell::bus::Client<cell::InspectionRequest, cell::InspectionReply> ins(bus,
                                                                          cell::bus::topics::kInspection);
    for (int i = 0; i < kFiles; ++i) {
      cell::InspectionRequest r;
      r.op(cell::INSPECTION_STORE_FILE);
      r.file().station("KT01");
      r.file().file(fmt::format("{:03}", i) + std::string(61, 'P'));  // 64: the longest (IDL)
      r.file().text("1 2 3\n");
      ASSERT_EQ(ins.Call(r, 30000ms).hdr().code(), 0) << i;
    }
  }
  json all = cell_.Json({"job", "ls", "--json"});
  ASSERT_EQ(all.size(), static_cast<size_t>(kJobs));
  EXPECT_GT(all.dump().size(), 65536u);                                               // more than one reply
  for (size_t i = 1; i < all.size(); ++i) ASSERT_LT(all[i - 1]["id"], all[i]["id"]);  // by id
  // A page after a cursor is the same slice of the whole; after the last there is nothing.
  const std::string cursor = all[99]["id"].dump();
  json slice = cell_.Json({"job", "ls", "--json", "--limit", "150", "--after", cursor});
  ASSERT_EQ(slice.size(), 150u);
  for (size_t i = 0; i < slice.size(); ++i) EXPECT_EQ(slice[i], all[100 + i]);
  EXPECT_EQ(cell_.Json({"job", "ls", "--json", "--after", all.back()["id"].dump()}), json::array());
  // The table prints the rows --json prints.
  auto table = Ctl({"job", "ls", "--limit", "300"});
  ASSERT_EQ(table.code, 0) << table.err;
  std::istringstream lines(table.out);
  std::string line;
  std::getline(lines, line);  // the header
  for (size_t i = 0; i < 300; ++i) {
    ASSERT_TRUE(std::getline(lines, line)) << i;
    EXPECT_EQ(line.substr(0, line.find(' ')), all[i]["id"].dump());
  }
  EXPECT_FALSE(std::getline(lines, line)) << line;
  // Filters: the jobs of one station in one state, the same rows as the whole listing filtered.
  json kt02 = cell_.Json({"job", "ls", "--json", "--state", "CANCELLED", "--station", "KT02"});
  json expected = json::array();
  for (auto& j : all)
    if (j["state"] == "CANCELLED" && j["station"] == "KT02") expected.push_back(j);
  EXPECT_EQ(kt02, expected);
  EXPECT_FALSE(kt02.empty());
  for (auto [args, says] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"job", "ls", "--limit", "0"}, "not in range"},
           {{"job", "ls", "--limit", "-5"}, "expected a decimal integer"},
           {{"job", "ls", "--state", "DONE"}, "not a job state"},
           {{"program", "ls", "--limit", "1x"}, "expected a decimal integer"},
           {{"inspect", "ls", "--limit", "0"}, "not in range"}}) {
    auto r = Ctl(args);
    EXPECT_EQ(r.code, 2) << args[0] << " " << args[2] << ": " << r.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << r.err;
    ExpectOneShortLine(r, args[0] + " " + args[2]);
  }

  // Inspection files by name: 560 rows of about 130 bytes are two replies.
  json files = cell_.Json({"inspect", "ls", "KT01/*", "--json"});
  ASSERT_EQ(files.size(), static_cast<size_t>(kFiles));
  EXPECT_GT(files.dump().size(), 65536u);
  for (size_t i = 1; i < files.size(); ++i) ASSERT_LT(files[i - 1]["name"], files[i]["name"]);
  json next = cell_.Json({"inspect", "ls", "KT01/*", "--json", "--limit", "2", "--after",
                          files[kFiles - 3]["name"].get<std::string>()});
  ASSERT_EQ(next.size(), 2u);
  EXPECT_EQ(next[1], files[kFiles - 1]);
  // One station's records and files (DESIGN §6 `inspect ls --station ID`): the whole listing filtered, and
  // pages of it; KT02's two files sort after KT01's 560, so KT02's first page reads past a reply of others.
  {
    cell::bus::Participant bus("hardening-station");
    cell::bus::Client<cell::InspectionRequest, cell::InspectionReply> ins(bus,
                                                                          cell::bus::topics::kInspection);
    for (const char* f : {"PROBE1", "PROBE2"}) {
      cell::InspectionRequest r;
      r.op(cell::INSPECTION_STORE_FILE);
      r.file().station("KT02");
      r.file().file(f);
      r.file().text("1 2 3\n");
      ASSERT_EQ(ins.Call(r, 30000ms).hdr().code(), 0) << f;
    }
  }
  json every = cell_.Json({"inspect", "ls", "--json"});
  for (const char* id : {"KT01", "KT02"}) {
    json want = json::array();
    for (auto& f : every)
      if (f["station"] == id) want.push_back(f);
    EXPECT_EQ(cell_.Json({"inspect", "ls", "--station", id, "--json"}), want) << id;
  }
  json kt02files = cell_.Json({"inspect", "ls", "KT02/*", "--station", "KT02", "--json", "--limit", "1"});
  ASSERT_EQ(kt02files.size(), 1u);
  EXPECT_EQ(kt02files[0]["name"], "KT02/PROBE1");
  EXPECT_EQ(cell_.Json({"inspect", "ls", "KT01/*", "--station", "KT02", "--json"}), json::array());
  auto bad = Ctl({"inspect", "ls", "--station", "KT 01"});
  EXPECT_EQ(bad.code, 2) << bad.err;
  ExpectOneShortLine(bad, "inspect ls --station");
  // Programs by name, after a cursor that need not exist.
  Put("VALVE1");
  json progs = cell_.Json({"program", "ls", "--json", "--limit", "1", "--after", "PUMP1"});
  ASSERT_EQ(progs.size(), 1u);
  EXPECT_EQ(progs[0]["name"], "VALVE1");
  EXPECT_EQ(cell_.Json({"program", "ls", "--json", "--after", "PUMP"})[0]["name"], "PUMP1");
}

// Item 1: a key binds the whole command; a different command under a used key is refused with exit 1.
TEST_F(Hardening, AnIdempotencyKeyBindsTheWholeCommand) {
  Put("PUMP1");
  Put("VALVE1");
  ASSERT_EQ(Ctl({"route", "define", "PUMP", "--op", "KT01:PUMP1"}).code, 0);
  ASSERT_EQ(Ctl({"route", "define", "VALVE", "--op", "KT02:VALVE1"}).code, 0);
  const std::map<std::string, std::string> key{{"CELLCTL_IDEMPOTENCY_KEY", "s7"}};
  auto first = Ctl({"route", "operate", "PUMP", "--pallet", "250"}, key);
  ASSERT_EQ(first.code, 0) << first.err;
  auto again = Ctl({"route", "operate", "PUMP", "--pallet", "250"}, key);  // a retry: the same job
  EXPECT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(again.out, first.out);
  auto other = Ctl({"route", "operate", "VALVE", "--pallet", "251"}, key);  // another command: refused
  EXPECT_EQ(other.code, 1) << other.out;
  EXPECT_EQ(other.out, "");
  EXPECT_NE(other.err.find("'s7:route-operate' was already used for another command"), std::string::npos)
      << other.err;
  ExpectOneShortLine(other, "route operate VALVE under a used key");
  auto jobs = cell_.Json({"job", "ls", "--json"});
  ASSERT_EQ(jobs.size(), 1u) << jobs.dump();  // pallet 251 was never operated
  EXPECT_EQ(jobs[0]["pallet"], 250);

  // route define and job cancel the same way.
  const std::map<std::string, std::string> k2{{"CELLCTL_IDEMPOTENCY_KEY", "s8"}};
  ASSERT_EQ(Ctl({"route", "define", "R2", "--op", "KT01:PUMP1"}, k2).code, 0);
  EXPECT_EQ(Ctl({"route", "define", "R2", "--op", "KT01:PUMP1"}, k2).code, 0);
  auto redefine = Ctl({"route", "define", "R2", "--op", "KT02:VALVE1"}, k2);
  EXPECT_EQ(redefine.code, 1) << redefine.err;
  EXPECT_EQ(cell_.Json({"route", "show", "R2", "--json"})["ops"][0]["programs"][0], "PUMP1");
  const std::map<std::string, std::string> k3{{"CELLCTL_IDEMPOTENCY_KEY", "s9"}};
  ASSERT_EQ(Ctl({"station", "hold", "KT02"}).code, 0);  // keeps the second job live
  auto j2 = FirstLine(Ctl({"route", "operate", "VALVE", "--pallet", "252"}).out);
  ASSERT_EQ(Ctl({"job", "cancel", j2}, k3).code, 0);
  EXPECT_EQ(Ctl({"job", "cancel", j2}, k3).code, 0);
  auto cancel_other = Ctl({"job", "cancel", FirstLine(first.out)}, k3);
  EXPECT_EQ(cancel_other.code, 1) << cancel_other.err;
  EXPECT_NE(cell_.Json({"job", "show", FirstLine(first.out), "--json"})["state"], "CANCELLED");
  ASSERT_EQ(Ctl({"station", "resume", "KT02"}).code, 0);
  // A put under a used key with other content: the store refuses it the same way.
  const std::map<std::string, std::string> k4{{"CELLCTL_IDEMPOTENCY_KEY", "s10"}};
  std::string a = cell_.data_dir() + "/A.apl", b = cell_.data_dir() + "/B.apl";
  std::ofstream(a) << Program("KEYA", 1);
  std::ofstream(b) << Program("KEYB", 1);
  ASSERT_EQ(Ctl({"program", "put", a}, k4).code, 0);
  EXPECT_EQ(Ctl({"program", "put", a}, k4).code, 0);
  EXPECT_EQ(Ctl({"program", "put", b}, k4).code, 1);
  EXPECT_NE(Ctl({"program", "show", "KEYB"}).code, 0);
  // Issue 39 item 4: a 70 KB put (chunked) repeated under its key replays; it failed "already exists".
  const std::map<std::string, std::string> k5{{"CELLCTL_IDEMPOTENCY_KEY", "s11"}};
  std::string big = cell_.data_dir() + "/BIG70.apl";
  {
    std::ofstream out(big);
    out << "%\n(NAM,BIG70)\n(UCY,1)\nN10 G71 G90 G01\n";
    for (int i = 0; i < 3000; ++i) out << "N20 X" << (i % 100) << ". Y0 Z100. F2000.\n";
    out << "N40 M30\n%\n";
  }
  ASSERT_GT(fs::file_size(big), 70000u);
  auto put1 = Ctl({"program", "put", big}, k5);
  ASSERT_EQ(put1.code, 0) << put1.err;
  auto put2 = Ctl({"program", "put", big}, k5);
  EXPECT_EQ(put2.code, 0) << put2.err;
  EXPECT_EQ(put2.out, put1.out);
  EXPECT_EQ(cell_.Json({"program", "show", "BIG70", "--json"})["revisions"].size(), 1u) << "stored twice";
}

// Items 2 and 3 against the services: the names the tests above refuse locally, refused by the scheduler and
// the station too when they arrive another way, and a route of 64 characters is not a prefix of one of 65.
TEST_F(Hardening, LongNamesAreNeverCutAndEmptyToolLoadsAreRefused) {
  Put("PUMP1");
  const std::string r64(64, 'R');
  ASSERT_EQ(Ctl({"route", "define", r64, "--op", "KT01:PUMP1"}).code, 0);
  auto longer = Ctl({"route", "define", r64 + "S", "--op", "KT02:PUMP1"});
  EXPECT_EQ(longer.code, 2) << longer.err;
  EXPECT_EQ(cell_.Json({"route", "show", r64, "--json"})["ops"][0]["stations"][0], "KT01");
  // A route file with a bad route name: refused (cellctl reads it first; the scheduler would too).
  std::string file = cell_.data_dir() + "/routes.txt";
  std::ofstream(file) << "ROUTE ../x\nOP KT01 : PUMP1\n";
  auto bad = Ctl({"route", "define", "../x", "--file", file});
  EXPECT_EQ(bad.code, 2) << bad.err;
  ExpectOneShortLine(bad, "route file with ../x");
  // A TLD load with a statement loads; a file of other blocks is refused by cellctl (before sending).
  std::string tld = cell_.data_dir() + "/tools.tld";
  std::ofstream(tld) << "(TLD,S9T4711P100.D10.)\n";
  EXPECT_EQ(Ctl({"tools", "load", "KT01", tld}).code, 0);
}

// Item 5 against the services: a KT-APL program sent to the Okuma station OK01 (configured in
// deploy/stations, not started) is refused by the scheduler at `route define` and at `pallet run`, one line,
// exit 1, nothing recorded.
TEST_F(Hardening, ProgramsForTheWrongControllerAreRefused) {
  Put("PUMP1");
  auto route = Ctl({"route", "define", "WRONG", "--op", "KT01,OK01:PUMP1"});
  EXPECT_EQ(route.code, 1) << route.err;
  EXPECT_NE(
      route.err.find("route WRONG op 1: program 'PUMP1' is ktapl (Kearney & Trecker KT-APL) but station "
                     "OK01 runs okuma (Okuma OSP-E100L)"),
      std::string::npos)
      << route.err;
  ExpectOneShortLine(route, "route define WRONG");
  EXPECT_NE(Ctl({"route", "show", "WRONG"}).code, 0);  // not defined
  // Issue 39 item 5: a map naming a program the store does not hold is refused at `pallet set`, not later.
  auto missing = Ctl({"pallet", "set", "6", "PUMP1", "NOPROG"});
  EXPECT_EQ(missing.code, 1) << missing.err;
  EXPECT_NE(missing.err.find("pallet 6: program 'NOPROG' not found"), std::string::npos) << missing.err;
  ExpectOneShortLine(missing, "pallet set 6 NOPROG");
  EXPECT_NE(Ctl({"pallet", "show", "6"}).code, 0);  // nothing mapped
  ASSERT_EQ(Ctl({"pallet", "set", "9", "PUMP1"}).code, 0);
  auto run = Ctl({"pallet", "run", "9", "--station", "OK01"});
  EXPECT_EQ(run.code, 1) << run.err;
  EXPECT_EQ(run.out, "");
  EXPECT_NE(run.err.find("pallet 9: program 'PUMP1' is ktapl"), std::string::npos) << run.err;
  ExpectOneShortLine(run, "pallet run 9 on OK01");
  EXPECT_EQ(cell_.Json({"job", "ls", "--json"}).size(), 0u);
  // The same program on its own controller runs.
  auto ok = Ctl({"pallet", "run", "9", "--station", "KT01"});
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_EQ(Ctl({"job", "wait", FirstLine(ok.out), "--timeout", "60"}).code, 0);
}

// Item 4 against the services: tool data outside the manual's TLD ranges (KT-APL ln 4041-4049: +-999.999 mm)
// is refused on every path (cellctl tools load, a program's TLD at run time), at the offending letter; the
// manual's own E45 example with its signed compensations (ln 4063-4097: D-.25, D-.0004) loads.
TEST_F(Hardening, ToolDataOutsideTheManualsRangesIsRefused) {
  // E45 loads (signed compensations), one value past the range does not.
  std::string e45 = cell_.data_dir() + "/e45.tld";
  std::ofstream(e45) << "G70\nN12 (TLD,S12T33412CP.02D-.25L345H5.9)\nN13(TLD,S12T33412.5CP.02D-.25L345H5.9)\n"
                        "N14(TLD,T33412.5W12P.0003D-.0004)\n";
  auto load = Ctl({"tools", "load", "KT01", e45});
  ASSERT_EQ(load.code, 0) << load.err;
  bool seen = false;
  for (const auto& e : cell_.Json({"station", "tools", "KT01", "--json"})) {
    if (e["tool"] == "33412.5") {
      seen = true;
      EXPECT_NEAR(e["diameter"].get<double>(), -0.25 * 25.4, 1e-9);
    }
  }
  EXPECT_TRUE(seen);
  std::string big = cell_.data_dir() + "/big.tld";
  std::ofstream(big) << "G71\n(TLD,S9T4711P1000.D10.)\n";
  auto refused = Ctl({"tools", "load", "KT01", big});
  EXPECT_EQ(refused.code, 1) << refused.err;
  EXPECT_NE(refused.err.find("big.tld:2:13: error: TLD P VALUE 1000 OUTSIDE +-999.999"), std::string::npos)
      << refused.err;
  ExpectOneShortLine(refused, "tools load P1000.");
  // A program's TLD at run time: the job fails with the same message at the program's line and column.
  std::string prog = cell_.data_dir() + "/BIGTLD.apl";
  std::ofstream(prog) << "%\n(NAM,BIGTLD)\n(UCY,10)\nN10 G71\nN20 (TLD,S9T4711P10.D-1000.)\nN30 M30\n%\n";
  ASSERT_EQ(Ctl({"program", "put", prog}).code, 0);
  ASSERT_EQ(Ctl({"pallet", "set", "10", "BIGTLD"}).code, 0);
  auto job = FirstLine(Ctl({"pallet", "run", "10", "--station", "KT01"}).out);
  ASSERT_FALSE(job.empty());
  EXPECT_NE(Ctl({"job", "wait", job, "--timeout", "60"}).code, 0);
  auto shown = cell_.Json({"job", "show", job, "--json"});
  EXPECT_EQ(shown["state"], "FAILED") << shown.dump();
  EXPECT_NE(shown.value("reason", "").find("BIGTLD:5:21: error: TLD D VALUE -1000 OUTSIDE +-999.999"),
            std::string::npos)
      << shown.dump();
}

// Item 6: one process per station identity, and the singletons.
TEST_F(Hardening, OneProcessPerIdentity) {
  const std::string other = MakeTempDir("cell-hardening-second-");
  // A second process of every kind, each with another data dir, refuses within 5 s with a clear message.
  for (auto argv : std::vector<std::vector<std::string>>{{"cell-interpreter", "--station", "KT01"},
                                                         {"cell-axis-servo", "--station", "KT02"},
                                                         {"cell-scheduler"},
                                                         {"cell-program-store"},
                                                         {"cell-inspection-writer"},
                                                         {"cell-dashboard"}}) {
    argv[0] = BinDir() + "/" + argv[0];
    auto t0 = std::chrono::steady_clock::now();
    auto r = RunCommand(argv, {{"CELL_DATA_DIR", other}, {"CELL_HTTP", "127.0.0.1:0"}}, 20s);
    auto took = std::chrono::steady_clock::now() - t0;
    EXPECT_EQ(r.code, 1) << argv[0] << ": " << r.err;
    EXPECT_NE(r.err.find("another live process is "), std::string::npos) << r.err;
    // The claim itself refuses within its 3 s window (common/identity/identity_test times it); here the whole
    // process, ASan start-up on a loaded machine included, must end well before the 20 s command timeout.
    EXPECT_LT(took, 15s) << argv[0];
  }
  fs::remove_all(other);
  // A kill -9 and a restart at once: the dead process's announcement does not block its successor.
  const int old = Pid("cell-interpreter/KT01");
  ASSERT_EQ(kill(old, SIGKILL), 0);
  auto r = Ctl({"restart", "cell-interpreter/KT01"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(Pid("cell-interpreter/KT01"), old);
  Put("PUMP1");
  ASSERT_EQ(Ctl({"route", "define", "PUMP", "--op", "KT01:PUMP1"}).code, 0);

  // Two at once anyway (here a second announcer of KT01's interpreter, as a process that was stopped past its
  // lease would be): the scheduler raises a FAULT condition naming both, and dispatches nothing to KT01.
  {
    cell::bus::Participant bus("hardening-impostor");
    cell::bus::Writer<cell::ServiceHealth> w(bus, cell::bus::topics::kHealth, cell::bus::QosKind::kState);
    cell::ServiceHealth h;
    h.service_id("cell-interpreter/KT01");
    h.kind("cell-interpreter");
    h.station("KT01");
    h.state(cell::SERVICE_READY);
    h.pid(999999);
    h.boot_id(0x5eedULL);
    h.started_ns(cell::health::WallNs());
    std::atomic<bool> stop{false};
    std::thread beat([&] {
      while (!stop) {
        h.heartbeat_ns(cell::health::WallNs());
        w.Write(h);
        std::this_thread::sleep_for(500ms);
      }
    });
    json st;
    bool fault = cell::bus::WaitUntil(
        [&] {
          st = json::object();
          for (auto& row : cell_.Json({"station", "ls", "--json"}))
            if (row["id"] == "KT01") st = row;  // by id: stations are listed in id order (EM01 first)
          return st["condition"] == "FAULT";
        },
        20000ms);
    EXPECT_TRUE(fault) << st.dump();
    if (fault) {
      std::string text = st["alarm_text"];
      EXPECT_NE(text.find("pid 999999"), std::string::npos) << text;
      EXPECT_NE(text.find("pid " + std::to_string(Pid("cell-interpreter/KT01"))), std::string::npos) << text;
    }
    auto job = FirstLine(Ctl({"route", "operate", "PUMP", "--pallet", "5"}).out);
    auto j = cell_.Json({"job", "show", job, "--json"});
    EXPECT_EQ(j["state"], "WAITING") << j.dump();
    stop = true;
    beat.join();
    // The impostor falls silent: the fault clears and the waiting pallet runs.
    auto w2 = Ctl({"job", "wait", job, "--timeout", "60"});
    EXPECT_EQ(w2.code, 0) << w2.out << w2.err;
  }
}

// Items 7, 8, 9: the local cell's processes.
TEST_F(Hardening, LocalCellProcesses) {
  auto rec = Record(cell_);
  // 7: no descriptor of cellctl's reaches a service: no socket is shared between two services (each opens its
  // own), and none holds more than stdin/stdout/stderr of what it was started with.
  std::map<std::string, std::string> owner;  // socket inode -> service
  for (auto& p : rec) {
    const std::string svc = p["service"];
    const std::string fd_dir = "/proc/" + std::to_string(p["pid"].get<int>()) + "/fd";
    for (auto& e : fs::directory_iterator(fd_dir)) {
      std::error_code ec;
      std::string target = fs::read_symlink(e.path(), ec).string();
      if (ec || target.rfind("socket:", 0) != 0) continue;
      auto [it, fresh] = owner.emplace(target, svc);
      EXPECT_TRUE(fresh) << target << " is open in both " << it->second << " and " << svc;
    }
  }
  // 9: local data is its owner's only.
  auto mode = [](const std::string& path) { return fs::status(path).permissions() & fs::perms::all; };
  EXPECT_EQ(mode(cell_.data_dir()), fs::perms::owner_all) << cell_.data_dir();
  EXPECT_EQ(mode(cell_.data_dir() + "/logs"), fs::perms::owner_all);
  for (auto& e : fs::recursive_directory_iterator(cell_.data_dir())) {
    auto m = fs::status(e.path()).permissions() & (fs::perms::group_all | fs::perms::others_all);
    EXPECT_EQ(m, fs::perms::none) << e.path() << " is readable by others";
  }

  // 8: restart starts the service with the same command line and environment, and records its PID. The
  // marker is in `up`'s environment only, not in restart's.
  const int sched = Pid("cell-scheduler");
  const auto argv = ProcessArgv(sched);
  const auto env = ProcessEnvironment(sched);
  // The scheduler and a station's interpreter killed together, the station restarted first: it is up at its
  // READY=1, with no scheduler to wait for (the gate's chaos test, 2026-12-04, failed here: "ready, but the
  // scheduler does not see station KT01", the scheduler being dead).
  ASSERT_EQ(kill(Pid("cell-interpreter/KT01"), SIGKILL), 0);
  ASSERT_EQ(kill(sched, SIGKILL), 0);
  auto ri = Ctl({"restart", "cell-interpreter/KT01"});
  ASSERT_EQ(ri.code, 0) << ri.err;
  auto r = Ctl({"restart", "cell-scheduler"}, {{"CELL_LOG_LEVEL", "debug"}});
  ASSERT_EQ(r.code, 0) << r.err;
  const int sched2 = Pid("cell-scheduler");
  EXPECT_NE(sched2, sched);
  EXPECT_EQ(ProcessArgv(sched2), argv);
  EXPECT_EQ(ProcessEnvironment(sched2), env);
  // A restart of a running service replaces it. A station's service is waited for by its READY=1 on the
  // restart's own notify socket (docs/operations.md §7), which it uses for that alone: stopped by the next
  // restart, long after the first cellctl has gone, it logs no failed sd_notify.
  ASSERT_EQ(Ctl({"restart", "cell-axis-servo/KT02"}).code, 0);
  const auto servo_env = ProcessEnvironment(Pid("cell-axis-servo/KT02"));
  EXPECT_EQ(servo_env.count("CELL_NOTIFY") ? servo_env.at("CELL_NOTIFY") : "", "ready");
  ASSERT_EQ(Ctl({"restart", "cell-axis-servo/KT02"}).code, 0);
  EXPECT_EQ(ReadFile(cell_.data_dir() + "/logs/cell-axis-servo@KT02.service.log").find("sd_notify failed"),
            std::string::npos);
  EXPECT_EQ(Ctl({"restart", "cell-nothing"}).code, 2);

  // `up` of a partly-down cell starts only what is missing.
  const auto before = cell_.Pids();
  ASSERT_EQ(kill(before.at("cell-program-store"), SIGKILL), 0);
  ASSERT_EQ(kill(before.at("cell-interpreter/KT02"), SIGKILL), 0);
  auto up = Ctl({"up"});
  ASSERT_EQ(up.code, 0) << up.err;
  const auto after = cell_.Pids();
  for (auto& [svc, pid] : after) {
    if (svc == "cell-program-store" || svc == "cell-interpreter/KT02")
      EXPECT_NE(pid, before.at(svc)) << svc;
    else
      EXPECT_EQ(pid, before.at(svc)) << svc;
  }
  EXPECT_EQ(Ctl({"program", "ls"}).code, 0);

  // `up --only stations` (a station host of a cell across hosts, deploy/hosts) starts the stations' processes
  // and no host service, recorded in its own data directory, and is ready once they announce themselves: the
  // running cell's scheduler sees the new station.
  const std::string station_host = cell_.data_dir() + "/station-host";
  auto part = Ctl({"up", "--only", "stations", "--stations", "KT03"}, {{"CELL_DATA_DIR", station_host}});
  ASSERT_EQ(part.code, 0) << part.out << part.err;
  std::set<std::string> started;
  for (auto& p : json::parse(ReadFile(station_host + "/cell-up.json"))) started.insert(p["service"]);
  EXPECT_EQ(started, (std::set<std::string>{"cell-interpreter/KT03", "cell-axis-servo/KT03"}));
  auto kt03_online = [&] {
    for (auto& row : cell_.Json({"station", "ls", "--json"}))
      if (row["id"] == "KT03") return row["online"] == true;
    return false;
  };
  bool kt03 = kt03_online();
  for (int i = 0; !kt03 && i < 20; ++i) {
    std::this_thread::sleep_for(500ms);
    kt03 = kt03_online();
  }
  EXPECT_TRUE(kt03);
  EXPECT_EQ(Ctl({"down"}, {{"CELL_DATA_DIR", station_host}}).code, 0);
  EXPECT_EQ(Ctl({"up", "--only", "router"}).code, 2);

  // `down` stops only the processes it started: a recorded PID that now belongs to another process (here a
  // sleep of the test's, put in the record as if the PID had been reused) is left alone.
  Process bystander({"/bin/sleep", "60"});
  auto rec2 = Record(cell_);
  for (auto& p : rec2)
    if (p["service"] == "cell-inspection-writer") {
      kill(p["pid"].get<int>(), SIGKILL);
      p["pid"] = bystander.pid();
    }
  std::ofstream(cell_.data_dir() + "/cell-up.json") << rec2.dump(2);
  auto down = cell_.Down();
  EXPECT_EQ(down.code, 0) << down.err;
  EXPECT_NE(down.err.find("is no longer cell-inspection-writer: left alone"), std::string::npos) << down.err;
  EXPECT_TRUE(bystander.Running());
  ASSERT_EQ(cell_.Up("KT01,KT02", "virtual").code, 0);  // for TearDown
}

}  // namespace
