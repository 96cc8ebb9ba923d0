// memory_bench: the resident memory of a running cell's services as pallets go through it (issue 39 item 1;
// deploy/bench.d/90-memory.sh starts the cell on the virtual clock and defines the routes; this starts none
// of it). It operates pallets through the routes named, round robin, keeping --inflight jobs live, and for
// each finished job asks what an operator asks: `job show` of it; every 10th job also one page of `job ls`,
// `program ls` and `inspect ls`; every --cellctl-every jobs `cellctl job show` as a process of its own (a
// participant that joins and leaves the domain, as every cellctl verb does). At each checkpoint (pallets
// finished) and after --idle seconds without work it prints every service's VmRSS from /proc/PID/status,
// the services being the processes of $CELL_DATA_DIR/cell-up.json. The summary says the growth of each
// service from the first checkpoint to the second (the figure: pallet 50 to 450, under 10 MB) and
// from the third to the last (flat within 10% after warm-up).
//
// Usage: memory_bench --routes A,B,... --cellctl PATH [--checkpoints 50,450,1000] [--inflight N]
//                     [--cellctl-every N] [--idle S]
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/idl/inspection.h"
#include "cell/idl/program_store.h"
#include "cell/idl/scheduler.h"
#include "cell/proc/proc.h"

extern char** environ;

namespace {

namespace bus = cell::bus;
using Clock = std::chrono::steady_clock;

std::vector<std::string> Split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string x; std::getline(ss, x, ',');)
    if (!x.empty()) out.push_back(x);
  return out;
}

// The cell's service processes: "cell-interpreter/KT01" -> pid, from cellctl up's record.
std::map<std::string, int> Services() {
  const char* dir = std::getenv("CELL_DATA_DIR");
  if (!dir) throw std::runtime_error("CELL_DATA_DIR is not set");
  std::ifstream in(std::string(dir) + "/cell-up.json");
  auto j = nlohmann::json::parse(in, nullptr, false);
  if (!j.is_array()) throw std::runtime_error("no cell-up.json in CELL_DATA_DIR: is the cell up?");
  std::map<std::string, int> out;
  for (auto& p : j) {  // "cell-interpreter@KT01.service" -> "cell-interpreter@KT01"
    std::string unit = p.value("unit", p.value("service", std::string()));
    if (unit.size() > 8 && unit.ends_with(".service")) unit.resize(unit.size() - 8);
    out[unit] = p.value("pid", 0);
  }
  return out;
}

using Sample = std::map<std::string, long>;  // service -> kB

Sample Measure(const std::map<std::string, int>& services) {
  Sample s;
  for (auto& [name, pid] : services) s[name] = cell::proc::ResidentKb(pid).value_or(-1);  // -1: gone
  return s;
}

void PrintSample(const std::string& when, double seconds, const Sample& s) {
  std::string line = fmt::format("{:<16} {:7.1f} s ", when, seconds);
  for (auto& [name, kb] : s) line += fmt::format(" {} {:.1f}", name, static_cast<double>(kb) / 1024.0);
  fmt::print("{} (MB)\n", line);
  std::fflush(stdout);
}

// Terminal job states as the scheduler publishes them.
class Finished {
 public:
  explicit Finished(bus::Participant& p)
      : reader_(p, bus::topics::kJobStatus, bus::QosKind::kEvent,
                [this](const cell::JobStatus& s, const bus::SampleInfo&) {
                  if (s.state() != cell::JOB_COMPLETED && s.state() != cell::JOB_FAILED &&
                      s.state() != cell::JOB_CANCELLED)
                    return;
                  std::lock_guard lk(mu_);
                  if (s.state() != cell::JOB_COMPLETED && failed_.insert(s.job_id()).second &&
                      failed_.size() <= 3)
                    fmt::print(stderr, "memory_bench: job {} (route {}, pallet {}) ended: {}\n", s.job_id(),
                               s.route().to_string(), s.pallet(), s.reason().to_string());
                  done_.insert(s.job_id());
                  cv_.notify_all();
                }) {}
  // Waits until one of `jobs` has ended; returns it (0 on timeout) and whether it failed.
  int WaitAny(const std::set<int>& jobs, bus::Millis timeout, bool* failed) {
    std::unique_lock lk(mu_);
    int found = 0;
    cv_.wait_for(lk, timeout, [&] {
      for (int j : jobs)
        if (done_.count(j)) {
          found = j;
          return true;
        }
      return false;
    });
    *failed = found && failed_.count(found);
    done_.erase(found);
    return found;
  }

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  std::set<int> done_, failed_;
  bus::Reader<cell::JobStatus> reader_;
};

