// cell-program-store: the cell's durable library of programs and files (SQLite under
// CELL_DATA_DIR), served over the bus.
#include <spdlog/spdlog.h>

#include "cell/config/config.h"
#include "cell/daemon/daemon.h"
#include "cell/health/health.h"
#include "cell/log/log.h"
#include "cell/program_store/service.h"

int main() {
  cell::log::Init("cell-program-store");
  try {
    cell::daemon::Daemon daemon;
    cell::program_store::StoreOptions opts;
    opts.data_dir = cell::config::DataDir();
    opts.namespaces = cell::config::ListStations();
    cell::program_store::ProgramStore store(opts);
    cell::bus::Participant bus("cell-program-store");
    cell::health::Announcer health(bus, "cell-program-store");
    cell::program_store::Service service(bus, store);
    health.Set(cell::SERVICE_READY, "serving " + (opts.data_dir / opts.database_file).string());
    daemon.NotifyReady("serving programs");
    spdlog::info("ready on domain {}, database {}", bus.domain(), (opts.data_dir / opts.database_file).string());
    int n = 0;
    daemon.RunUntilStop([&] {
      if (++n % 30 == 0) service.Housekeeping();
      return true;
    });
    daemon.NotifyStopping();
    return 0;
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
}
