// bus_discovery_bench: how long a new process takes to find a running one, per pair of DDS stacks
// (deploy/bench.d/80-discovery.sh). Not a test.
//
//   bus_discovery_bench [--runs N]
//   bus_discovery_bench --join EXPECTED   (a running cell on CELL_DOMAIN: when a newcomer has heard it)
//
// For each stack S a server process runs (a state writer with one sample, and a request/reply server); for
// each stack P, N fresh probe processes on P each measure, from the start of main(), (a) the first sample of
// the state topic (a late joiner: the server's writer must find the probe's reader) and (b) the first reply
// to a request (both directions matched). Prints median, min and max per pair, and the median as a ratio to
// Fast DDS -> Fast DDS measured in the same run. The domain is CELL_DOMAIN.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/idl/health.h"
#include "cell/idl/station.h"

namespace bus = cell::bus;

namespace {

const auto kStart = std::chrono::steady_clock::now();  // as close to main() as a static gets
const char* kStacks[] = {"fastdds", "cyclonedds"};

double MsSinceStart() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - kStart).count();
}

int Serve(const std::string& stack) {
  bus::Participant p(bus::Named("discovery-bench-server", stack));
  bus::Writer<cell::StationStatus> w(p, "bench/discovery/" + stack, bus::QosKind::kState);
  cell::StationStatus s;
  s.station("BENCH");
  w.Write(s);
  bus::Server<cell::StationRequest, cell::StationReply> server(p, "bench/discovery/" + stack + "/svc",
                                                               [](const cell::StationRequest& r) {
                                                                 cell::StationReply rep;
                                                                 rep.station(r.station());
                                                                 return rep;
                                                               });
  std::printf("serving\n");
  std::fflush(stdout);
  pause();  // until SIGTERM
  return 0;
}

int Probe(const std::string& stack, const std::string& server) {
  bus::Participant p(bus::Named("discovery-bench-probe", stack));
  bus::Client<cell::StationRequest, cell::StationReply> client(p, "bench/discovery/" + server + "/svc");
  bus::Reader<cell::StationStatus> r(p, "bench/discovery/" + server, bus::QosKind::kState);
  double sample = -1, reply = -1;
  std::thread t([&] {
    if (r.Take(bus::Millis(10000))) sample = MsSinceStart();
  });
  cell::StationRequest req;
  req.station("BENCH");
  try {
    client.Call(req, bus::Millis(10000), bus::Millis(50));
    reply = MsSinceStart();
  } catch (const std::exception&) {
  }
  t.join();
  std::printf("%.2f %.2f\n", sample, reply);
  return sample < 0 || reply < 0 ? 1 : 0;
}

struct Child {
  pid_t pid;
  FILE* out;
};

Child Spawn(const std::vector<std::string>& args) {
  int fd[2];
  if (pipe(fd) != 0) std::exit(1);
  pid_t pid = fork();
  if (pid == 0) {
    dup2(fd[1], 1);
    close(fd[0]);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv("/proc/self/exe", argv.data());
    _exit(127);
  }
  close(fd[1]);
  return {pid, fdopen(fd[0], "r")};
}

std::string Stats(std::vector<double> v, double base) {
  std::sort(v.begin(), v.end());
  double med = v[v.size() / 2];
  long slow = std::count_if(v.begin(), v.end(), [](double x) { return x > 500; });
  char buf[160];
  std::snprintf(buf, sizeof buf, "median %7.1f ms  min %7.1f  max %7.1f  >0.5 s %ld/%zu  ratio %.2f", med,
                v.front(), v.back(), slow, v.size(), base > 0 ? med / base : 1.0);
  return buf;
}

}  // namespace

// A newcomer joining a running cell (issue 43, a large cell): ms from main() until it has heard the first
// and then every one of `expected` services' heartbeats (state topic cell/health, transient-local), and the
// remote participants it knows at each step.
int Join(int expected) {
  bus::Participant p(bus::Named("discovery-bench-join"));
  std::mutex mu;
  std::set<std::string> heard;
  bus::Reader<cell::ServiceHealth> r(p, bus::topics::kHealth, bus::QosKind::kState,
                                     [&](const cell::ServiceHealth& h, const bus::SampleInfo&) {
                                       std::lock_guard lk(mu);
                                       heard.insert(h.service_id().to_string());
                                     });
  size_t last = 0;
  for (int i = 0; i < 6000; ++i) {
    size_t n;
    {
      std::lock_guard lk(mu);
      n = heard.size();
    }
    if (n != last && (last == 0 || n / 10 != last / 10 || n >= static_cast<size_t>(expected)))
      std::printf("%8.0f ms: %3zu services heard, %3d participants\n", MsSinceStart(), n,
                  p.RemoteParticipants());
    last = n;
    if (n >= static_cast<size_t>(expected)) return 0;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::printf("gave up after %.0f ms: %zu of %d services heard\n", MsSinceStart(), last, expected);
  return 1;
}

int main(int argc, char** argv) {
  std::vector<std::string> a(argv, argv + argc);
  if (a.size() == 3 && a[1] == "--join") return Join(std::atoi(a[2].c_str()));
  if (a.size() == 3 && a[1] == "--serve") return Serve(a[2]);
  if (a.size() == 4 && a[1] == "--probe") return Probe(a[2], a[3]);
  int runs = 10;
  if (a.size() == 3 && a[1] == "--runs") runs = std::max(1, std::atoi(a[2].c_str()));
  std::map<std::string, std::vector<double>> sample, reply;
  for (const char* server : kStacks) {
    Child s = Spawn({a[0], "--serve", server});
    char line[64];
    if (!std::fgets(line, sizeof line, s.out)) return 1;  // "serving"
    for (const char* probe : kStacks)
      for (int i = 0; i < runs; ++i) {
        Child c = Spawn({a[0], "--probe", probe, server});
        double ms = -1, rs = -1;
        if (std::fscanf(c.out, "%lf %lf", &ms, &rs) != 2 || ms < 0 || rs < 0) {
          std::fprintf(stderr, "probe %s -> %s failed\n", probe, server);
          return 1;
        }
        fclose(c.out);
        waitpid(c.pid, nullptr, 0);
        const std::string pair = std::string(probe) + " -> " + server;
        sample[pair].push_back(ms);
        reply[pair].push_back(rs);
      }
    kill(s.pid, SIGTERM);
    waitpid(s.pid, nullptr, 0);
    fclose(s.out);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  const std::string base = "fastdds -> fastdds";
  std::printf("new process (probe) -> running process (server), %d runs each, ms from main():\n", runs);
  for (auto& [pair, v] : sample)
    std::printf("  %-26s first state sample: %s\n", pair.c_str(), Stats(v, median(sample[base])).c_str());
  for (auto& [pair, v] : reply)
    std::printf("  %-26s first reply:        %s\n", pair.c_str(), Stats(v, median(reply[base])).c_str());
  return 0;
}
