// Whole-cell chaos (issue 13, item 11): a 4-station cell on the virtual clock operates routes while a driver
// kills random services with -9 at random moments (at least 30 kills, every kind of service, many while
// segments flow) and restarts each with `cellctl restart`. An operator operates pallets through `cellctl`,
// retrying each command under its own CELLCTL_IDEMPOTENCY_KEY while the scheduler is down, and a librarian
// puts programs the same way. Afterwards:
//   - every operated pallet is in exactly one job, and that job ended (COMPLETED, or FAILED with a reason:
//     a pallet whose station died under it needs an operator, docs/scheduler.md §5);
//   - every completed job has exactly one completed run record per operation, and no operation of any job
//     started twice (each run that started files a record, completed or not);
//   - no backlog is left on any station;
//   - every program put (before or during the chaos) reads back byte for byte;
//   - the cell still works: one more pallet per route completes.
//   - every SQLite database of the cell passes PRAGMA integrity_check;
// The librarian's first put during the chaos is a large program (CELL_CHAOS_BIG_MB, default 1; the chunked
// put path, retried under its key across kills of the store: issue 39 item 4); a campaign on a release build
// sets it to 20 (docs/operations.md, "kill -9 campaign").
// CELL_CHAOS_SEED fixes the random choices (the seed is printed either way).
// The test is the cell's child subreaper, so it learns how every service process ended: one that ends without
// the test killing it fails the test with its wait status and the tail of its log, except for the one known
// crash of Fast DDS 2.9.1 (a lease-timer race in its participant discovery that aborts on an assertion,
// docs/architecture.md "Leaving"): the test restarts such a service as systemd's Restart=on-failure would,
// and the cell's invariants must hold across that crash too.
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <utility>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cell/store/sqlite.h"
#include "cell/testing/local_cell.h"

using namespace cell::testing;
using namespace std::chrono_literals;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

constexpr int kMinKills = 30;
constexpr int kLiveJobs = 6;

// A KT/FMS part program with enough motion that its segments flow for a while on the virtual clock.
std::string Program(const std::string& name, int moves, int variant) {
  std::string s = "%\n(NAM," + name + ")\n(UCY,30)\nN10 G71 G90 G01\nN20 X0 Y0 Z100. F0\n";
  int n = 30;
  for (int i = 0; i < moves; ++i) {
    s += fmt::format("N{} X{}. Y{}. Z{}. F{}.\n", n, 50 + (i * 37 + variant * 11) % 400, 20 + (i * 53) % 300,
                     10 + (i * 7) % 60, 3000 + 500 * (i % 4));
    n += 10;
  }
  return s + fmt::format("N{} G00 X0 Y0 Z100. F0\nN{} M30\n%\n", n, n + 10);
}

std::string Lines(const std::vector<std::string>& v) {
  std::string out;
  for (auto& s : v) out += s + "\n";
  return out;
}

std::string FirstLine(const std::string& s) {
  return s.substr(0, s.find('\n'));
}

// Reaps the cell's service processes: `cellctl` starts them in their own session and exits, so (with
// PR_SET_CHILD_SUBREAPER on this process) they become this process's children. Only the pids in the cell's
// record are waited for, one by one (waitpid(-1) would take RunCommand's children from it).
class Reaper {
 public:
  explicit Reaper(const LocalCell& cell) : cell_(cell) {
    prctl(PR_SET_CHILD_SUBREAPER, 1);
    thread_ = std::thread([this] {
      while (!stop_) {
        Poll();
        std::this_thread::sleep_for(50ms);
      }
    });
  }
  ~Reaper() {
    stop_ = true;
    thread_.join();
  }
  // This test kills pid (so its end is expected).
  void Killing(int pid) {
    std::lock_guard lk(mu_);
    killed_.insert(pid);
  }
  // Every service process that ended without Killing(): service, pid, how it ended, its log's last lines.
  std::vector<std::string> Unexpected() {
    Poll();
    std::lock_guard lk(mu_);
    return unexpected_;
  }
  // Services that died of the known Fast DDS abort since the last call (to be restarted), and how many in
  // all.
  std::vector<std::string> TakeVendorCrashes() {
    Poll();
    std::lock_guard lk(mu_);
    return std::exchange(vendor_crashed_, {});
  }
  int vendor_crashes() {
    std::lock_guard lk(mu_);
    return vendor_crashes_;
  }

