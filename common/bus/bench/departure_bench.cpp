// bus_departure_bench: participants that leave a running cell, against processes that watch them (issue 38:
// the Fast DDS 2.9.1 lease-timer abort). Not a test.
//
//   bus_departure_bench [--observers K] [--leavers L] [--life MS] [--seconds S] [--stack fastdds|cyclonedds]
//
// K observer processes each hold a participant with a reader and a writer (as a service does). L loops each
// start a leaver process after another: a participant with a writer that lives MS ms (default 3500: past the
// 3 s lease, so each observer's lease timer for it has fired at least once) and is then destroyed cleanly.
// After S seconds it prints the departures and every observer that did not live to the end, with the tail of
// its stderr, and exits 1 if any died. The domain is CELL_DOMAIN.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cell/bus/bus.h"
#include "cell/idl/station.h"

namespace bus = cell::bus;

namespace {

const char* kTopic = "bench/departure";

std::atomic<bool> g_stop{false};
void OnTerm(int) {
  g_stop = true;
}

int Observe(const std::string& stack) {
  signal(SIGTERM, OnTerm);
  bus::Participant p(bus::Named("departure-bench-observer", stack));
  bus::Reader<cell::StationStatus> r(p, kTopic, bus::QosKind::kState);
  bus::Writer<cell::StationStatus> w(p, kTopic, bus::QosKind::kState);
  cell::StationStatus s;
  s.station("OBSERVER");
  while (!g_stop) {
    w.Write(s);  // traffic to every leaver, as a service's heartbeat is
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  return 0;
}

int Leave(const std::string& stack, int life_ms) {
  bus::Participant p(bus::Named("departure-bench-leaver", stack));
  bus::Writer<cell::StationStatus> w(p, kTopic, bus::QosKind::kState);
  cell::StationStatus s;
  s.station("LEAVER");
  w.Write(s);
  std::this_thread::sleep_for(std::chrono::milliseconds(life_ms));
  return 0;  // the participant is destroyed here, as a process that ends cleanly destroys it
}

pid_t Spawn(const std::vector<std::string>& args, const std::string& err) {
  pid_t pid = fork();
  if (pid == 0) {
    if (!err.empty()) {
      FILE* f = std::freopen(err.c_str(), "w", stderr);
      if (!f) _exit(126);
    }
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv("/proc/self/exe", argv.data());
    _exit(127);
  }
  return pid;
}

std::string Tail(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string t = ss.str();
  return t.size() > 400 ? "..." + t.substr(t.size() - 400) : t;
}

}  // namespace

int main(int argc, char** argv) {
  int observers = 8, leavers = 8, life = 3500, seconds = 600;
  std::string stack = "fastdds";
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto next = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    if (a == "--observers") {
      observers = std::atoi(next().c_str());
    } else if (a == "--leavers") {
      leavers = std::atoi(next().c_str());
    } else if (a == "--life") {
      life = std::atoi(next().c_str());
    } else if (a == "--seconds") {
      seconds = std::atoi(next().c_str());
    } else if (a == "--stack") {
      stack = next();
    } else if (a == "--observe") {
      return Observe(next());
    } else if (a == "--leave") {
      std::string st = next();
      return Leave(st, std::atoi(next().c_str()));
    } else {
      std::fprintf(stderr,
                   "usage: bus_departure_bench [--observers K] [--leavers L] [--life MS] [--seconds S] "
                   "[--stack fastdds|cyclonedds]\n");
      return 2;
    }
  }
  const std::string dir = std::string(std::getenv("TMPDIR") ? std::getenv("TMPDIR") : "/tmp");
  std::vector<pid_t> obs;
  std::vector<std::string> errs;
  for (int k = 0; k < observers; ++k) {
    errs.push_back(dir + "/departure-bench-" + std::to_string(getpid()) + "-" + std::to_string(k) + ".err");
    obs.push_back(Spawn({"bus_departure_bench", "--observe", stack}, errs.back()));
  }
  std::atomic<long> departures{0}, failed{0};
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  std::vector<std::thread> loops;
  for (int l = 0; l < leavers; ++l)
    loops.emplace_back([&, l] {
      // Staggered, so departures spread over the observers' lease timers.
      std::this_thread::sleep_for(std::chrono::milliseconds(life * l / std::max(1, leavers)));
      while (std::chrono::steady_clock::now() < end) {
        pid_t pid = Spawn({"bus_departure_bench", "--leave", stack, std::to_string(life)}, "/dev/null");
        int st = 0;
        waitpid(pid, &st, 0);
        if (WIFEXITED(st) && WEXITSTATUS(st) == 0)
          ++departures;
        else
          ++failed;
      }
    });
  for (auto& t : loops) t.join();
  int died = 0;
  for (int k = 0; k < observers; ++k) {
    int st = 0;
    if (waitpid(obs[k], &st, WNOHANG) == obs[k]) {
      ++died;
      std::printf("observer %d (pid %d) died: %s %d; its stderr ends:\n%s\n", k, obs[k],
                  WIFSIGNALED(st) ? "signal" : "exit", WIFSIGNALED(st) ? WTERMSIG(st) : WEXITSTATUS(st),
                  Tail(errs[k]).c_str());
      continue;
    }
    kill(obs[k], SIGTERM);
    waitpid(obs[k], &st, 0);
  }
  for (auto& e : errs) std::remove(e.c_str());
  std::printf("%s: %ld departures (%ld leavers failed) watched by %d observers for %d s: %d observers died\n",
              stack.c_str(), departures.load(), failed.load(), observers, seconds, died);
  return died == 0 ? 0 : 1;
}
