// A secured cell (issue 22; docs/security.md): `cellctl up --secure` makes the PKI in the data directory and
// starts every process with CELL_SECURITY=on. Pallets run end to end through the secured bus; the refusals
// are checked against their positive controls: the operator puts a program where the viewer is refused (and
// the viewer still reads), and an unsecured cellctl finds nobody where the secured one is answered.
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include "cell/dnc/codes.h"
#include "cell/dnc/settings.h"
#include "cell/testing/local_cell.h"
#include "cell/testing/process.h"
#include "sim_control.h"

using namespace cell::testing;
using nlohmann::json;

namespace {

class SecureCell : public ::testing::Test {
 protected:
  void SetUp() override {
    auto r = cell_.Up("KT01", "virtual", {"--secure"});
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    cell_.SetEnv("CELL_SECURITY", "on");  // cellctl: the operator identity of the cell's PKI
  }
  void TearDown() override {
    auto r = cell_.Down();
    EXPECT_EQ(r.code, 0) << r.err;
  }
  RunResult As(const std::string& identity, std::vector<std::string> args,
               const std::string& security = "on") {
    args.insert(args.begin(), BinDir() + "/cellctl");
    auto env = cell_.env();
    env["CELL_SECURITY"] = security;
    if (!identity.empty()) env["CELL_IDENTITY"] = identity;
    return RunCommand(args, env, std::chrono::seconds(60));
  }
  std::string Program(const std::string& name) {
    const std::string path = cell_.data_dir() + "/" + name + ".apl";
    std::ofstream(path) << "%\n(NAM," << name << ")\n(UCY,30)\nN10 G71 G90 G01\nN20 X0 Y0 Z100. F0\n"
                        << "N30 X100. Y50. Z0 F1000.\nN40 G00 X0 Y0 Z100. F0\nN50 M30\n%\n";
    return path;
  }
  LocalCell cell_{"cell-secure-"};
};

TEST_F(SecureCell, PalletsRunEndToEndThroughTheSecuredBus) {
  // The PKI is where DESIGN says, private keys the owner's only.
  const std::filesystem::path sec = cell_.data_dir() + "/security";
  ASSERT_TRUE(std::filesystem::exists(sec / "identities" / "interpreter-KT01" / "key.pem"));
  EXPECT_EQ(std::filesystem::status(sec / "ca.key").permissions() & std::filesystem::perms::group_all,
            std::filesystem::perms::none);

  auto put = cell_.Ctl({"program", "put", Program("SECURE1")});
  ASSERT_EQ(put.code, 0) << put.err;
  ASSERT_EQ(cell_.Ctl({"route", "define", "RS", "--op", "KT01:SECURE1"}).code, 0);
  auto op = cell_.Ctl({"route", "operate", "RS", "--pallet", "4"});
  ASSERT_EQ(op.code, 0) << op.err;
  const std::string job = op.out.substr(0, op.out.find('\n'));
  auto wait = cell_.Ctl({"job", "wait", job, "--timeout", "90"});
  EXPECT_EQ(wait.code, 0) << wait.out << wait.err;
  EXPECT_EQ(wait.out, "COMPLETED\n");

  // The dashboard, the viewer, draws the program KT01 ran from the text the station published as the run
  // started (cell/station/program): it may not ask the store (docs/dashboard.md, "Toolpath"). Three motion
  // ops, N20-N40, as SECURE1 has.
  std::string url = ReadFile(cell_.data_dir() + "/dashboard.url");
  url = url.substr(0, url.find('\n'));
  ASSERT_NE(url.find("http://127.0.0.1:"), std::string::npos) << url;
  httplib::Client web("127.0.0.1", std::stoi(url.substr(url.rfind(':') + 1)));
  json path;
  for (auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
       std::chrono::steady_clock::now() < until;
       std::this_thread::sleep_for(std::chrono::milliseconds(200))) {
    auto r = web.Get("/api/station/KT01/path");
    if (r && r->status == 200) {
      path = json::parse(r->body, nullptr, false);
      break;
    }
  }
  ASSERT_TRUE(path.is_object()) << "no toolpath for KT01 from the secured dashboard";
  EXPECT_EQ(path["program"], "SECURE1") << path.dump();
  EXPECT_EQ(path["motion_ops"], 3) << path.dump();
  EXPECT_EQ(path["source"].get<std::string>().rfind("run ", 0), 0u) << path.dump();
  // Control: a program the station did not run would come from the store, which the viewer may not ask.
  auto other = web.Get("/api/station/KT01/path?program=BYNOBODY");
  ASSERT_TRUE(other);
  EXPECT_NE(other->status, 200) << other->body;
  // The Gantt chart's plan: the viewer may ask the scheduler SCHED_PLAN (docs/security.md), and the page
  // has what ran on KT01 beside it.
  json plan;
  for (auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
       std::chrono::steady_clock::now() < until;
       std::this_thread::sleep_for(std::chrono::milliseconds(200))) {
    auto r = web.Get("/api/plan");
    if (r && r->status == 200) plan = json::parse(r->body, nullptr, false);
    if (plan.is_object() && !plan["fetched"].is_null() && !plan["ran"].empty()) break;
  }
  ASSERT_TRUE(plan.is_object()) << "no /api/plan from the secured dashboard";
  EXPECT_FALSE(plan["fetched"].is_null()) << plan.dump();
  EXPECT_TRUE(plan["error"].is_null()) << plan.dump();
  ASSERT_FALSE(plan["ran"].empty()) << plan.dump();
  EXPECT_EQ(plan["ran"][0]["station"], "KT01") << plan.dump();
}

TEST_F(SecureCell, TheViewerReadsButCannotWrite) {
  // Control: the operator's put is accepted.
  auto ok = As("", {"program", "put", Program("BYOPER")});
  EXPECT_EQ(ok.code, 0) << ok.err;
  auto refused = As("viewer", {"program", "put", Program("BYVIEWER")});
  EXPECT_NE(refused.code, 0);
  EXPECT_NE(refused.err.find("may not publish cell/program_store/request"), std::string::npos) << refused.err;
  EXPECT_EQ(refused.err.find('\n'), refused.err.size() - 1) << "one line: " << refused.err;
  // The scheduler answers the viewer the plan and refuses it the rest (the topic carries every op).
  auto plan = As("viewer", {"plan", "--json"});
  EXPECT_EQ(plan.code, 0) << plan.err;
  auto define = As("viewer", {"route", "define", "RV", "--op", "KT01:BYOPER"});
  EXPECT_NE(define.code, 0);
  EXPECT_NE(define.err.find("identity 'viewer' may ask the scheduler the plan only"), std::string::npos)
      << define.err;
  EXPECT_NE(As("", {"route", "show", "RV"}).code, 0) << "the viewer's route was defined";
  // The viewer's read works: it sees the station the cell runs.
  auto ls = As("viewer", {"station", "ls", "--json"});
  ASSERT_EQ(ls.code, 0) << ls.err;
  bool kt01_online = false;
  for (auto& s : json::parse(ls.out))
    if (s["id"] == "KT01") kt01_online = s["online"].get<bool>();
  EXPECT_TRUE(kt01_online) << ls.out;
  // The viewer's put never reached the store.
  EXPECT_NE(As("", {"program", "get", "BYVIEWER"}).code, 0);
  // It lists programs from what the store publishes (cell/program/list), as the operator does by request.
  auto programs = As("viewer", {"program", "ls", "BY*", "--json"});
  ASSERT_EQ(programs.code, 0) << programs.err;
  const json list = json::parse(programs.out, nullptr, false);
  ASSERT_FALSE(list.is_discarded()) << "stdout is not JSON: " << programs.out << programs.err;
  std::vector<std::string> names;
  for (auto& f : list) names.push_back(f["name"].get<std::string>());
  EXPECT_EQ(names, std::vector<std::string>{"BYOPER"}) << programs.out;
  // The store's journal names who put it (the audit trail, authenticated).
  std::string store_log;
  for (const auto& p : cell_.Record())
    if (p.service == "cell-program-store") store_log = p.log;
  ASSERT_FALSE(store_log.empty());
  const std::string line = "accepted program put HOST:BYOPER from identity 'operator' (authenticated";
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (ReadFile(store_log).find(line) == std::string::npos && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_NE(ReadFile(store_log).find(line), std::string::npos) << ReadFile(store_log);
}

// Issue 39 item 3: an identity that may not read a topic the verb needs gets the promised one line and exit 1
// (cellctl died of SIGSEGV tearing down the refused reader).
TEST_F(SecureCell, AnIdentityThatMayNotReadIsRefusedInOneLine) {
  auto ls = As("interpreter-KT01", {"station", "ls"});
  EXPECT_EQ(ls.code, 1) << ls.out << ls.err;
  EXPECT_NE(ls.err.find("may not subscribe to"), std::string::npos) << ls.err;
  EXPECT_NE(ls.err.find("interpreter-KT01"), std::string::npos) << ls.err;
  EXPECT_EQ(ls.err.find('\n'), ls.err.size() - 1) << "one line: " << ls.err;
}

// Issue 39 item 9: a certificate swapped for another identity's (it still verifies against the cell's CA) was
// refused with "cannot create a DDS participant (Fast DDS's log says why)"; the one line names the identity
// and the reason.
TEST_F(SecureCell, ASwappedCertificateIsNamedInTheRefusal) {
  const std::filesystem::path ids = std::filesystem::path(cell_.data_dir()) / "security" / "identities";
  ASSERT_TRUE(std::filesystem::exists(ids / "operator" / "cert.pem"));
  const std::string own = ReadFile((ids / "operator" / "cert.pem").string());
  std::filesystem::copy_file(ids / "viewer" / "cert.pem", ids / "operator" / "cert.pem",
                             std::filesystem::copy_options::overwrite_existing);
  auto r = As("operator", {"job", "ls"});
  std::ofstream(ids / "operator" / "cert.pem", std::ios::trunc) << own;  // cellctl's identity, restored
  EXPECT_EQ(r.code, 1) << r.out << r.err;
  EXPECT_NE(r.err.find("DDS Security refused identity 'operator'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("cert.pem (operator): the certificate of CN=viewer,O=cell, not of operator"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "one line: " << r.err;
  EXPECT_EQ(As("operator", {"job", "ls", "--json"}).code, 0);  // the control: its own certificate again
}

// Issue 39 item 8: one identity revoked without reissuing the PKI (`cellctl pki revoke`, a CRL both stacks
// read): it can no longer join (one line naming it and the CRL), and the others keep working.
TEST_F(SecureCell, ARevokedIdentityIsRefusedAndTheOthersKeepWorking) {
  auto before = As("interpreter-KT01", {"station", "ls"});  // joins; its grant does not cover station ls
  EXPECT_NE(before.err.find("may not subscribe to"), std::string::npos) << before.err;
  auto revoke = As("", {"pki", "revoke", "interpreter-KT01"});
  ASSERT_EQ(revoke.code, 0) << revoke.err;
  EXPECT_NE(revoke.out.find("revoked interpreter-KT01"), std::string::npos) << revoke.out;
  auto after = As("interpreter-KT01", {"station", "ls"});
  EXPECT_EQ(after.code, 1) << after.out << after.err;
  EXPECT_NE(after.err.find("DDS Security refused identity 'interpreter-KT01'"), std::string::npos)
      << after.err;
  EXPECT_NE(after.err.find("cert.pem (interpreter-KT01): revoked"), std::string::npos) << after.err;
  EXPECT_EQ(after.err.find('\n'), after.err.size() - 1) << "one line: " << after.err;
  // The others, started after the revocation (they load the CRL too), still work with the running cell.
  auto ls = As("", {"job", "ls", "--json"});
  EXPECT_EQ(ls.code, 0) << ls.err;
  EXPECT_EQ(As("viewer", {"station", "ls", "--json"}).code, 0);
}

TEST_F(SecureCell, AnUnsecuredCellctlFindsNobody) {
  auto secured = As("", {"job", "ls", "--json"});
  EXPECT_EQ(secured.code, 0) << secured.err;  // control
  auto plain = As("", {"job", "ls", "--json"}, "off");
  EXPECT_NE(plain.code, 0) << plain.out;
  auto missing = As("nobody", {"job", "ls"});
  EXPECT_NE(missing.code, 0);
  EXPECT_NE(missing.err.find("nobody"), std::string::npos) << missing.err;
}

TEST(SecureCellMixed, ASecuredCellThatMixesDdsStacksIsRefusedAtStart) {
  // The cell on Cyclone (CELL_DDS), KT01's station file (a copy of deploy/'s) naming Fast DDS.
  LocalCell cell("cell-secure-mixed-");
  cell.SetEnv("CELL_DDS", "cyclonedds");
  const std::string config = cell.data_dir() + "/config";
  std::filesystem::copy(SourceDir() + "/deploy", config, std::filesystem::copy_options::recursive);
  std::string text;
  {
    std::ifstream in(config + "/stations/KT01.toml");
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto at = text.find("[station]\n");
  ASSERT_NE(at, std::string::npos);
  text.insert(at + 10, "dds = \"fastdds\"\n");
  std::ofstream(config + "/stations/KT01.toml", std::ios::trunc) << text;
  cell.SetEnv("CELL_CONFIG_DIR", config);
  auto r = cell.Up("KT01", "virtual", {"--secure"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.err.find("a secured cell uses one DDS stack: station KT01 runs fastdds, the cell cyclonedds"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(cell.data_dir() + "/cell-up.json")) << "nothing was started";
}

// Issue 42 item 5 under DDS Security: `cellctl up --secure` starts KT01's cell-dnc (its file has a [serial]
// line, a pseudo-terminal with the simulated control on the master) as the identity dnc-KT01. The operator's
// `dnc status` and `dnc send` go through the secured bus (the send reads the program from the store as
// dnc-KT01 and delivers it byte-exact); the viewer reads the line's state too.
TEST(SecureCellDnc, CellDncRunsAsItsStationIdentityAndServesTheOperator) {
  namespace dnc = cell::dnc;
  LocalCell cell("cell-secure-dnc-");
  const std::string config = cell.data_dir() + "/config";
  std::filesystem::copy(SourceDir() + "/deploy", config, std::filesystem::copy_options::recursive);
  dnc::test::Pty pty;
  std::ofstream(config + "/stations/KT01.toml", std::ios::app)
      << "\n[serial]\ndevice = \"" << pty.slave() << "\"\nflow = \"xonxoff\"\n";
  cell.SetEnv("CELL_CONFIG_DIR", config);
  auto r = cell.Up("KT01", "virtual", {"--secure"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  cell.SetEnv("CELL_SECURITY", "on");
  auto status = cell.Ctl({"dnc", "status", "--json"});
  ASSERT_EQ(status.code, 0) << status.err;
  json rows = json::parse(status.out);
  ASSERT_EQ(rows.size(), 1u) << status.out;
  EXPECT_EQ(rows[0]["station"], "KT01");
  EXPECT_EQ(rows[0]["dnc"], true) << "cell-dnc/KT01 is not heard on cell/dnc/status: " << status.out;
  EXPECT_EQ(rows[0]["state"], "idle");

  const std::string text = "%\nN10 G01 X100. Y50. F1000.\nN20 M30\n";
  const std::string path = cell.data_dir() + "/DNC1.txt";
  std::ofstream(path) << text;
  r = cell.Ctl({"program", "put", path, "--name", "DNC1", "--node", "HOST", "--dialect", "ktapl", "--force"});
  ASSERT_EQ(r.code, 0) << r.err;
  cell::config::SerialTable keys;
  keys.device = pty.slave();
  const dnc::Format format = dnc::Resolve(dnc::Control::kKtApl, keys).format;
  dnc::test::SimOptions so;
  so.format = format;
  so.line_bytes_per_s = 960;  // 9600 baud, 7E1: the KT-APL's default (docs/dnc.md judgement call 5)
  dnc::test::SimControl sim(pty, so);
  sim.StartReading();
  r = cell.Ctl({"dnc", "send", "KT01", "DNC1"});
  if (r.code != 0) sim.Stop();
  sim.Join();
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("sent HOST:DNC1 to KT01"), std::string::npos) << r.out;
  EXPECT_EQ(sim.wire(), dnc::Encode(format, text));

  auto env = cell.env();
  env["CELL_IDENTITY"] = "viewer";
  auto viewer = RunCommand({BinDir() + "/cellctl", "dnc", "status", "--json"}, env, std::chrono::seconds(60));
  ASSERT_EQ(viewer.code, 0) << viewer.err;
  rows = json::parse(viewer.out);
  ASSERT_EQ(rows.size(), 1u) << viewer.out;
  EXPECT_EQ(rows[0]["program"], "HOST:DNC1");
  EXPECT_EQ(rows[0]["transfers"], 1);
  r = cell.Down();
  EXPECT_EQ(r.code, 0) << r.err;
}

}  // namespace
