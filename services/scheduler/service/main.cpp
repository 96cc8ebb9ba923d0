// cell-scheduler: the host of the cell: pallet maps, routes, OPERATE dispatch, backlog, jobs.
#include <spdlog/spdlog.h>

#include "cell/config/config.h"
#include "cell/daemon/daemon.h"
#include "cell/health/health.h"
#include "cell/identity/identity.h"
#include "cell/log/log.h"
#include "cell/scheduler/service.h"

int main() {
  cell::log::Init("cell-scheduler");
  try {
    cell::daemon::Daemon daemon;
    cell::bus::Participant bus("cell-scheduler");
    cell::health::Announcer health(bus, "cell-scheduler");
    cell::identity::Claim claim(bus, health);
    claim.Confirm();  // one scheduler per cell
    cell::scheduler::Service svc(bus, cell::config::DataDir());
    svc.Start();
    health.Set(cell::SERVICE_READY);
    daemon.NotifyReady("scheduling");
    spdlog::info("ready on domain {} with {}", bus.domain(), bus.vendor());
    while (!daemon.WaitForStop(std::chrono::milliseconds(250))) {
      svc.Tick();
      if (svc.Healthy()) daemon.Tick();
    }
    daemon.NotifyStopping();
    svc.Stop();
    return 0;
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
}