// The operator's side: the requests cellctl would send, through one participant.
class Operator {
 public:
  explicit Operator(bus::Participant& p)
      : sched_(p, bus::topics::kScheduler),
        store_(p, bus::topics::kProgramStore),
        insp_(p, bus::topics::kInspection) {
    if (!sched_.WaitForServer(bus::Millis(10000))) throw std::runtime_error("no scheduler on the bus");
  }
  int Operate(const std::string& route, int pallet, int n) {
    cell::SchedulerRequest r;
    r.op(cell::SCHED_ROUTE_OPERATE);
    r.name(route);
    r.pallet(pallet);
    r.hdr().idempotency_key(fmt::format("memory-bench-{}-{}", getpid(), n));
    auto rep = sched_.Call(r, bus::Millis(30000));
    bus::ThrowIfError(rep);
    return rep.job_id();
  }
  void Show(int job) {
    cell::SchedulerRequest r;
    r.op(cell::SCHED_JOB_SHOW);
    r.job_id(job);
    bus::ThrowIfError(sched_.Call(r, bus::Millis(30000)));
  }
  // One page of each listing, as `job ls`, `program ls` and `inspect ls` ask for it.
  void Listings() {
    cell::SchedulerRequest j;
    j.op(cell::SCHED_JOB_LIST);
    j.page().limit(50);
    bus::ThrowIfError(sched_.Call(j, bus::Millis(30000)));
    cell::ProgramRequest p;
    p.op(cell::PROGRAM_LIST);
    p.node("HOST");
    p.page().limit(50);
    bus::ThrowIfError(store_.Call(p, bus::Millis(30000)));
    cell::InspectionRequest i;
    i.op(cell::INSPECTION_LIST);
    i.page().limit(50);
    bus::ThrowIfError(insp_.Call(i, bus::Millis(30000)));
  }

 private:
  bus::Client<cell::SchedulerRequest, cell::SchedulerReply> sched_;
  bus::Client<cell::ProgramRequest, cell::ProgramReply> store_;
  bus::Client<cell::InspectionRequest, cell::InspectionReply> insp_;
};

// `cellctl job show JOB` as its own process, its output discarded.
void RunCellctl(const std::string& cellctl, int job) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  std::vector<std::string> args = {cellctl, "job", "show", std::to_string(job)};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid;
  const int rc = posix_spawn(&pid, cellctl.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw std::runtime_error("cannot start " + cellctl);
  int st = 0;
  waitpid(pid, &st, 0);
  if (!WIFEXITED(st) || WEXITSTATUS(st) != 0)
    throw std::runtime_error(fmt::format("cellctl job show {} failed", job));
}

struct Options {
  std::vector<std::string> routes;
  std::string cellctl;
  std::vector<int> checkpoints{50, 450, 1000};
  int inflight = 4, cellctl_every = 25, idle_s = 30;
};

Options Parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--routes") {
      o.routes = Split(next());
    } else if (a == "--cellctl") {
      o.cellctl = next();
    } else if (a == "--checkpoints") {
      o.checkpoints.clear();
      for (auto& c : Split(next())) o.checkpoints.push_back(std::stoi(c));
    } else if (a == "--inflight") {
      o.inflight = std::stoi(next());
    } else if (a == "--cellctl-every") {
      o.cellctl_every = std::stoi(next());
    } else if (a == "--idle") {
      o.idle_s = std::stoi(next());
    } else {
      throw std::invalid_argument("unknown argument " + a);
    }
  }
  if (o.routes.empty() || o.cellctl.empty() || o.checkpoints.empty() || o.inflight < 1 || o.inflight > 100)
    throw std::invalid_argument("--routes and --cellctl are required; --inflight is 1-100");
  return o;
}

