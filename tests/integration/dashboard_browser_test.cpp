// The dashboard in a real browser (DESIGN §6a, issue 23): a cell comes up with its dashboard, headless
// Chromium opens the page first, then the test operates the cell through cellctl and reads the live DOM
// after each step, without reloading: the station goes ACTIVE, the job reaches COMPLETED, a pallet whose
// tool no station holds waits with a reason naming the tool. The MTConnect documents of the running cell
// validate against the 2.4 schemas, and `cellctl watch --count 1` shows the same state. A screenshot of the
// page is kept as an artefact (tests/artefacts/dashboard.png in the build tree).
#include <gtest/gtest.h>
#include <httplib.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "cell/testing/local_cell.h"
#include "cell/testing/webdriver.h"

namespace cell::testing {
namespace {

using namespace std::chrono_literals;

// A KT-APL program whose cut takes a few seconds of real machine time (300 mm at 3000 mm/min: 6 s, long
// enough to watch the tool marker move on the toolpath). Three motion ops: N20, N30, N40.
std::string Program(const std::string& name, const std::string& utl) {
  return "%\n(NAM," + name + ")\n(UTL," + utl +
         ")\n(UCY,60)\nN10 G71 G90 G01\nN20 X0 Y0 Z100. F0\n"
         "N30 X300. Y40. Z20. F3000.\nN40 G00 X0 Y0 Z100. F0\nN45 (EVT," +
         name + " PART DONE)\nN50 M30\n%\n";
}

// The MTConnect 2.4 schemas the repository carries (tests/schemas/README.md); "" when they are missing.
std::string SchemaDir() {
  const std::string dir = SourceDir() + "/tests/schemas/mtconnect";
  return std::filesystem::exists(dir + "/MTConnectStreams_2.4_1.0.xsd") ? dir : "";
}

class DashboardBrowser : public ::testing::Test {
 protected:
  void SetUp() override {
    auto r = cell_.Up("KT01,KT02", "real");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    url_ = ReadFile(cell_.data_dir() + "/dashboard.url");
    url_ = url_.substr(0, url_.find('\n'));
    ASSERT_NE(url_.find("http://127.0.0.1:"), std::string::npos) << url_;
    EXPECT_NE(r.out.find("dashboard: " + url_), std::string::npos) << r.out;
  }
  void TearDown() override { cell_.Down(); }
  void Put(const std::string& name, const std::string& text) {
    std::string path = cell_.data_dir() + "/" + name + ".apl";
    std::ofstream(path) << text;
    auto r = cell_.Ctl({"program", "put", path});
    ASSERT_EQ(r.code, 0) << r.err;
  }
  std::string Operate(const std::string& route, int pallet) {
    auto r = cell_.Ctl({"route", "operate", route, "--pallet", std::to_string(pallet)});
    EXPECT_EQ(r.code, 0) << r.err;
    return r.out.substr(0, r.out.find('\n'));
  }
  std::string Validate(const std::string& path, const std::string& schema) {
    httplib::Client c("127.0.0.1", std::stoi(url_.substr(url_.rfind(':') + 1)));
    auto r = c.Get(path);
    if (!r) return "no answer to " + path;
    std::string file = cell_.data_dir() + "/doc.xml";
    std::ofstream(file) << r->body;
    auto v = RunCommand({"xmllint", "--noout", "--nonet", "--schema", SchemaDir() + "/" + schema, file});
    return v.code == 0 ? "" : path + ": " + v.err;
  }
  LocalCell cell_{"cell-dashboard-"};
  std::string url_;
};

TEST_F(DashboardBrowser, ThePageFollowsTheCellLive) {
  Browser b(1600, 1400);
  b.Navigate(url_);
  // The first GET renders the state: a card per configured station (deploy/stations: BS01, EM01, KT01-KT04,
  // OK01), the two of this cell READY once their CNCs have announced themselves, the others UNAVAILABLE.
  ASSERT_TRUE(b.WaitTrue("return document.querySelectorAll('.card').length === 7", 10s));
  EXPECT_EQ(b.Exec("return document.querySelector('#station-KT03').dataset.execution"), "UNAVAILABLE");
  ASSERT_TRUE(b.WaitTrue("return document.querySelector('#station-KT01').dataset.execution === 'READY'", 15s))
      << b.Exec("return document.querySelector('#station-KT01').outerHTML");
  ASSERT_TRUE(b.WaitTrue("return document.querySelector('#conn').textContent === 'live'", 10s));
  b.Exec("window.__noReload = 42; return true;");  // gone if the page ever reloads

  // 1. A pallet on KT01: the card goes ACTIVE with the program and pallet, then the job COMPLETED.
  Put("DASH1", Program("DASH1", "1001"));
  ASSERT_EQ(cell_.Ctl({"route", "define", "RDASH", "--op", "KT01:DASH1"}).code, 0);
  const std::string job = Operate("RDASH", 4);
  EXPECT_TRUE(b.WaitTrue(
      "const c = document.querySelector('#station-KT01');"
      "return c.dataset.execution === 'ACTIVE' && c.querySelector('.f-program').textContent === 'DASH1'"
      " && c.querySelector('.f-pallet').textContent === '4';",
      30s))
      << b.Exec("return document.querySelector('#station-KT01').outerHTML");
  // Its card opens the running program's toolpath: the path as drawn from the program store's DASH1, one
  // path per drawn motion op in each view (plan and elevation): DASH1's three motion ops are N20 (where the
  // path starts, docs/plot.md) and the two drawn, N30 and N40. While the pallet runs the tool marker moves
  // and the moves done turn bold; once the run ends, both are done.
  b.Exec("document.querySelector('#station-KT01 .pathbtn').click(); return true;");
  ASSERT_TRUE(b.WaitTrue(
      "const v = document.querySelector('#pathview'); return v && v.dataset.state === 'drawn';", 15s))
      << b.Exec(
             "const v = document.querySelector('#pathview'); return v ? v.outerHTML.slice(0, 2000) : "
             "'none';");
  b.Exec(
      "const v = document.querySelector('#pathview'); window.__marks = new Set(); window.__doneActive = 0;"
      "window.__watch = setInterval(() => { "
      "window.__marks.add(v.querySelector('g.tool').getAttribute('transform'));"
      "  if (document.querySelector('#station-KT01').dataset.execution === 'ACTIVE')"
      "    window.__doneActive = Math.max(window.__doneActive, Number(v.dataset.done)); }, 50); return "
      "true;");
  for (const char* view : {"plan", "elevation"})
    EXPECT_EQ(b.Exec(std::string("return document.querySelectorAll('#pathview g.view[data-view=") + view +
                     "] path[data-seq]').length;"),
              2)
        << view;
  EXPECT_EQ(b.Exec("return document.querySelector('#pathview').dataset.moves;"), "2");
  EXPECT_NE(b.Exec("return document.querySelector('#pathview .pathinfo').textContent;")
                .get<std::string>()
                .find("3 motion ops"),
            std::string::npos);
  EXPECT_TRUE(b.WaitTrue("return window.__marks.size >= 4;", 30s))
      << b.Exec("return [...window.__marks].join(' | ');");
  EXPECT_TRUE(b.WaitTrue(
      "const r = document.querySelector('#job-" + job + "'); return r && r.dataset.state === 'RUNNING';",
      10s));
  EXPECT_TRUE(b.WaitTrue(
      "const r = document.querySelector('#job-" + job + "'); return r && r.dataset.state === 'COMPLETED';",
      60s))
      << b.Exec("return document.querySelector('#jobs').outerHTML");
  EXPECT_TRUE(
      b.WaitTrue("return document.querySelector('#station-KT01').dataset.execution !== 'ACTIVE'", 10s));
  // The toolpath followed the run: N30 was done while the pallet ran (the tool on N40's rapid back), both
  // once it ended; a screenshot of the toolpath over the page, then the page alone.
  EXPECT_GE(b.Exec("return window.__doneActive;").get<int>(), 1);
  EXPECT_TRUE(b.WaitTrue(
      "return document.querySelectorAll('#pathview g.view[data-view=plan] path.done').length === 2;", 10s))
      << b.Exec("return document.querySelector('#pathview').dataset.done;");
  b.Screenshot(CELL_ARTEFACT_DIR "/dashboard-toolpath.png");
  b.Exec(
      "clearInterval(window.__watch); document.querySelector('#pathview .pathclose').click(); return true;");
  // The run record and the cycle time reach the page too.
  EXPECT_TRUE(
      b.WaitTrue("return [...document.querySelectorAll('#inspections tr')].some(r => r.dataset.name === "
                 "'run-KT01-1.json' || (r.dataset.name||'').startsWith('run-KT01'));",
                 20s))
      << b.Exec("return document.querySelector('#inspections').outerHTML");
  EXPECT_TRUE(b.WaitTrue("return document.querySelector('#cycletable').textContent.includes('DASH1')", 10s));
  // Its EVT (cell/station/event) in the program events table.
  EXPECT_TRUE(
      b.WaitTrue("return document.querySelector('#progevents').textContent.includes('DASH1 PART DONE')", 10s))
      << b.Exec("return document.querySelector('#progevents').outerHTML");

  // 2. A pallet needing tool 7777, which no station holds: it waits, and each card says why.
  Put("DASH2", Program("DASH2", "7777"));
  ASSERT_EQ(cell_.Ctl({"route", "define", "RWAIT", "--op", "KT01,KT02:DASH2"}).code, 0);
  const std::string waiting = Operate("RWAIT", 9);
  const std::string reason = "const w = document.querySelector('#station-KT02 .waiting[data-job=\"" +
                             waiting + "\"]'); return w ? w.textContent : '';";
  EXPECT_TRUE(b.WaitTrue("const w = document.querySelector('#station-KT01 .waiting[data-job=\"" + waiting +
                             "\"]'); return w && w.textContent.includes('Pallet 9') && "
                             "w.textContent.includes('missing tools 7777');",
                         20s))
      << b.Exec("return document.querySelector('#station-KT01').outerHTML");
  EXPECT_NE(b.Exec(reason).get<std::string>().find("7777"), std::string::npos);
  EXPECT_TRUE(b.WaitTrue(
      "const r = document.querySelector('#job-" + waiting + "'); return r && r.dataset.state === 'WAITING';",
      10s));
  // Its decision log opens on a click.
  b.Exec("document.querySelector('#job-" + waiting + "').click(); return true;");
  EXPECT_TRUE(b.WaitTrue(
      "const l = document.querySelector('#log-" + waiting + "'); return l && l.textContent.includes('7777');",
      10s));
  EXPECT_EQ(b.Exec("return window.__noReload;"), 42) << "the page reloaded";

  // The same state in the terminal view.
  auto w = cell_.Ctl({"watch", "--count", "1"});
  EXPECT_EQ(w.code, 0) << w.err;
  EXPECT_NE(w.out.find("KT01"), std::string::npos) << w.out;
  EXPECT_NE(w.out.find("pallet 9 (job " + waiting +
                       ", route RWAIT): KT01 missing tools 7777; KT02 missing tools 7777"),
            std::string::npos)
      << w.out;
  // The job's row: id, state, route.
  bool row = false;
  for (size_t a = 0, b; (b = w.out.find('\n', a)) != std::string::npos; a = b + 1) {
    std::istringstream words(w.out.substr(a, b - a));
    std::string id, state, route;
    words >> id >> state >> route;
    row = row || (id == job && state == "COMPLETED" && route == "RDASH");
  }
  EXPECT_TRUE(row) << w.out;

  // MTConnect documents of the live cell.
  ASSERT_NE(SchemaDir(), "") << "tests/schemas/mtconnect not found in CELL_SOURCE_DIR";
  EXPECT_EQ(Validate("/probe", "MTConnectDevices_2.4_1.0.xsd"), "");
  EXPECT_EQ(Validate("/current", "MTConnectStreams_2.4_1.0.xsd"), "");
  EXPECT_EQ(Validate("/sample?count=500", "MTConnectStreams_2.4_1.0.xsd"), "");
  EXPECT_EQ(Validate("/assets", "MTConnectAssets_2.4_1.0.xsd"), "");

  b.Screenshot(CELL_ARTEFACT_DIR "/dashboard.png");
  EXPECT_GT(std::filesystem::file_size(CELL_ARTEFACT_DIR "/dashboard.png"), 10000u);

  // 3. The dashboard restarts: the page shows the lost connection, reconnects by itself and resyncs.
  auto pids = cell_.Pids();
  ASSERT_TRUE(pids.count("cell-dashboard"));
  kill(pids["cell-dashboard"], SIGKILL);
  EXPECT_TRUE(b.WaitTrue("return document.querySelector('#conn').className.includes('down')", 10s));
}

}  // namespace
}  // namespace cell::testing
