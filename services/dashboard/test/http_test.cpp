// Every HTTP endpoint of the dashboard, through a real server on a free loopback port and cpp-httplib's
// client: the page, its state and event stream (resume, resync), and the MTConnect agent interface with
// its documents validated against the 2.4 schemas; /sample continuity over a long run.
#include <gtest/gtest.h>
#include <httplib.h>

#include <atomic>
#include <cctype>
#include <filesystem>
#include <set>
#include <thread>

#include "cell/dashboard/server.h"
#include "cell/error/error.h"
#include "test_stations.h"

namespace cell::dashboard {
namespace {

using testing::Status;
using testing::TwoStations;
using testing::Validate;

// Every number that follows `prefix` in `text`, in order. (No std::regex: GCC 12 warns inside it under the
// sanitizer build.)
std::vector<std::uint64_t> NumbersAfter(const std::string& text, const std::string& prefix) {
  std::vector<std::uint64_t> out;
  for (size_t at = text.find(prefix); at != std::string::npos; at = text.find(prefix, at + 1)) {
    size_t p = at + prefix.size(), e = p;
    while (e < text.size() && std::isdigit(static_cast<unsigned char>(text[e]))) ++e;
    if (e > p) out.push_back(std::stoull(text.substr(p, e - p)));
  }
  return out;
}

// A server-sent event stream read on a thread.
class Sse {
 public:
  Sse(int port, const std::string& path, const std::string& last_event_id = "") : cli_("127.0.0.1", port) {
    cli_.set_read_timeout(30, 0);
    httplib::Headers h;
    if (!last_event_id.empty()) h.emplace("Last-Event-ID", last_event_id);
    t_ = std::thread([this, path, h] {
      auto res = cli_.Get(path, h, [this](const char* d, size_t n) {
        std::lock_guard lk(mu_);
        text_.append(d, n);
        cv_.notify_all();
        return true;
      });
      std::lock_guard lk(mu_);
      status_ = res ? res->status : -1;
      done_ = true;
      cv_.notify_all();
    });
  }
  ~Sse() {
    cli_.stop();
    t_.join();
  }
  // Waits until the text read so far satisfies pred.
  bool WaitFor(const std::function<bool(const std::string&)>& pred, int ms = 5000) {
    std::unique_lock lk(mu_);
    return cv_.wait_for(lk, std::chrono::milliseconds(ms), [&] { return pred(text_) || done_; }) &&
           pred(text_);
  }
  std::string text() {
    std::lock_guard lk(mu_);
    return text_;
  }
  int status() {
    std::unique_lock lk(mu_);
    cv_.wait_for(lk, std::chrono::seconds(5), [&] { return done_; });
    return status_;
  }
  // "data:" payloads in order, with their ids.
  std::vector<std::pair<std::uint64_t, nlohmann::json>> Events() {
    std::vector<std::pair<std::uint64_t, nlohmann::json>> out;
    std::string t = text();
    for (size_t at = t.find("id: "); at != std::string::npos; at = t.find("id: ", at + 1)) {
      if (at > 0 && t[at - 1] != '\n') continue;
      size_t nl = t.find('\n', at);
      if (nl == std::string::npos || t.compare(nl + 1, 6, "data: ") != 0) continue;
      size_t end = t.find("\n\n", nl);
      if (end == std::string::npos) break;
      out.emplace_back(std::stoull(t.substr(at + 4, nl - at - 4)),
                       nlohmann::json::parse(t.substr(nl + 7, end - nl - 7)));
    }
    return out;
  }