// Growth of the three services the issue measures, and of the rest, between two samples.
void Summarize(const std::vector<std::pair<std::string, Sample>>& samples) {
  if (samples.size() < 2) return;
  auto growth = [&](const std::string& svc, size_t a, size_t b) {
    return static_cast<double>(samples[b].second.at(svc) - samples[a].second.at(svc)) / 1024.0;
  };
  for (auto& [svc, kb] : samples.front().second) {
    const bool target =
        svc == "cell-program-store" || svc == "cell-scheduler" || svc == "cell-inspection-writer";
    std::string line = fmt::format("{:<26} {} -> {}: {:+.1f} MB", svc, samples[0].first, samples[1].first,
                                   growth(svc, 0, 1));
    if (target) line += growth(svc, 0, 1) < 10.0 ? " (target < 10 MB: met)" : " (target < 10 MB: MISSED)";
    // Warm-up ends at the third checkpoint; the last checkpoint is the sample before the idle one.
    if (const size_t a = 2, b = samples.size() - 2; samples.size() > 4) {
      const double base = static_cast<double>(samples[a].second.at(svc));
      const double pct = 100.0 * (static_cast<double>(samples[b].second.at(svc)) - base) / base;
      line += fmt::format("; {} -> {}: {:+.1f}%", samples[a].first, samples[b].first, pct);
      if (target) line += pct < 10.0 ? " (flat within 10%: met)" : " (flat within 10%: MISSED)";
    }
    fmt::print("{}\n", line);
  }
}

int Run(const Options& o) {
  const auto services = Services();
  bus::Participant p("memory-bench");
  Finished finished(p);
  Operator op(p);
  const auto t0 = Clock::now();
  auto secs = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  std::vector<std::pair<std::string, Sample>> samples;
  PrintSample("start", 0, Measure(services));
  std::set<int> live;
  std::map<int, int> pallet_of;  // live job -> pallet
  std::set<int> busy;            // pallets in a live job
  int issued = 0, done = 0, failed = 0, next_pallet = 1;
  size_t cp = 0;
  const int total = o.checkpoints.back();
  while (done < total) {
    while (issued < total && static_cast<int>(live.size()) < o.inflight) {
      while (busy.count(next_pallet)) next_pallet = next_pallet % 200 + 1;  // pallets 1-200, reused
      const int job =
          op.Operate(o.routes[static_cast<size_t>(issued) % o.routes.size()], next_pallet, issued);
      live.insert(job);
      pallet_of[job] = next_pallet;
      busy.insert(next_pallet);
      next_pallet = next_pallet % 200 + 1;
      ++issued;
    }
    bool bad = false;
    const int job = finished.WaitAny(live, bus::Millis(120000), &bad);
    if (!job) throw std::runtime_error(fmt::format("no job ended within 120 s ({} live)", live.size()));
    live.erase(job);
    busy.erase(pallet_of[job]);
    pallet_of.erase(job);
    ++done;
    failed += bad;
    op.Show(job);
    if (done % 10 == 0) op.Listings();
    if (o.cellctl_every > 0 && done % o.cellctl_every == 0) RunCellctl(o.cellctl, job);
    if (cp < o.checkpoints.size() && done == o.checkpoints[cp]) {
      samples.emplace_back(fmt::format("pallet {}", done), Measure(services));
      PrintSample(samples.back().first, secs(), samples.back().second);
      ++cp;
    }
  }
  std::this_thread::sleep_for(std::chrono::seconds(o.idle_s));
  samples.emplace_back(fmt::format("idle {} s", o.idle_s), Measure(services));
  PrintSample(samples.back().first, secs(), samples.back().second);
  fmt::print("{} pallets in {:.0f} s ({:.1f} pallets/s, {} failed)\n", done, secs() - o.idle_s,
             done / (secs() - o.idle_s), failed);
  Summarize(samples);
  return failed ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Run(Parse(argc, argv));
  } catch (const std::invalid_argument& e) {
    fmt::print(
        stderr,
        "memory_bench: {}\nusage: memory_bench --routes A,B --cellctl PATH [--checkpoints 50,450,1000] "
        "[--inflight N] [--cellctl-every N] [--idle S]\n",
        e.what());
    return 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "memory_bench: {}\n", e.what());
    return 1;
  }
}