 private:
  void Poll() {
    std::lock_guard lk(mu_);
    for (auto& p : cell_.Record()) known_.emplace(p.pid, p);
    for (auto it = known_.begin(); it != known_.end();) {
      siginfo_t info{};
      if (waitid(P_PID, static_cast<id_t>(it->first), &info, WEXITED | WNOHANG) != 0 || info.si_pid == 0) {
        ++it;  // running, or not (yet) our child: cellctl has not exited
        continue;
      }
      if (!killed_.count(it->first)) {
        const std::string how =
            info.si_code == CLD_EXITED
                ? fmt::format("exited with status {}", info.si_status)
                : fmt::format("ended by signal {} ({})", info.si_status, strsignal(info.si_status));
        std::string tail = ReadFile(it->second.log);
        if (tail.size() > 1500) tail = "..." + tail.substr(tail.size() - 1500);
        if (info.si_code != CLD_EXITED && info.si_status == SIGABRT && IsFastDdsLeaseRace(tail)) {
          std::printf("%s (pid %d): Fast DDS 2.9.1's lease-timer assertion (restarted as systemd would)\n",
                      it->second.service.c_str(), it->first);
          vendor_crashed_.push_back(it->second.service);
          ++vendor_crashes_;
          it = known_.erase(it);
          continue;
        }
        unexpected_.push_back(fmt::format("{} (pid {}) {} without this test killing it; its log ends:\n{}",
                                          it->second.service, it->first, how, tail));
      }
      it = known_.erase(it);
    }
  }
  // PDP::check_remote_participant_liveliness asserts that the participant it checks is still known; a remote
  // participant removed by another thread while its lease timer fired is not (Fast DDS 2.9.1, built with
  // assertions on in Debian).
  static bool IsFastDdsLeaseRace(const std::string& log) {
    return log.find("check_remote_participant_liveliness") != std::string::npos &&
           log.find("GUID_t::unknown() != remote_participant->m_guid") != std::string::npos;
  }

  const LocalCell& cell_;
  std::mutex mu_;
  std::map<int, RecordedProcess> known_;  // not reaped yet
  std::vector<std::string> vendor_crashed_;
  int vendor_crashes_ = 0;
  std::set<int> killed_;
  std::vector<std::string> unexpected_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

struct Route {
  std::string name;
  std::vector<std::string> ops;  // --op strings
};

class Chaos : public ::testing::Test {
 protected:
  // A cellctl command retried (same idempotency key) until it succeeds: exit 0 or the deadline.
  RunResult Retry(const std::vector<std::string>& args, const std::string& key,
                  std::chrono::seconds deadline = 120s) {
    auto env = cell_.env();
    env["CELLCTL_IDEMPOTENCY_KEY"] = key;
    std::vector<std::string> argv{BinDir() + "/cellctl"};
    argv.insert(argv.end(), args.begin(), args.end());
    auto until = std::chrono::steady_clock::now() + deadline;
    RunResult r;
    do {
      r = RunCommand(argv, env, 60s);
      if (r.code == 0) return r;
      std::this_thread::sleep_for(300ms);
    } while (std::chrono::steady_clock::now() < until);
    return r;
  }
  // `job ls --json`, retried while the scheduler is down.
  json Jobs() {
    for (int i = 0; i < 600; ++i) {
      auto r = cell_.Ctl({"job", "ls", "--json"});
      if (r.code == 0) {
        auto j = json::parse(r.out, nullptr, false);
        if (j.is_array()) return j;
      }
      std::this_thread::sleep_for(200ms);
    }
    ADD_FAILURE() << "job ls failed for two minutes";
    return json::array();
  }

  // What systemd's Restart=on-failure does for a service that died of the known Fast DDS abort.
  void RestartVendorCrashes() {
    for (auto& svc : reaper_.TakeVendorCrashes()) {
      auto r = cell_.Ctl({"restart", svc});
      ASSERT_EQ(r.code, 0) << "cellctl restart " << svc << ": " << r.err;
    }
  }

