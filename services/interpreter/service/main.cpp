// cell-interpreter --station ID: the CNC of one station (language, tool table, variables, runs).
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include "cell/config/config.h"
#include "cell/config/dds.h"
#include "cell/daemon/daemon.h"
#include "cell/health/health.h"
#include "cell/identity/identity.h"
#include "cell/interp/station_rules.h"
#include "cell/log/log.h"
#include "cell/station/service.h"

int main(int argc, char** argv) {
  CLI::App app{"cell-interpreter: the CNC of one station"};
  std::string station;
  app.add_option("--station", station, "station id (deploy/stations/<ID>.toml)")->required();
  CLI11_PARSE(app, argc, argv);
  cell::log::Init("cell-interpreter", station);
  try {
    cell::daemon::Daemon daemon;  // its steps name where a start that never ends is stuck
    daemon.Starting("loading the station file");
    auto cfg = cell::interp::LoadStation(station);      // the registry checks its dialect and tools
    const auto dds = cell::config::DdsVendor(cfg.dds);  // the station file's dds, else CELL_DDS
    daemon.Starting("joining the bus (" + dds.vendor + ")");
    cell::bus::Participant bus(cell::bus::Named("cell-interpreter/" + station, dds.vendor));
    cell::health::Announcer health(bus, "cell-interpreter", station);
    daemon.Starting("claiming the station");
    cell::identity::Claim claim(bus, health);
    claim.Confirm();  // one process per station: before the station serves anything
    daemon.Starting("opening the station's topics and database");
    cell::station::Service st(bus, cfg, cell::config::DataDir());
    daemon.Starting("starting the station");
    st.Start();
    health.Set(cell::SERVICE_READY, cfg.dialect);
    daemon.NotifyReady("station " + station + " ready");
    spdlog::info("ready on domain {} with {} (from {}) ({} station)", bus.domain(), dds.vendor, dds.source,
                 cfg.dialect);
    daemon.RunUntilStop([&] { return st.Healthy(); });
    daemon.NotifyStopping();
    st.Stop();
    return 0;
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
}
