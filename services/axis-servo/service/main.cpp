// cell-axis-servo --station ID [--clock real|virtual]: the machine behind one station.
#include <cstdlib>

#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include "cell/config/config.h"
#include "cell/config/dds.h"
#include "cell/daemon/daemon.h"
#include "cell/health/health.h"
#include "cell/identity/identity.h"
#include "cell/log/log.h"
#include "cell/servo/service.h"

int main(int argc, char** argv) {
  CLI::App app{"cell-axis-servo: the simulated machine of one station"};
  std::string station;
  const char* env_clock = std::getenv("CELL_CLOCK");
  std::string clock = env_clock && *env_clock ? env_clock : "real";
  app.add_option("--station", station, "station id (deploy/stations/<ID>.toml)")->required();
  app.add_option("--clock", clock,
                 "real (wall-clock ticks) or virtual (as fast as the CPU allows); "
                 "default: CELL_CLOCK, else real")
      ->check(CLI::IsMember({"real", "virtual"}));
  CLI11_PARSE(app, argc, argv);
  cell::log::Init("cell-axis-servo", station);
  try {
    if (clock != "real" && clock != "virtual")
      throw cell::Error(cell::Errc::kInvalidArgument, "CELL_CLOCK=" + clock + ": expected real or virtual");
    cell::daemon::Daemon daemon;  // its steps name where a start that never ends is stuck
    daemon.Starting("loading the station file");
    auto cfg = cell::config::LoadStation(station);  // validates the [station] table
    auto machine = cell::machine::LoadMachineConfig(cfg.file);
    const auto dds = cell::config::DdsVendor(cfg.dds);  // the station file's dds, else CELL_DDS
    daemon.Starting("joining the bus (" + dds.vendor + ")");
    cell::bus::Participant bus(cell::bus::Named("cell-axis-servo/" + station, dds.vendor));
    cell::health::Announcer health(bus, "cell-axis-servo", station);
    daemon.Starting("claiming the station");
    cell::identity::Claim claim(bus, health);
    claim.Confirm();  // one machine per station: before it takes a segment
    daemon.Starting("starting the machine");
    cell::servo::Service svc(
        bus, machine, clock == "virtual" ? cell::servo::ClockKind::kVirtual : cell::servo::ClockKind::kReal);
    svc.Start();
    health.Set(cell::SERVICE_READY, clock + " clock");
    daemon.NotifyReady("machine " + station + " ready (" + clock + " clock)");
    spdlog::info("ready on domain {} with {} (from {}) ({} clock, {} kind)", bus.domain(), dds.vendor,
                 dds.source, clock, machine.kind);
    daemon.RunUntilStop([&] { return svc.Healthy(); });
    daemon.NotifyStopping();
    svc.Stop();
    return 0;
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
}
