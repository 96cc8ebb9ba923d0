// The dashboard's figures (./cell bench dashboard, docs/dashboard.md "Benchmark"). It starts a real
// cell-dashboard on its own DDS domain, with a cell of four KT stations (KT01-KT04), and plays those
// stations itself on the bus (heartbeats, status, tool tables, axis telemetry), so the figures are the
// dashboard's alone:
//   (a) a station state change written on DDS -> the change in a headless Chromium's DOM (a
//       MutationObserver's timestamp), median and p99, against the 100 ms target;
//   (b) GET /current (4 stations) against GET of a static file from the same server, same run;
//   (c) 50 live clients (server-sent events) held for a minute while the state changes 10 times a
//       second: every client must receive every change, in order (no gap, no resync).
// Env: CELL_BENCH_CHANGES (a, default 200), CELL_BENCH_GETS (b, default 500), CELL_BENCH_CLIENTS (c,
// default 50), CELL_BENCH_SECONDS (c, default 60).
#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <thread>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/health/health.h"
#include "cell/idl/motion.h"
#include "cell/idl/station.h"
#include "cell/testing/process.h"
#include "cell/testing/webdriver.h"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

int Env(const char* name, int def) {
  const char* v = std::getenv(name);
  return v && *v ? std::atoi(v) : def;
}

double Pct(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(p * static_cast<double>(v.size() - 1) + 0.5)];
}

double WallMs() {
  return static_cast<double>(std::chrono::duration_cast<std::chrono::microseconds>(
                                 std::chrono::system_clock::now().time_since_epoch())
                                 .count()) /
         1000.0;
}

// The four stations, as their interpreters and servos would publish them.
class FakeStations {
 public:
  explicit FakeStations(cell::bus::Participant& p)
      : status_(p, cell::bus::topics::kStationStatus, cell::bus::QosKind::kState),
        tools_(p, cell::bus::topics::kToolTable, cell::bus::QosKind::kState),
        axes_(p, cell::bus::topics::kAxisState, cell::bus::QosKind::kTelemetry) {
    for (auto& id : kIds)
      beats_.push_back(std::make_unique<cell::health::Announcer>(p, "cell-interpreter", id));
    for (auto& b : beats_) b->Set(cell::SERVICE_READY);
    for (auto& id : kIds) {
      cell::ToolTable t;
      t.station(id);
      t.revision(1);
      for (int i = 1; i <= 20; ++i) {
        cell::ToolEntry e;
        e.tool(std::to_string(1000 + i));
        e.socket(i);
        e.length(100 + i);
        e.diameter(i);
        e.life_left_min(120);
        t.tools().push_back(e);
      }
      tools_.Write(t);
      Status(id, 1);
    }
  }
  void Status(const std::string& id, int line) {
    cell::StationStatus s;
    s.station(id);
    s.dialect("ktapl");
    s.execution(cell::EXECUTION_ACTIVE);
    s.condition(cell::CONDITION_NORMAL);
    s.program("BENCH");
    s.line(line);
    s.pallet(1);
    s.tool("1001");
    s.updated_ns(cell::health::WallNs());
    status_.Write(s);
  }
  void Axes(double t) {
    for (size_t i = 0; i < kIds.size(); ++i) {
      cell::AxisState a;
      a.station(kIds[i]);
      a.actual()[0] = 100 * std::sin(t + static_cast<double>(i));
      a.actual()[1] = 50 * std::cos(t);
      a.actual()[2] = 10 * t;
      a.actual()[4] = 90;
      a.spindle_rpm(2400);
      a.path_feed(1200);
      a.wall_ns(cell::health::WallNs());
      axes_.Write(a);
    }
  }
  bool Matched() const { return status_.Matched() > 0 && tools_.Matched() > 0; }
  static inline const std::vector<std::string> kIds = {"KT01", "KT02", "KT03", "KT04"};

 private:
  cell::bus::Writer<cell::StationStatus> status_;
  cell::bus::Writer<cell::ToolTable> tools_;
  cell::bus::Writer<cell::AxisState> axes_;
  std::vector<std::unique_ptr<cell::health::Announcer>> beats_;
};

