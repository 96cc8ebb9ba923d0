#include "cell/dashboard/server.h"

#include <httplib.h>

#include <charconv>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "cell/error/error.h"
#include "cell/records/time.h"

namespace cell::dashboard {

// The page's own assets, embedded at build time from services/dashboard/www (www_assets.cpp).
extern const char* const kIndexHtml;
extern const char* const kStyleCss;
extern const char* const kAppJs;

namespace {

constexpr const char* kXml = "application/xml";

std::optional<std::int64_t> Int(const std::string& s) {
  std::int64_t v = 0;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || p != s.data() + s.size() || s.empty()) return std::nullopt;
  return v;
}

void Replace(std::string& text, const std::string& what, const std::string& with) {
  auto at = text.find(what);
  if (at != std::string::npos) text.replace(at, what.size(), with);
}

}  // namespace

bool IsLoopback(const std::string& host) {
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

ListenAddress ParseListen(const std::string& text) {
  auto bad = [&](const std::string& why) {
    return Error(Errc::kInvalidArgument, "CELL_HTTP='" + text + "': " + why + " (expected HOST:PORT)");
  };
  ListenAddress a;
  auto colon = text.rfind(':');
  if (colon == std::string::npos) throw bad("no port");
  std::string host = text.substr(0, colon), port = text.substr(colon + 1);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  if (host.empty()) host = "127.0.0.1";
  if (host.find_first_of(" /[]") != std::string::npos) throw bad("bad host '" + host + "'");
  auto p = Int(port);
  if (!p || *p < 0 || *p > 65535) throw bad("port must be 0..65535");
  a.host = host;
  a.port = static_cast<int>(*p);
  return a;
}

ServerOptions ServerOptionsFromEnv() {
  ServerOptions o;
  const char* http = std::getenv("CELL_HTTP");
  if (http && *http) o.listen = ParseListen(http);
  if (const char* c = std::getenv("CELL_HTTP_CERT")) o.cert_file = c;
  if (const char* k = std::getenv("CELL_HTTP_KEY")) o.key_file = k;
  if (o.cert_file.empty() != o.key_file.empty())
    throw Error(Errc::kInvalidArgument, "CELL_HTTP_CERT and CELL_HTTP_KEY go together (TLS needs both)");
  if (!IsLoopback(o.listen.host) && o.cert_file.empty())
    throw Error(Errc::kInvalidArgument,
                "CELL_HTTP='" + o.listen.host + ":" + std::to_string(o.listen.port) +
                    "' is beyond loopback: set CELL_HTTP_CERT and CELL_HTTP_KEY (TLS) "
                    "or listen on 127.0.0.1");
  return o;
}

std::string RenderPage(const nlohmann::json& state) {
  std::string page = kIndexHtml;
  Replace(page, "/*STYLE*/", kStyleCss);
  Replace(page, "/*APP*/", kAppJs);
  // Inside <script type="application/json">: only "</" could end the element early.
  std::string js = state.dump();
  for (size_t at = 0; (at = js.find("</", at)) != std::string::npos; at += 3) js.replace(at, 2, "<\\/");
  Replace(page, "/*STATE*/", js);
  return page;
}

HttpServer::HttpServer(CellView& view, ServerOptions opts) : view_(view), opts_(std::move(opts)) {
  std::ifstream in(opts_.chartjs, std::ios::binary);
  if (in) {
    std::stringstream ss;
    ss << in.rdbuf();
    chartjs_ = ss.str();
  }
  if (!opts_.cert_file.empty())
    srv_ = std::make_unique<httplib::SSLServer>(opts_.cert_file.c_str(), opts_.key_file.c_str());
  else
    srv_ = std::make_unique<httplib::Server>();
  if (!srv_->is_valid())
    throw Error(Errc::kInvalidArgument,
                "cannot use TLS certificate '" + opts_.cert_file + "' and key '" + opts_.key_file + "'");
  // Every live browser holds one worker for its event stream; the rest serve requests.
  const int threads = opts_.max_streams + 16;
  srv_->new_task_queue = [threads] { return new httplib::ThreadPool(static_cast<size_t>(threads)); };
  srv_->set_keep_alive_timeout(30);
  // Small responses (/current, events) go out at once: Nagle plus delayed ACKs cost 40 ms a keep-alive GET.
  srv_->set_tcp_nodelay(true);
  Routes();
}

HttpServer::~HttpServer() {
  Stop();
}

std::string HttpServer::url() const {
  std::string host =
      opts_.listen.host.find(':') != std::string::npos ? "[" + opts_.listen.host + "]" : opts_.listen.host;
  return std::string(opts_.cert_file.empty() ? "http" : "https") + "://" + host + ":" +
         std::to_string(port_) + "/";
}

bool HttpServer::running() const {
  return srv_ && srv_->is_running();
}

void HttpServer::Start() {
  if (opts_.listen.port == 0)
    port_ = srv_->bind_to_any_port(opts_.listen.host.c_str());
  else
    port_ = srv_->bind_to_port(opts_.listen.host.c_str(), opts_.listen.port) ? opts_.listen.port : -1;
  if (port_ <= 0)
    throw Error(Errc::kUnavailable, "cannot listen on " + opts_.listen.host + ":" +
                                        std::to_string(opts_.listen.port) +
                                        " (in use, or not an address of this host): set CELL_HTTP");
  thread_ = std::thread([this] { srv_->listen_after_bind(); });
  while (!srv_->is_running() && thread_.joinable()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

void HttpServer::Stop() {
  stopping_ = true;
  if (srv_) srv_->stop();
  if (thread_.joinable()) thread_.join();
}

// The program a path route draws: ?program=, else the one the station reports (the last one stays).
static std::string ProgramOf(const nlohmann::json& snapshot, const std::string& station,
                             const httplib::Request& req) {
  if (req.has_param("program")) return req.get_param_value("program");
  for (const auto& st : snapshot.value("stations", nlohmann::json::array()))
    if (st.value("id", std::string()) == station && st.contains("program") && st["program"].is_string())
      return st["program"].get<std::string>();
  return "";
}

void HttpServer::PathRoutes() {
  auto answer = [this](const httplib::Request& req, bool svg, httplib::Response& res) {
    const std::string station = req.matches[1];
    std::pair<int, nlohmann::json> a{404, {{"error", "no toolpaths here"}}};
    if (paths_) a = paths_(station, ProgramOf(view_.Snapshot(), station, req));
    res.status = a.first;
    res.set_header("Cache-Control", "no-store");
    if (svg && a.first == 200)
      res.set_content(a.second.value("svg", std::string()), "image/svg+xml; charset=utf-8");
    else if (svg)
      res.set_content(a.second.value("error", std::string()) + "\n", "text/plain; charset=utf-8");
    else
      res.set_content(a.second.dump(), "application/json");
  };
  srv_->Get(R"(/api/station/([A-Za-z0-9_-]+)/path)",
            [answer](const httplib::Request& req, httplib::Response& res) { answer(req, false, res); });
  srv_->Get(R"(/station/([A-Za-z0-9_-]+)/path\.svg)",
            [answer](const httplib::Request& req, httplib::Response& res) { answer(req, true, res); });
}

void HttpServer::Routes() {
  auto& s = *srv_;
  PathRoutes();
  s.Get("/", [this](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(RenderPage(view_.Snapshot()), "text/html; charset=utf-8");
  });
  s.Get("/static/chart.js", [this](const httplib::Request&, httplib::Response& res) {
    if (chartjs_.empty()) {
      res.status = 404;
      res.set_content("Chart.js not installed (Debian package libjs-chart.js)\n", "text/plain");
      return;
    }
    res.set_header("Cache-Control", "max-age=3600");
    res.set_content(chartjs_, "application/javascript");
  });
  s.Get("/api/state", [this](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(view_.Snapshot().dump(), "application/json");
  });
  s.Get("/api/plan", [this](const httplib::Request&, httplib::Response& res) {
    PlanFetch plan;
    if (plan_) {
      plan = plan_();
    } else {
      plan.error = "this dashboard asks no scheduler for a plan";
    }
    std::vector<std::string> stations;
    for (const auto& st : view_.model().stations()) stations.push_back(st.id);
    res.set_header("Cache-Control", "no-store");
    res.set_content(GanttJson(stations, plan, view_.Ran(), records::NowNs()).dump(), "application/json");
  });
  s.Get(R"(/api/job/(\d+))", [this](const httplib::Request& req, httplib::Response& res) {
    auto id = Int(req.matches[1]);
    auto j = id && *id < (1ll << 31) ? view_.JobDetail(static_cast<int>(*id)) : std::nullopt;
    if (!j) {
      res.status = 404;
      res.set_content(nlohmann::json({{"error", "no job " + std::string(req.matches[1])}}).dump(),
                      "application/json");
      return;
    }
    res.set_content(j->dump(), "application/json");
  });
  s.Get("/api/events", [this](const httplib::Request& req, httplib::Response& res) {
    if (streams_.fetch_add(1) >= opts_.max_streams) {
      streams_.fetch_sub(1);
      res.status = 503;
      res.set_content("too many live clients\n", "text/plain");
      return;
    }
    std::uint64_t after = view_.LastEvent();
    std::string from = req.has_header("Last-Event-ID") ? req.get_header_value("Last-Event-ID")
                                                       : req.get_param_value("after");
    if (auto v = Int(from); v && *v >= 0) after = static_cast<std::uint64_t>(*v);
    // An id this process never gave out: the browser saw an earlier dashboard process; it needs the state.
    const bool resync = after > view_.LastEvent();
    res.set_header("Cache-Control", "no-store");
    res.set_header("X-Accel-Buffering", "no");
    auto last = std::make_shared<std::uint64_t>(after);
    auto idle = std::make_shared<int>(0);
    res.set_chunked_content_provider(
        "text/event-stream",
        [this, last, idle, resync](size_t offset, httplib::DataSink& sink) {
          if (stopping_) return false;
          std::string out;
          if (offset == 0) out = "retry: 1000\n\n";  // the browser reconnects after 1 s
          if ((offset == 0 && resync) || view_.WaitEvent(*last, std::chrono::milliseconds(500))) {
            std::optional<std::vector<CellView::Event>> evs;
            if (offset != 0 || !resync) evs = view_.EventsAfter(*last, 512);
            if (!evs) {
              // This browser fell behind the event log: it gets the whole state again.
              auto snap = view_.Snapshot();
              *last = snap["event"].get<std::uint64_t>();
              out += "event: resync\nid: " + std::to_string(*last) + "\ndata: " + snap.dump() + "\n\n";
            } else {
              for (auto& e : *evs) {
                out += "id: " + std::to_string(e.id) + "\ndata: " + e.data + "\n\n";
                *last = e.id;
              }
            }
            *idle = 0;
          } else if (++*idle >= 20) {  // 10 s of silence: a comment keeps proxies and the browser patient
            out += ": idle\n\n";
            *idle = 0;
          }
          if (!out.empty() && !sink.write(out.data(), out.size())) return false;
          return sink.is_writable();
        },
        [this](bool) { streams_.fetch_sub(1); });
  });

  // ---- MTConnect ----
  auto device = [this](const std::string& name) { return view_.model().StationIndex(name); };
  auto xml = [](httplib::Response& res, int status, std::string body) {
    res.status = status;
    res.set_header("Cache-Control", "no-store");
    res.set_content(std::move(body), kXml);
  };
  auto probe = [this, xml](int dev, httplib::Response& res) { xml(res, 200, view_.Probe(dev)); };
  auto current = [this, xml](const httplib::Request& req, int dev, httplib::Response& res) {
    if (req.has_param("at"))
      return xml(res, 400, view_.ErrorDoc("UNSUPPORTED", "'at' is not supported: use /sample?from=&count="));
    xml(res, 200, view_.Current(dev));
  };
  auto sample = [this, xml](const httplib::Request& req, int dev, httplib::Response& res) {
    std::optional<std::int64_t> from;
    std::int64_t count = 100;
    if (req.has_param("from")) {
      from = Int(req.get_param_value("from"));
      if (!from)
        return xml(res, 400,
                   view_.ErrorDoc("INVALID_REQUEST",
                                  "'from' must be an integer, got '" + req.get_param_value("from") + "'"));
    }
    if (req.has_param("count")) {
      auto c = Int(req.get_param_value("count"));
      if (!c)
        return xml(res, 400,
                   view_.ErrorDoc("INVALID_REQUEST",
                                  "'count' must be an integer, got '" + req.get_param_value("count") + "'"));
      count = *c;
    }
    auto r = view_.Sample(from, count, dev);
    xml(res, r.status, std::move(r.body));
  };
  s.Get("/probe", [probe](const httplib::Request&, httplib::Response& res) { probe(-1, res); });
  s.Get("/current",
        [current](const httplib::Request& req, httplib::Response& res) { current(req, -1, res); });
  s.Get("/sample", [sample](const httplib::Request& req, httplib::Response& res) { sample(req, -1, res); });
  s.Get("/assets",
        [this, xml](const httplib::Request&, httplib::Response& res) { xml(res, 200, view_.AssetsDoc("")); });
  s.Get(R"(/asset/([^/]+))", [this, xml](const httplib::Request& req, httplib::Response& res) {
    std::string id = req.matches[1];
    xml(res, view_.HasAsset(id) ? 200 : 404, view_.AssetsDoc(id));
  });
  s.Get(R"(/([^/]+)/(probe|current|sample))", [this, xml, device, probe, current, sample](
                                                  const httplib::Request& req, httplib::Response& res) {
    int dev = device(req.matches[1]);
    if (dev < 0)
      return xml(res, 404, view_.ErrorDoc("NO_DEVICE", "no device '" + std::string(req.matches[1]) + "'"));
    std::string what = req.matches[2];
    if (what == "probe") return probe(dev, res);
    if (what == "current") return current(req, dev, res);
    sample(req, dev, res);
  });
  // Anything else is an MTConnect error document (browsers get it too, which is honest).
  s.set_error_handler([this](const httplib::Request& req, httplib::Response& res) {
    if (res.status != 404 || !res.body.empty()) return;
    res.set_content(view_.ErrorDoc("INVALID_URI", "no such request: " + req.path), kXml);
  });
}

}  // namespace cell::dashboard
