// cell-dnc --station ID: the DNC process of one station's serial line (docs/dnc.md). It resolves the
// station file's [serial] table against the control's defaults, takes the line exclusively and holds it,
// and serves the station's DNC requests (cell::dnc::Service), announced on the bus like every process; a
// station without [serial] has no cell-dnc.
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include "cell/bus/bus.h"
#include "cell/config/config.h"
#include "cell/config/dds.h"
#include "cell/daemon/daemon.h"
#include "cell/dnc/line.h"
#include "cell/dnc/service.h"
#include "cell/dnc/settings.h"
#include "cell/health/health.h"
#include "cell/identity/identity.h"
#include "cell/log/log.h"

namespace {

// The station's line, checked against its control; errors name the station file.
cell::dnc::Serial LineOf(const cell::config::StationConfig& cfg) {
  if (!cfg.serial) {
    throw cell::Error(cell::Errc::kFailedPrecondition,
                      cfg.file.string() + ": no [serial] table: station " + cfg.id + " has no DNC line");
  }
  try {
    return cell::dnc::Resolve(cell::dnc::ControlOf(cfg.dialect), *cfg.serial);
  } catch (const cell::Error& e) {
    throw cell::Error(e.code(), cfg.file.string() + ": " + e.what());
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"cell-dnc: programs to and from one station's control over its serial line"};
  std::string station;
  app.add_option("--station", station, "station id (deploy/stations/<ID>.toml with a [serial] table)")
      ->required();
  CLI11_PARSE(app, argc, argv);
  cell::log::Init("cell-dnc", station);
  try {
    cell::daemon::Daemon daemon;
    auto cfg = cell::config::LoadStation(station);
    const cell::dnc::Serial serial = LineOf(cfg);
    auto open = [serial] { return std::unique_ptr<cell::dnc::Port>(cell::dnc::TtyPort::Open(serial)); };
    auto line = open();  // exclusive: a second cell-dnc on the line is refused before it joins the bus
    const auto dds = cell::config::DdsVendor(cfg.dds);
    cell::bus::Participant bus(cell::bus::Named("cell-dnc/" + station, dds.vendor));
    cell::health::Announcer health(bus, "cell-dnc", station);
    cell::identity::Claim claim(bus, health);
    claim.Confirm();  // one process per serial line
    cell::dnc::Service service(bus, station, cfg.dialect, serial, std::move(line), open);
    health.Set(cell::SERVICE_READY, cfg.dialect);
    daemon.NotifyReady("line " + serial.device + " ready");
    spdlog::info("ready on domain {} with {}: {} {} baud {} {}{}{} flow {} end {}", bus.domain(), dds.vendor,
                 serial.device, serial.baud, cell::dnc::CodeName(serial.format.code), serial.format.data_bits,
                 cell::dnc::ParityName(serial.format.parity).substr(0, 1), serial.stop_bits,
                 cell::dnc::FlowName(serial.flow), cell::dnc::EndName(serial.format.end));
    daemon.RunUntilStop([&service] {
      service.Tick();
      return true;
    });
    daemon.NotifyStopping();
    return 0;
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
}