// (a) DDS write -> DOM change in Chromium.
void DomLatency(FakeStations& st, const std::string& url) {
  const int n = Env("CELL_BENCH_CHANGES", 200);
  cell::testing::Browser b(1400, 1000);
  b.Navigate(url);
  if (!b.WaitTrue(
          "const c = document.querySelector('#station-KT01'); return c && c.dataset.execution === 'ACTIVE';",
          20s)) {
    std::printf("(a) the page never showed KT01 ACTIVE\n");
    std::exit(1);
  }
  b.Exec(
      "window.__t = {}; const el = document.querySelector('#station-KT01 .f-line');"
      "new MutationObserver(() => { window.__t[el.textContent] = performance.timeOrigin + performance.now(); "
      "})"
      ".observe(el, {childList: true, characterData: true, subtree: true}); return true;");
  std::vector<double> sent(static_cast<size_t>(n) + 1000, 0);
  for (int i = 1000; i < 1000 + n; ++i) {
    sent[static_cast<size_t>(i - 1000)] = WallMs();
    st.Status("KT01", i);
    std::this_thread::sleep_for(50ms);
  }
  std::this_thread::sleep_for(1s);
  auto got = b.Exec("return window.__t;");
  std::vector<double> lat;
  int missing = 0;
  for (int i = 1000; i < 1000 + n; ++i) {
    auto k = std::to_string(i);
    if (!got.contains(k)) {
      ++missing;
      continue;
    }
    lat.push_back(got[k].get<double>() - sent[static_cast<size_t>(i - 1000)]);
  }
  std::printf(
      "(a) DDS station change -> browser DOM: %d changes, median %.1f ms, p99 %.1f ms, max %.1f ms "
      "(target p50 < 100 ms: %s); %d never seen\n",
      n, Pct(lat, 0.5), Pct(lat, 0.99), Pct(lat, 1.0), Pct(lat, 0.5) < 100 ? "met" : "MISSED", missing);
}

// (b) /current against a static file.
void CurrentVsStatic(const std::string& host, int port) {
  const int n = Env("CELL_BENCH_GETS", 500);
  httplib::Client c(host, port);
  c.set_keep_alive(true);
  auto time = [&](const std::string& path, size_t& bytes) {
    std::vector<double> ms;
    for (int i = 0; i < n + 20; ++i) {
      auto t0 = Clock::now();
      auto r = c.Get(path);
      double d = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      if (!r || r->status != 200) {
        std::printf("(b) GET %s failed\n", path.c_str());
        std::exit(1);
      }
      bytes = r->body.size();
      if (i >= 20) ms.push_back(d);  // after warm-up
    }
    return ms;
  };
  size_t cur_bytes = 0, js_bytes = 0;
  auto js = time("/static/chart.js", js_bytes);
  auto cur = time("/current", cur_bytes);
  std::printf("(b) GET /current (4 stations, %zu bytes): median %.3f ms, p99 %.3f ms\n", cur_bytes,
              Pct(cur, 0.5), Pct(cur, 0.99));
  std::printf("    GET /static/chart.js (static file, %zu bytes, baseline): median %.3f ms, p99 %.3f ms\n",
              js_bytes, Pct(js, 0.5), Pct(js, 0.99));
  std::printf("    ratio of medians /current : static = %.2f\n", Pct(cur, 0.5) / Pct(js, 0.5));
}

