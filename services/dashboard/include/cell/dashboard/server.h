// The dashboard's HTTP side (cpp-httplib): the live page, its state and event stream (server-sent
// events), the toolpath of what a station runs, and the MTConnect agent interface. Read-only: GET only,
// nothing reaches the cell.
//
//   /                      the page, with the current state inside it (one GET renders it)
//   /static/chart.js       Chart.js from Debian's libjs-chart.js
//   /api/state             the state as JSON;  /api/job/<id>  one job with its decision log
//   /api/events            server-sent events after Last-Event-ID (or ?after=N); `resync` when too old
//   /api/station/<ID>/path[?program=]   the toolpath of what the station runs (cell/dashboard/path.h), JSON
//   /station/<ID>/path.svg[?program=]   the same plot as a plain SVG page
//   /api/plan              the scheduler's plan beside what actually ran, for the Gantt chart (gantt.h)
//   /probe /current /sample?from=&count= /assets /asset/<id>, and /<device>/probe|current|sample
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <utility>

#include "cell/dashboard/cell_view.h"
#include "cell/dashboard/gantt.h"

namespace httplib {
class Server;
}

namespace cell::dashboard {

struct ListenAddress {
  std::string host = "127.0.0.1";
  int port = 7878;  // 0: any free port
};

// "HOST:PORT", "[V6]:PORT" or ":PORT" (loopback). Throws cell::Error(kInvalidArgument) naming the value.
ListenAddress ParseListen(const std::string& text);
bool IsLoopback(const std::string& host);

struct ServerOptions {
  ListenAddress listen;
  std::string cert_file, key_file;  // TLS when both are set; required for an address beyond loopback
  std::string chartjs = "/usr/share/javascript/chart.js/chart.min.js";
  int max_streams = 200;  // live browsers at once; more get 503
};

// CELL_HTTP (default 127.0.0.1:7878), CELL_HTTP_CERT, CELL_HTTP_KEY. Throws cell::Error(kInvalidArgument)
// for a malformed address, or one beyond loopback without a certificate and key.
ServerOptions ServerOptionsFromEnv();

// What answers the path routes: an HTTP status and a JSON body (with "svg", or "error"), for a station and
// program. The HTTP side knows no bus; cell-dashboard gives it cell::dashboard::Paths.
using PathSource =
    std::function<std::pair<int, nlohmann::json>(const std::string& station, const std::string& program)>;

// The scheduler's plan as last fetched (cell::dashboard::PlanSource in cell-dashboard); it must not block.
using PlanSourceFn = std::function<PlanFetch()>;

class HttpServer {
 public:
  HttpServer(CellView& view, ServerOptions opts);
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  // Binds and serves on its own thread. Throws cell::Error(kUnavailable) when the address cannot be bound.
  void Start();
  // Before Start. Without one the path routes answer 404.
  void SetPathSource(PathSource source) { paths_ = std::move(source); }
  // Before Start. Without one /api/plan has no rows and says why.
  void SetPlanSource(PlanSourceFn source) { plan_ = std::move(source); }
  void Stop();
  int port() const { return port_; }
  std::string url() const;  // http(s)://host:port/
  int streams() const { return streams_.load(); }
  bool running() const;

 private:
  void Routes();
  void PathRoutes();
  PathSource paths_;
  PlanSourceFn plan_;
  CellView& view_;
  ServerOptions opts_;
  std::unique_ptr<httplib::Server> srv_;
  std::string chartjs_;
  std::atomic<int> streams_{0};
  std::atomic<bool> stopping_{false};
  int port_ = 0;
  std::thread thread_;
};

// The page with the state embedded (exposed for tests).
std::string RenderPage(const nlohmann::json& state);

}  // namespace cell::dashboard
