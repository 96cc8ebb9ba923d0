// cell-daemon-probe: the smallest service built on cell_daemon, for tests (never installed).
//   cell-daemon-probe [--station ID] [--unhealthy-after N] [--startup-ms MS]
// Starts, reports ready, ticks the watchdog while healthy (unhealthy after N health checks, if given),
// stops on SIGTERM/SIGINT with STOPPING=1 and exit code 0.
#include <cstdlib>
#include <string>
#include <thread>

#include "cell/daemon/daemon.h"
#include "cell/log/log.h"

int main(int argc, char** argv) {
  std::string station;
  long unhealthy_after = -1;
  long startup_ms = 0;
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--station") {
      station = argv[i + 1];
    } else if (a == "--unhealthy-after") {
      unhealthy_after = std::atol(argv[i + 1]);
    } else if (a == "--startup-ms") {
      startup_ms = std::atol(argv[i + 1]);
    } else {
      std::fprintf(stderr, "cell-daemon-probe: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  cell::log::Init("cell-daemon-probe", station);
  cell::daemon::Daemon daemon;
  std::this_thread::sleep_for(std::chrono::milliseconds(startup_ms));
  daemon.NotifyReady("probe ready");
  spdlog::info("ready; watchdog {} us", daemon.WatchdogInterval().count());
  long checks = 0;
  daemon.RunUntilStop([&] { return unhealthy_after < 0 || ++checks <= unhealthy_after; });
  daemon.NotifyStopping("probe stopping");
  spdlog::info("stopped by signal {}", daemon.StopSignal());
  return 0;
}