// (c) N live clients for a while; every station change must reach every client once, in order.
void LiveClients(FakeStations& st, const std::string& host, int port) {
  const int clients = Env("CELL_BENCH_CLIENTS", 50), seconds = Env("CELL_BENCH_SECONDS", 60);
  struct Client {
    std::unique_ptr<httplib::Client> http;
    std::thread t;
    std::string buf;
    std::uint64_t last_id = 0;
    long gaps = 0, resyncs = 0, events = 0;
    std::vector<int> lines;  // KT02's line numbers in arrival order
    std::vector<double> lat;
    std::atomic<bool> open{false};
  };
  std::vector<std::unique_ptr<Client>> cs;
  std::map<int, double> sent;
  std::mutex sent_mu;
  for (int i = 0; i < clients; ++i) {
    auto c = std::make_unique<Client>();
    c->http = std::make_unique<httplib::Client>(host, port);
    c->http->set_read_timeout(30, 0);
    Client* me = c.get();
    c->t = std::thread([me, &sent, &sent_mu] {
      me->http->Get("/api/events", [&](const char* d, size_t n) {
        me->open = true;
        me->buf.append(d, n);
        for (size_t end; (end = me->buf.find("\n\n")) != std::string::npos; me->buf.erase(0, end + 2)) {
          std::string ev = me->buf.substr(0, end);
          if (ev.rfind("event: resync", 0) == 0) ++me->resyncs;
          auto idp = ev.find("id: ");
          if (idp == std::string::npos) continue;
          std::uint64_t id = std::stoull(ev.substr(idp + 4));
          if (me->last_id != 0 && id != me->last_id + 1) ++me->gaps;
          me->last_id = id;
          ++me->events;
          // KT02's card: its "line" (the first after its id in the station's JSON).
          size_t kt02 = ev.find("\"id\":\"KT02\"");
          size_t lp = kt02 == std::string::npos ? kt02 : ev.find("\"line\":", kt02);
          if (ev.find("\"type\":\"station\"") != std::string::npos && lp != std::string::npos &&
              std::isdigit(static_cast<unsigned char>(ev[lp + 7]))) {
            int line = std::atoi(ev.c_str() + lp + 7);
            me->lines.push_back(line);
            std::lock_guard lk(sent_mu);
            if (sent.count(line)) me->lat.push_back(WallMs() - sent[line]);
          }
        }
        return true;
      });
    });
    cs.push_back(std::move(c));
  }
  auto all_open = [&] {
    for (auto& c : cs)
      if (!c->open) return false;
    return true;
  };
  for (auto t0 = Clock::now(); !all_open() && Clock::now() - t0 < 20s;) std::this_thread::sleep_for(50ms);
  const int changes = seconds * 10;
  auto t0 = Clock::now();
  for (int i = 0; i < changes; ++i) {
    {
      std::lock_guard lk(sent_mu);
      sent[100000 + i] = WallMs();
    }
    st.Status("KT02", 100000 + i);
    st.Axes(static_cast<double>(i) / 10);
    std::this_thread::sleep_until(t0 + std::chrono::milliseconds(100 * (i + 1)));
  }
  std::this_thread::sleep_for(2s);
  long gaps = 0, resyncs = 0, incomplete = 0, events = 0;
  std::vector<double> lat;
  for (auto& c : cs) {
    c->http->stop();
    c->t.join();
    gaps += c->gaps;
    resyncs += c->resyncs;
    events += c->events;
    std::vector<int> want(static_cast<size_t>(changes));
    std::iota(want.begin(), want.end(), 100000);
    std::vector<int> got;
    for (int l : c->lines)
      if (l >= 100000) got.push_back(l);
    if (got != want) ++incomplete;
    lat.insert(lat.end(), c->lat.begin(), c->lat.end());
  }
  std::printf(
      "(c) %d live clients for %d s, %d station changes (10/s) plus axis events: %ld events delivered, "
      "%ld gaps, %ld resyncs, %ld clients missing a change -> %s\n",
      clients, seconds, changes, events, gaps, resyncs, incomplete,
      gaps == 0 && resyncs == 0 && incomplete == 0 ? "no dropped updates" : "UPDATES DROPPED");
  std::printf("    DDS change -> client receipt over all clients: median %.1f ms, p99 %.1f ms\n",
              Pct(lat, 0.5), Pct(lat, 0.99));
}

}  // namespace

int main() {
  const fs::path work = cell::testing::MakeTempDir("cell-dashboard-bench-");
  fs::create_directories(work / "config/stations");
  const fs::path src =
      cell::testing::SourceDir().empty() ? fs::path(CELL_SOURCE_DIR) : fs::path(cell::testing::SourceDir());
  for (const auto& id : FakeStations::kIds)
    fs::copy_file(src / "deploy/stations" / (id + ".toml"), work / "config/stations" / (id + ".toml"));
  const std::string bin = std::getenv("CELL_BIN_DIR") ? std::getenv("CELL_BIN_DIR") : CELL_BIN_DIR;
  cell::testing::Process dash({bin + "/cell-dashboard"},
                              {{"CELL_CONFIG_DIR", (work / "config").string()},
                               {"CELL_DATA_DIR", (work / "data").string()},
                               {"CELL_HTTP", "127.0.0.1:0"}},
                              (work / "dashboard.log").string(), (work / "dashboard.log").string());
  std::string url;
  for (auto t0 = Clock::now(); url.empty() && Clock::now() - t0 < 20s;) {
    std::ifstream in(work / "data/dashboard.url");
    std::getline(in, url);
    if (url.empty()) std::this_thread::sleep_for(50ms);
  }
  if (url.empty()) {
    std::printf("cell-dashboard did not start: %s\n",
                cell::testing::ReadFile((work / "dashboard.log").string()).c_str());
    return 1;
  }
  const int port = std::stoi(url.substr(url.rfind(':') + 1));
  cell::bus::Participant p("dashboard-bench");
  FakeStations st(p);
  cell::bus::WaitUntil([&] { return st.Matched(); }, 10s);
  std::printf("cell-dashboard at %s, 4 stations played on DDS domain %d\n", url.c_str(), p.domain());
  DomLatency(st, url);
  CurrentVsStatic("127.0.0.1", port);
  LiveClients(st, "127.0.0.1", port);
  dash.Signal(SIGTERM);
  dash.Wait(10s);
  std::error_code ec;
  fs::remove_all(work, ec);
  return 0;
}
