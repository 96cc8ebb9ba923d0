// cell-inspection-writer: durable run records and inspection files, served over the bus.
#include <spdlog/spdlog.h>

#include "cell/bus/bus.h"
#include "cell/config/config.h"
#include "cell/daemon/daemon.h"
#include "cell/health/health.h"
#include "cell/identity/identity.h"
#include "cell/inspection/records.h"
#include "cell/inspection/service.h"
#include "cell/log/log.h"

int main() {
  cell::log::Init("cell-inspection-writer");
  try {
    cell::daemon::Daemon daemon;
    cell::inspection::Records records(cell::config::DataDir() / "records");
    cell::bus::Participant bus("cell-inspection-writer");
    cell::health::Announcer health(bus, "cell-inspection-writer");
    cell::identity::Claim claim(bus, health);
    claim.Confirm();  // one writer per cell
    cell::inspection::Service service(bus, records);
    health.Set(cell::SERVICE_READY);
    daemon.NotifyReady("writing records");
    spdlog::info("ready on domain {} with {}", bus.domain(), bus.vendor());
    daemon.RunUntilStop([] { return true; });
    daemon.NotifyStopping();
    return 0;
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
}
