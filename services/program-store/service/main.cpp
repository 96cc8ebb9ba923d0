// cell-program-store: the cell's durable library of programs and files (SQLite under
// CELL_DATA_DIR), served over the bus.
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "cell/config/config.h"
#include "cell/daemon/daemon.h"
#include "cell/health/health.h"
#include "cell/identity/identity.h"
#include "cell/interp/station_rules.h"
#include "cell/log/log.h"
#include "cell/program_store/service.h"

namespace {

// How long a chunked upload may stay silent before it is dropped (its client died): 120 s, or
// CELL_PROGRAM_STORE_STREAM_IDLE_S (tests shorten it).
std::chrono::seconds StreamIdle() {
  if (const char* v = std::getenv("CELL_PROGRAM_STORE_STREAM_IDLE_S"); v && *v) {
    char* end = nullptr;
    long s = std::strtol(v, &end, 10);
    if (*end != '\0' || s < 1 || s > 86400)
      throw cell::Error(cell::Errc::kInvalidArgument,
                        "CELL_PROGRAM_STORE_STREAM_IDLE_S must be 1..86400 seconds");
    return std::chrono::seconds(s);
  }
  return std::chrono::seconds(120);
}

}  // namespace

int main() {
  cell::log::Init("cell-program-store");
  try {
    cell::daemon::Daemon daemon;
    cell::program_store::StoreOptions opts;
    opts.data_dir = cell::config::DataDir();
    // A station namespace falls back to the station's dialect for files that do not show theirs. A
    // Balt-System station also has the memories MP0, MP2..MP6 as "ID/MPn" (MP1, the default, is "ID").
    for (const auto& id : cell::config::ListStations()) {
      const std::string dialect = cell::interp::LoadStation(id).dialect;
      std::vector<std::string> spaces = {id};
      if (dialect == "balt") {
        for (const char* mp : {"/MP0", "/MP2", "/MP3", "/MP4", "/MP5", "/MP6"}) spaces.push_back(id + mp);
      }
      for (const auto& ns : spaces) {
        opts.namespaces.push_back(ns);
        opts.namespace_dialects[ns] = cell::program_store::ParseDialect(dialect);
      }
    }
    const std::chrono::seconds idle = StreamIdle();
    cell::bus::Participant bus("cell-program-store");
    cell::health::Announcer health(bus, "cell-program-store");
    cell::identity::Claim claim(bus, health);
    claim.Confirm();  // one program store per cell: before the database is opened (and its scratch emptied)
    cell::program_store::ProgramStore store(opts);
    cell::program_store::Service service(bus, store, idle);
    health.Set(cell::SERVICE_READY, "serving " + (opts.data_dir / opts.database_file).string());
    daemon.NotifyReady("serving programs");
    spdlog::info("ready on domain {} with {}, database {}", bus.domain(), bus.vendor(),
                 (opts.data_dir / opts.database_file).string());
    // Abandoned uploads are looked for at a quarter of the idle limit (at least every 30 s), whatever the
    // main loop's tick (1 s, or a quarter of the systemd watchdog interval).
    const auto every = std::clamp<std::chrono::steady_clock::duration>(
        idle / 4, std::chrono::milliseconds(250), std::chrono::seconds(30));
    auto next = std::chrono::steady_clock::now() + every;
    daemon.RunUntilStop([&] {
      if (std::chrono::steady_clock::now() >= next) {
        service.Housekeeping();
        next = std::chrono::steady_clock::now() + every;
      }
      return true;
    });
    daemon.NotifyStopping();
    return 0;
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
}
