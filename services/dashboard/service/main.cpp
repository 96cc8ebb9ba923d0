// cell-dashboard: the shop-floor view. Subscribes to the cell's state and event topics and serves the live
// page and the MTConnect agent interface over HTTP (CELL_HTTP, default 127.0.0.1:7878). Read-only: it
// writes nothing to the cell (only its own heartbeat, like every process); its requests are the program
// store's GET of the program a station runs, to draw its toolpath (docs/dashboard.md, "Toolpath"), and the
// scheduler's plan for the Gantt chart ("Plan").
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <fstream>
#include <optional>

#include "cell/bus/bus.h"
#include "cell/config/config.h"
#include "cell/daemon/daemon.h"
#include "cell/dashboard/feed.h"
#include "cell/dashboard/path.h"
#include "cell/dashboard/plan_source.h"
#include "cell/dashboard/server.h"
#include "cell/health/health.h"
#include "cell/identity/identity.h"
#include "cell/interp/interp.h"
#include "cell/log/log.h"
#include "cell/machine/machine_config.h"

int main() {
  cell::log::Init("cell-dashboard");
  try {
    cell::daemon::Daemon daemon;
    auto http_opts = cell::dashboard::ServerOptionsFromEnv();
    cell::dashboard::ViewOptions view_opts;
    if (const char* b = std::getenv("CELL_DASHBOARD_BUFFER"); b && *b) {
      char* end = nullptr;
      long n = std::strtol(b, &end, 10);
      if (*end || n < 16 || n > (1l << 24))
        throw cell::Error(cell::Errc::kInvalidArgument,
                          std::string("CELL_DASHBOARD_BUFFER='") + b + "': observations, 16..16777216");
      view_opts.buffer_size = static_cast<size_t>(n);
    }
    // The page's words for dialects and machine kinds: the registry's titles and the machine tables' own.
    for (const auto* d : cell::interp::Dialects())
      view_opts.vocabulary["dialects"][std::string(d->name())] = std::string(d->title());
    for (const auto& k : cell::machine::MachineKinds())
      view_opts.vocabulary["kinds"][std::string(k.name)] = std::string(k.title);
    cell::dashboard::CellView view(cell::dashboard::LoadStationDefs(), view_opts);
    cell::bus::Participant bus("cell-dashboard");
    // Secured, the dashboard is the read-only viewer (docs/security.md): it publishes nothing, so it neither
    // announces itself on cell/health nor claims its service id.
    std::optional<cell::health::Announcer> health;
    if (bus.identity() != "viewer") {
      health.emplace(bus, "cell-dashboard");
      cell::identity::Claim claim(bus, *health);
      claim.Confirm();  // one dashboard per cell: before it binds its port and writes dashboard.url
    }
    cell::dashboard::PlanSource plan(bus);
    cell::dashboard::FeedOptions feed_opts;
    feed_opts.on_job = [&plan] { plan.Poke(); };
    cell::dashboard::Feed feed(bus, view, feed_opts);
    cell::dashboard::Paths paths(bus);
    cell::dashboard::HttpServer http(view, http_opts);
    http.SetPlanSource([&plan] { return plan.Latest(); });
    http.SetPathSource([&paths](const std::string& station, const std::string& program) {
      auto a = paths.Path(station, program);
      return std::make_pair(a.status, std::move(a.body));
    });
    http.Start();
    // Where a local cell's tools (cellctl up, ./cell demo, tests) find the page when the port was 0.
    std::ofstream(cell::config::DataDir() / "dashboard.url") << http.url() << "\n";
    if (health) health->Set(cell::SERVICE_READY, http.url());
    daemon.NotifyReady("serving " + http.url());
    spdlog::info("ready on domain {} with {}: serving {} (MTConnect: {}probe)", bus.domain(), bus.vendor(),
                 http.url(), http.url());
    while (!daemon.WaitForStop(std::chrono::milliseconds(250))) {
      feed.Tick();
      if (http.running()) daemon.Tick();
    }
    daemon.NotifyStopping();
    http.Stop();
    return 0;
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
}