 private:
  httplib::Client cli_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::string text_;
  int status_ = 0;
  bool done_ = false;
  std::thread t_;
};

class HttpTest : public ::testing::Test {
 protected:
  void Start(ViewOptions vo = {}, int max_streams = 200) {
    view_ = std::make_unique<CellView>(TwoStations(), vo);
    ServerOptions o;
    o.listen = {"127.0.0.1", 0};
    o.max_streams = max_streams;
    srv_ = std::make_unique<HttpServer>(*view_, o);
    srv_->Start();
    ASSERT_GT(srv_->port(), 0);
  }
  void SetUp() override { Start(); }
  httplib::Result Get(const std::string& path) {
    httplib::Client c("127.0.0.1", srv_->port());
    return c.Get(path);
  }
  // GET an MTConnect document: its status, content type and schema validity.
  std::string Xml(const std::string& path, int status, const char* schema) {
    auto r = Get(path);
    EXPECT_TRUE(r) << path;
    if (!r) return "";
    EXPECT_EQ(r->status, status) << path << "\n" << r->body;
    EXPECT_EQ(r->get_header_value("Content-Type"), "application/xml") << path;
    EXPECT_EQ(Validate(r->body, schema), "") << path << "\n" << r->body;
    return r->body;
  }
  std::unique_ptr<CellView> view_;
  std::unique_ptr<HttpServer> srv_;
};

TEST_F(HttpTest, OneGetRendersTheCurrentStateWithNothingFromTheInternet) {
  view_->Online("KT01", true);
  view_->Status(Status("KT01", "ACTIVE", "PUMP341", 12, 3));
  auto r = Get("/");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(r->get_header_value("Content-Type"), "text/html; charset=utf-8");
  const std::string& page = r->body;
  auto a = page.find("<script id=\"state\" type=\"application/json\">");
  ASSERT_NE(a, std::string::npos);
  a = page.find('>', a) + 1;
  auto state = nlohmann::json::parse(page.substr(a, page.find("</script>", a) - a));
  EXPECT_EQ(state["stations"][0]["execution"], "ACTIVE");
  EXPECT_EQ(state["stations"][0]["program"], "PUMP341");
  EXPECT_EQ(page.find("/*APP*/"), std::string::npos);  // the script and style are inlined
  EXPECT_NE(page.find("new EventSource("), std::string::npos);
  for (const char* attr : {"src=\"", "href=\""})
    for (size_t at = page.find(attr); at != std::string::npos; at = page.find(attr, at + 1)) {
      std::string target = page.substr(at + std::string(attr).size(), 8);
      EXPECT_EQ(target.rfind("/", 0), 0u) << "an asset not from this server: " << target;
      EXPECT_NE(target.rfind("//", 0), 0u) << "an asset not from this server: " << target;
    }
  auto js = Get("/static/chart.js");
  ASSERT_TRUE(js);
  EXPECT_EQ(js->status, 200) << "Debian's libjs-chart.js must be installed (deploy/install-deps)";
  EXPECT_NE(js->body.find("Chart"), std::string::npos);
}

TEST_F(HttpTest, StateAndJobDetailAsJson) {
  JobIn j;
  j.id = 5;
  j.state = "WAITING";
  j.pallet = 2;
  j.decisions = {DecisionIn{
      1, 0, 1, "operate", "", "no eligible station", 0, {{"KT01", true, false, false, 0, {"7777"}}}}};
  view_->Job(j);
  auto s = Get("/api/state");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->get_header_value("Content-Type"), "application/json");
  auto state = nlohmann::json::parse(s->body);
  EXPECT_EQ(state["jobs"][0]["id"], 5);
  EXPECT_FALSE(state["jobs"][0].contains("decisions"));
  auto d = Get("/api/job/5");
  ASSERT_TRUE(d);
  EXPECT_EQ(nlohmann::json::parse(d->body)["decisions"][0]["considered"][0]["missing_tools"],
            nlohmann::json::array({"7777"}));
  auto none = Get("/api/job/6");
  ASSERT_TRUE(none);
  EXPECT_EQ(none->status, 404);
}

// The toolpath routes hand the station and the program to the path source (cell-dashboard's Paths, which
// draws from the program store): the program from ?program=, else the one the station reports; the JSON as
// the source gives it, the SVG alone as image/svg+xml, and the source's error with its status.
TEST_F(HttpTest, ToolpathRoutesAskThePathSourceForTheStationsProgram) {
  srv_->Stop();
  ServerOptions o;
  o.listen = {"127.0.0.1", 0};
  srv_ = std::make_unique<HttpServer>(*view_, o);
  std::vector<std::pair<std::string, std::string>> asked;
  srv_->SetPathSource([&asked](const std::string& station, const std::string& program) {
    asked.emplace_back(station, program);
    if (program == "GONE") return std::make_pair(404, nlohmann::json{{"error", "no program 'GONE'"}});
    return std::make_pair(200, nlohmann::json{{"program", program}, {"svg", "<svg/>"}, {"moves", {1, 2}}});
  });
  srv_->Start();
  view_->Online("KT01", true);
  view_->Status(Status("KT01", "ACTIVE", "PUMP341", 12, 3));
  auto j = Get("/api/station/KT01/path");
  ASSERT_TRUE(j);
  EXPECT_EQ(j->status, 200);
  EXPECT_EQ(j->get_header_value("Content-Type"), "application/json");
  EXPECT_EQ(nlohmann::json::parse(j->body)["program"], "PUMP341");
  auto svg = Get("/station/KT01/path.svg?program=OTHER");
  ASSERT_TRUE(svg);
  EXPECT_EQ(svg->status, 200);
  EXPECT_EQ(svg->get_header_value("Content-Type"), "image/svg+xml; charset=utf-8");
  EXPECT_EQ(svg->body, "<svg/>");
  auto gone = Get("/station/KT01/path.svg?program=GONE");
  ASSERT_TRUE(gone);
  EXPECT_EQ(gone->status, 404);
  EXPECT_EQ(gone->body, "no program 'GONE'\n");
  auto idle = Get("/api/station/KT02/path");  // KT02 has run nothing: the source says why
  ASSERT_TRUE(idle);
  const std::vector<std::pair<std::string, std::string>> want = {
      {"KT01", "PUMP341"}, {"KT01", "OTHER"}, {"KT01", "GONE"}, {"KT02", ""}};
  EXPECT_EQ(asked, want);
}

TEST_F(HttpTest, EventStreamPushesChangesAndResumesAfterLastEventId) {
  const auto start = view_->LastEvent();
  std::uint64_t seen = 0;
  {
    Sse sse(srv_->port(), "/api/events?after=" + std::to_string(start));
    view_->Online("KT01", true);
    view_->Status(Status("KT01", "ACTIVE", "P", 1));
    ASSERT_TRUE(sse.WaitFor([](const std::string& t) { return t.find("\"ACTIVE\"") != std::string::npos; }))
        << sse.text();
    auto evs = sse.Events();
    ASSERT_EQ(evs.size(), 2u);
    EXPECT_EQ(evs[0].first, start + 1);
    EXPECT_EQ(evs[1].second["station"]["execution"], "ACTIVE");
    seen = evs.back().first;
  }
  // Lost connection: two changes meanwhile; the browser comes back with Last-Event-ID and misses none.
  view_->Status(Status("KT01", "FEED_HOLD", "P", 1));
  view_->Status(Status("KT01", "ACTIVE", "P", 2));
  Sse again(srv_->port(), "/api/events", std::to_string(seen));
  ASSERT_TRUE(again.WaitFor([](const std::string& t) { return t.find("\"line\":2") != std::string::npos; }));
  auto evs = again.Events();
  ASSERT_EQ(evs.size(), 2u);
  EXPECT_EQ(evs[0].first, seen + 1);
  EXPECT_EQ(evs[0].second["station"]["execution"], "FEED_HOLD");
  EXPECT_EQ(evs[1].first, seen + 2);
}

TEST_F(HttpTest, EventStreamResyncsABrowserThatIsTooFarBehindOrFromAnotherProcess) {
  ViewOptions vo;
  vo.event_log = 4;
  Start(vo);
  view_->Online("KT01", true);
  for (int i = 1; i <= 10; ++i) view_->Status(Status("KT01", "ACTIVE", "P", i));
  {
    Sse old(srv_->port(), "/api/events", "1");  // its events left the log
    ASSERT_TRUE(
        old.WaitFor([](const std::string& t) { return t.find("event: resync") != std::string::npos; }));
    EXPECT_NE(old.text().find("\"line\":10"), std::string::npos);
  }
  Sse other(srv_->port(), "/api/events", "999999");  // an id this process never gave out
  ASSERT_TRUE(
      other.WaitFor([](const std::string& t) { return t.find("event: resync") != std::string::npos; }));
}

TEST_F(HttpTest, LiveClientsBeyondTheLimitAreRefused) {
  Start({}, 1);
  Sse first(srv_->port(), "/api/events");
  ASSERT_TRUE(first.WaitFor([](const std::string& t) { return t.find("retry:") != std::string::npos; }));
  Sse second(srv_->port(), "/api/events");
  EXPECT_EQ(second.status(), 503);
}

TEST_F(HttpTest, MtconnectEndpointsAnswerWithValidDocuments) {
  view_->Online("KT01", true);
  view_->Status(Status("KT01", "ACTIVE", "PUMP341", 12, 3));
  view_->Tools("KT01", testing::Tools({{"1001", 1, 152.4, 25.4, 240, false, false}}));
  EXPECT_NE(Xml("/probe", 200, "MTConnectDevices_2.4_1.0.xsd").find("uuid=\"OK01\""), std::string::npos);
  EXPECT_EQ(Xml("/OK01/probe", 200, "MTConnectDevices_2.4_1.0.xsd").find("KT01"), std::string::npos);
  EXPECT_NE(Xml("/current", 200, "MTConnectStreams_2.4_1.0.xsd").find(">ACTIVE</Execution>"),
            std::string::npos);
  Xml("/KT01/current", 200, "MTConnectStreams_2.4_1.0.xsd");
  Xml("/sample", 200, "MTConnectStreams_2.4_1.0.xsd");
  Xml("/sample?from=1&count=10", 200, "MTConnectStreams_2.4_1.0.xsd");
  Xml("/KT01/sample?count=5", 200, "MTConnectStreams_2.4_1.0.xsd");
  EXPECT_NE(Xml("/assets", 200, "MTConnectAssets_2.4_1.0.xsd").find("assetId=\"KT01.T1001\""),
            std::string::npos);
  Xml("/asset/KT01.T1001", 200, "MTConnectAssets_2.4_1.0.xsd");
  EXPECT_NE(Xml("/asset/KT01.T9", 404, "MTConnectError_2.4_1.0.xsd").find("ASSET_NOT_FOUND"),
            std::string::npos);
  EXPECT_NE(Xml("/KT09/current", 404, "MTConnectError_2.4_1.0.xsd").find("NO_DEVICE"), std::string::npos);
  EXPECT_NE(Xml("/sample?from=abc", 400, "MTConnectError_2.4_1.0.xsd").find("INVALID_REQUEST"),
            std::string::npos);
  EXPECT_NE(Xml("/sample?count=x", 400, "MTConnectError_2.4_1.0.xsd").find("INVALID_REQUEST"),
            std::string::npos);
  EXPECT_NE(Xml("/sample?from=0", 404, "MTConnectError_2.4_1.0.xsd").find("OUT_OF_RANGE"), std::string::npos);
  EXPECT_NE(Xml("/sample?from=1&count=0", 404, "MTConnectError_2.4_1.0.xsd").find("OUT_OF_RANGE"),
            std::string::npos);
  EXPECT_NE(Xml("/current?at=3", 400, "MTConnectError_2.4_1.0.xsd").find("UNSUPPORTED"), std::string::npos);
  EXPECT_NE(Xml("/no/such/thing", 404, "MTConnectError_2.4_1.0.xsd").find("INVALID_URI"), std::string::npos);
}

// Reads /sample from nextSequence to nextSequence while a writer produces 60,000 observations into a
// buffer of 4,096 (wrapping it 15 times): every sequence number arrives exactly once, in order; then
// `from` before the buffer's start is OUT_OF_RANGE.
TEST_F(HttpTest, SampleIsContinuousAcrossALongRunAndOutOfRangePastTheBuffer) {
  ViewOptions vo;
  vo.buffer_size = 4096;
  Start(vo);
  view_->Online("KT01", true);
  const std::uint64_t begin = view_->NextSequence();
  constexpr int kChanges = 60000;
  std::atomic<std::uint64_t> read_to{begin};
  std::atomic<bool> failed{false};
  std::thread writer([&] {
    for (int i = 1; i <= kChanges && !failed; ++i) {
      // Stay within the buffer of the reader (it is a client that keeps up, not one that stalls).
      while (view_->NextSequence() - read_to.load() > 3000 && !failed) std::this_thread::yield();
      view_->Status(Status("KT01", "ACTIVE", "P", i));
    }
  });
  httplib::Client c("127.0.0.1", srv_->port());
  std::uint64_t from = begin, expect = begin;
  int docs = 0;
  while (expect < begin + static_cast<std::uint64_t>(kChanges) + 1) {
    auto r = c.Get("/sample?from=" + std::to_string(from) + "&count=1000");
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << r->body;
    if (docs++ % 50 == 0) {
      EXPECT_EQ(Validate(r->body, "MTConnectStreams_2.4_1.0.xsd"), "");
    }
    std::vector<std::uint64_t> seqs = NumbersAfter(r->body, " sequence=\"");
    std::sort(seqs.begin(), seqs.end());
    for (auto s : seqs) {
      if (s != expect) failed = true;
      ASSERT_EQ(s, expect) << "a gap or a repeat in /sample";
      ++expect;
    }
    auto next = NumbersAfter(r->body, "nextSequence=\"");
    ASSERT_EQ(next.size(), 1u);
    from = next[0];
    ASSERT_EQ(from, expect);
    read_to = from;
  }
  writer.join();
  auto stale = c.Get("/sample?from=" + std::to_string(begin) + "&count=10");
  ASSERT_TRUE(stale);
  EXPECT_EQ(stale->status, 404);
  EXPECT_NE(stale->body.find("OUT_OF_RANGE"), std::string::npos);
  EXPECT_EQ(Validate(stale->body, "MTConnectError_2.4_1.0.xsd"), "");
}

// With a certificate and key the dashboard speaks HTTPS only (what an address beyond loopback requires).
TEST(Tls, ServesHttpsWithTheConfiguredCertificate) {
  const std::string dir = cell::testing::MakeTempDir("cell-dashboard-tls-");
  auto gen = cell::testing::RunCommand({"openssl", "req", "-x509", "-newkey", "ec", "-pkeyopt",
                                        "ec_paramgen_curve:prime256v1", "-nodes", "-keyout", dir + "/key.pem",
                                        "-out", dir + "/cert.pem", "-days", "1", "-subj", "/CN=localhost"});
  ASSERT_EQ(gen.code, 0) << gen.err;
  CellView view(TwoStations());
  ServerOptions o;
  o.listen = {"127.0.0.1", 0};
  o.cert_file = dir + "/cert.pem";
  o.key_file = dir + "/key.pem";
  HttpServer srv(view, o);
  srv.Start();
  EXPECT_EQ(srv.url().rfind("https://127.0.0.1:", 0), 0u) << srv.url();
  httplib::SSLClient tls("127.0.0.1", srv.port());
  tls.enable_server_certificate_verification(false);  // self-signed for the test
  auto r = tls.Get("/probe");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(Validate(r->body, "MTConnectDevices_2.4_1.0.xsd"), "");
  httplib::Client plain("127.0.0.1", srv.port());
  plain.set_read_timeout(2, 0);
  auto p = plain.Get("/probe");
  EXPECT_TRUE(!p || p->status != 200) << "plain HTTP must not be served on the TLS port";
  srv.Stop();
  ServerOptions bad = o;
  bad.cert_file = dir + "/missing.pem";
  EXPECT_THROW(HttpServer(view, bad), cell::Error);
  std::filesystem::remove_all(dir);
}

TEST(Listen, LoopbackByDefaultAndTlsBeyondIt) {
  auto a = ParseListen("127.0.0.1:7878");
  EXPECT_EQ(a.host, "127.0.0.1");
  EXPECT_EQ(a.port, 7878);
  EXPECT_EQ(ParseListen(":0").port, 0);
  EXPECT_EQ(ParseListen("[::1]:80").host, "::1");
  EXPECT_THROW(ParseListen("7878"), cell::Error);
  EXPECT_THROW(ParseListen("host:99999"), cell::Error);
  EXPECT_TRUE(IsLoopback("localhost"));
  EXPECT_FALSE(IsLoopback("0.0.0.0"));
  setenv("CELL_HTTP", "0.0.0.0:7878", 1);
  try {
    ServerOptionsFromEnv();
    ADD_FAILURE() << "an address beyond loopback without TLS must be refused";
  } catch (const cell::Error& e) {
    EXPECT_NE(std::string(e.what()).find("CELL_HTTP_CERT"), std::string::npos) << e.what();
  }
  setenv("CELL_HTTP_CERT", "/x.pem", 1);
  setenv("CELL_HTTP_KEY", "/y.pem", 1);
  EXPECT_EQ(ServerOptionsFromEnv().listen.host, "0.0.0.0");
  unsetenv("CELL_HTTP");
  unsetenv("CELL_HTTP_CERT");
  unsetenv("CELL_HTTP_KEY");
  EXPECT_EQ(ServerOptionsFromEnv().listen.port, 7878);
}

}  // namespace
}  // namespace cell::dashboard