  LocalCell cell_{"cell-chaos-"};
  Reaper reaper_{cell_};  // after cell_: gone before `cellctl down` ends the services
  std::mutex mu_;
  std::map<std::string, std::string> programs_;  // name -> content, every program put
  std::map<int, std::string> pallet_job_;        // pallet -> job id, as `route operate` printed it
  std::map<int, std::string> pallet_route_;
  std::atomic<bool> running_seen_{false};  // some job was RUNNING at the operator's last look
};

TEST_F(Chaos, KillNineAtRandomMomentsWhileRoutesOperate) {
  const char* seed_env = std::getenv("CELL_CHAOS_SEED");
  const unsigned seed =
      seed_env && *seed_env ? static_cast<unsigned>(std::stoul(seed_env)) : std::random_device{}();
  std::printf("chaos seed %u (CELL_CHAOS_SEED=%u reproduces the random choices)\n", seed, seed);
  std::mt19937 rng(seed);
  const char* big_env = std::getenv("CELL_CHAOS_BIG_MB");
  const double big_mb = big_env && *big_env ? std::stod(big_env) : 1.0;
  const auto t_start = std::chrono::steady_clock::now();

  auto up = cell_.Up("KT01,KT02,KT03,KT04", "virtual");
  ASSERT_EQ(up.code, 0) << up.out << up.err;

  // Programs and routes (every pallet number once; KT04 is a coded-pallet module: 1-127).
  for (int i = 1; i <= 4; ++i) {
    std::string name = fmt::format("CHAOS{}", i);
    std::string text = Program(name, 1200 + 100 * i, i);
    std::string path = cell_.data_dir() + "/" + name + ".apl";
    std::ofstream(path) << text;
    ASSERT_EQ(Retry({"program", "put", path}, "put-" + name).code, 0);
    programs_[name] = text;
  }
  const std::vector<Route> routes = {{"TWO-OPS", {"KT01,KT02:CHAOS1", "KT03,KT04:CHAOS2"}},
                                     {"BACK", {"KT03,KT04:CHAOS3"}},
                                     {"ANY", {"KT01,KT02,KT03,KT04:CHAOS4,CHAOS1"}}};
  std::map<std::string, int> ops_of;
  for (auto& r : routes) {
    std::vector<std::string> args{"route", "define", r.name};
    for (auto& op : r.ops) args.insert(args.end(), {"--op", op});
    ASSERT_EQ(Retry(args, "define-" + r.name).code, 0);
    ops_of[r.name] = static_cast<int>(r.ops.size());
  }

  // The operator: keeps kLiveJobs pallets in the cell until told to stop.
  std::atomic<bool> stop_operating{false};
  std::atomic<int> next_pallet{1};
  std::thread operator_thread([&] {
    while (!stop_operating && next_pallet <= 120) {
      json jobs = Jobs();
      int live = 0;
      bool running = false;
      for (auto& j : jobs) {
        std::string st = j["state"];
        if (st != "COMPLETED" && st != "FAILED" && st != "CANCELLED") ++live;
        running = running || st == "RUNNING";
      }
      running_seen_ = running;
      for (; live < kLiveJobs && !stop_operating && next_pallet <= 120; ++live) {
        const int pallet = next_pallet++;
        const Route& route = routes[static_cast<size_t>(pallet) % routes.size()];
        auto r = Retry({"route", "operate", route.name, "--pallet", std::to_string(pallet)},
                       fmt::format("operate-{}", pallet));
        EXPECT_EQ(r.code, 0) << "pallet " << pallet << ": " << r.err;
        std::lock_guard lk(mu_);
        pallet_job_[pallet] = FirstLine(r.out);
        pallet_route_[pallet] = route.name;
      }
      std::this_thread::sleep_for(300ms);
    }
  });
  struct Joiner {  // an ASSERT below returns early: the operator stops and is joined either way
    std::atomic<bool>& stop;
    std::thread& t;
    ~Joiner() {
      stop = true;
      if (t.joinable()) t.join();
    }
  } joiner{stop_operating, operator_thread};

  // The driver: kill -9 one or two services at random moments, restart them with `cellctl restart`.
  std::vector<std::string> kinds = {"cell-program-store", "cell-scheduler",  "cell-inspection-writer",
                                    "cell-interpreter",   "cell-axis-servo", "cell-dashboard"};
  std::map<std::string, int> kills_by_kind;
  int kills = 0, kills_running = 0, puts = 0;
  std::vector<std::string> services;
  for (auto& [svc, pid] : cell_.Pids()) services.push_back(svc);
  auto kind_of = [](const std::string& svc) { return svc.substr(0, svc.find('/')); };
  auto all_kinds_covered = [&] {
    for (auto& k : kinds)
      if (kills_by_kind[k] < 3) return false;
    return true;
  };
  while (kills < kMinKills || !all_kinds_covered()) {
    std::this_thread::sleep_for(
        std::chrono::milliseconds(std::uniform_int_distribution<int>(100, 1500)(rng)));
    // At least half the kills must find a job running. On a loaded machine the cell spends longer coming back
    // after each kill, so fewer random moments find one (5 of 30 beside a second build, issue 44): while the
    // running kills are behind, wait (up to 30 s) for the operator to see a job running.
    for (int waited = 0; kills_running * 2 < kills + 1 && !running_seen_ && waited < 300; ++waited)
      std::this_thread::sleep_for(100ms);
    // A kind not yet killed three times first, else any service.
    std::vector<std::string> victims;
    const int n = std::uniform_int_distribution<int>(1, 2)(rng);
    for (int i = 0; i < n; ++i) {
      std::vector<std::string> pool;
      for (auto& s : services)
        if (kills_by_kind[kind_of(s)] < 3 || all_kinds_covered()) pool.push_back(s);
      if (pool.empty()) pool = services;
      std::string v = pool[std::uniform_int_distribution<size_t>(0, pool.size() - 1)(rng)];
      if (std::find(victims.begin(), victims.end(), v) == victims.end()) victims.push_back(v);
    }
    RestartVendorCrashes();
    const auto pids = cell_.Pids();
    for (auto& v : victims) {
      reaper_.Killing(pids.at(v));
      if (kill(pids.at(v), SIGKILL) != 0) {  // it ended since the record was read: only the known abort may
        auto crashed = reaper_.TakeVendorCrashes();
        ASSERT_NE(std::find(crashed.begin(), crashed.end(), v), crashed.end())
            << v << ": " << Lines(reaper_.Unexpected());
      }
      ++kills;
      ++kills_by_kind[kind_of(v)];
      if (running_seen_) ++kills_running;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(std::uniform_int_distribution<int>(0, 800)(rng)));
    for (auto& v : victims) {
      auto r = cell_.Ctl({"restart", v});
      ASSERT_EQ(r.code, 0) << "cellctl restart " << v << ": " << r.err;
    }
    // The librarian: now and then a new program, put under its key and retried across the kills.
    if (std::uniform_int_distribution<int>(0, 2)(rng) == 0) {
      std::string name = fmt::format("LIB{}", ++puts);
      // About 40 bytes a move: the first is big_mb megabytes, the rest a few hundred bytes.
      const int moves = puts == 1 ? static_cast<int>(big_mb * 1e6 / 40) : 5 + puts;
      std::string text = Program(name, moves, puts);
      std::string path = cell_.data_dir() + "/" + name + ".apl";
      std::ofstream(path) << text;
      ASSERT_EQ(Retry({"program", "put", path}, "put-" + name).code, 0) << name;
      programs_[name] = text;
    }
  }
  stop_operating = true;
  operator_thread.join();
  RestartVendorCrashes();
  for (auto& e : reaper_.Unexpected()) ADD_FAILURE() << e;
  const auto t_chaos = std::chrono::steady_clock::now();

  // Every job ends: none is stuck after the chaos (bounded).
  json jobs;
  const auto deadline = std::chrono::steady_clock::now() + 240s;
  while (true) {
    RestartVendorCrashes();
    jobs = Jobs();
    bool all_ended = true;
    for (auto& j : jobs) {
      std::string st = j["state"];
      all_ended = all_ended && (st == "COMPLETED" || st == "FAILED" || st == "CANCELLED");
    }
    if (all_ended) break;
    if (std::chrono::steady_clock::now() > deadline) {
      ADD_FAILURE() << "jobs still live 240 s after the last kill: " << jobs.dump(1);
      break;
    }
    std::this_thread::sleep_for(500ms);
  }

  // Every operated pallet: exactly one job, ended, the one `route operate` printed.
  std::map<int, std::vector<json>> by_pallet;
  int completed = 0, failed = 0;
  for (auto& j : jobs) by_pallet[j["pallet"].get<int>()].push_back(j);
  for (auto& [pallet, id] : pallet_job_) {
    ASSERT_EQ(by_pallet[pallet].size(), 1u)
        << "pallet " << pallet << " is in " << by_pallet[pallet].size() << " jobs";
    const json& j = by_pallet[pallet][0];
    EXPECT_EQ(std::to_string(j["id"].get<long>()), id) << "pallet " << pallet;
    if (j["state"] == "COMPLETED") ++completed;
    if (j["state"] == "FAILED") {
      ++failed;
      EXPECT_FALSE(j["reason"].is_null()) << j.dump();
    }
  }
  EXPECT_EQ(jobs.size(), pallet_job_.size());

  // Run records: one completed record per operation of a completed job; no operation started (so none
  // completed) twice (a record is filed for every run that started, completed or not: a pallet lost
  // or aborted mid-run needs an operator, it is never run again by itself, docs/scheduler.md §5).
  std::map<long, std::vector<json>> records;           // job id -> completed run records
  std::map<long, std::map<std::string, int>> started;  // job id -> operation's programs -> runs started
  for (auto& e : fs::directory_iterator(cell_.data_dir() + "/records")) {
    if (!e.is_regular_file() || e.path().filename().string().rfind("run-", 0) != 0) continue;
    auto r = json::parse(ReadFile(e.path().string()), nullptr, false);
    ASSERT_FALSE(r.is_discarded()) << e.path();
    const long job = r["job_id"].get<long>();
    if (++started[job][r["programs"].dump()] > 1)
      ADD_FAILURE() << "job " << job << " started " << r["programs"] << " twice (" << e.path().filename()
                    << ")";
    if (r["completed"].get<bool>()) records[job].push_back(r);
  }
  for (auto& j : jobs) {
    const long id = j["id"].get<long>();
    auto& recs = records[id];
    // What a failure needs to be understood: the job and its completed records (station, dispatch).
    const auto said = [&] {
      std::string out = j.dump();
      for (auto& r : recs)
        out += fmt::format("\n  completed on {} as dispatch {}: {}", r["station"].get<std::string>(),
                           r["dispatch_id"].get<long>(), r["programs"].dump());
      return out;
    };
    if (j["state"] == "COMPLETED")
      EXPECT_EQ(recs.size(), static_cast<size_t>(ops_of[j["route"].get<std::string>()])) << said();
    else
      EXPECT_LT(recs.size(), static_cast<size_t>(ops_of[j["route"].get<std::string>()])) << said();
  }

  // No backlog is left behind.
  auto stations = cell_.Json({"station", "ls", "--json"});
  for (auto& s : stations) EXPECT_EQ(s["backlog_s"].get<double>(), 0.0) << s.dump();

  // Every program reads back byte for byte.
  std::size_t program_bytes = 0, largest = 0;
  for (auto& [name, text] : programs_) {
    program_bytes += text.size();
    largest = std::max(largest, text.size());
    auto r = cell_.Ctl({"program", "get", name});
    EXPECT_EQ(r.code, 0) << name << ": " << r.err;
    EXPECT_TRUE(r.out == text) << name << " differs (" << r.out.size() << " bytes, put " << text.size()
                               << ")";
  }

  // The cell still works.
  RestartVendorCrashes();
  int pallet = 121;
  for (auto& route : routes) {
    auto r = Retry({"route", "operate", route.name, "--pallet", std::to_string(pallet)},
                   fmt::format("after-{}", pallet));
    ASSERT_EQ(r.code, 0) << r.err;
    auto w = cell_.Ctl({"job", "wait", FirstLine(r.out), "--timeout", "120"});
    EXPECT_EQ(w.code, 0) << route.name << ": " << w.out << w.err;
    ++pallet;
  }

  // Every database of the cell is whole (read-only connections beside the running services).
  int databases = 0;
  for (auto& e : fs::recursive_directory_iterator(cell_.data_dir())) {
    if (!e.is_regular_file() || e.path().extension() != ".db") continue;
    cell::store::OpenOptions ro;
    ro.read_only = true;
    auto db = cell::store::Database::Open(e.path(), ro);
    EXPECT_EQ(db.QueryText("PRAGMA integrity_check"), "ok") << e.path();
    ++databases;
  }
  EXPECT_GE(databases, 3) << "the scheduler's, the program store's and the stations' databases";

  const auto secs = [](auto d) { return std::chrono::duration_cast<std::chrono::seconds>(d).count(); };
  std::string by_kind;
  for (auto& [k, n] : kills_by_kind) by_kind += fmt::format(" {} {}", k, n);
  std::printf(
      "chaos: %d kills (%d while a job was running;%s), %d Fast DDS aborts restarted, %zu pallets: %d "
      "completed, %d failed; %d programs put during the chaos; %zu programs byte-equal (%zu bytes, the "
      "largest %zu); %d databases pass integrity_check; %lld s of chaos, %lld s in all\n",
      kills, kills_running, by_kind.c_str(), reaper_.vendor_crashes(), pallet_job_.size(), completed, failed,
      puts, programs_.size(), program_bytes, largest, databases,
      static_cast<long long>(secs(t_chaos - t_start)),
      static_cast<long long>(secs(std::chrono::steady_clock::now() - t_start)));
  for (auto& e : reaper_.Unexpected()) ADD_FAILURE() << e;
  EXPECT_GE(kills, kMinKills);
  EXPECT_GE(kills_running, kMinKills / 2);
  EXPECT_GT(completed, 0);
}

}  // namespace
