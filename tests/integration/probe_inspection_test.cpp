// Measurement end to end (issue 14), with real processes: pallet 1 carries a part model (a face at Z 10 and a
// 40.1 mm bore centred at X200.05 Y99.96, 0.05 and -0.04 off its nominal X200 Y100), stored in the program
// store as type part_model and named in the pallet map before its programs; KT01's station hands it to its
// servo for the run. Pallet 1 runs PROBE, which opens an inspection file (G36 + OIF, manual ln 7894-7908),
// probes the face (G26Z, App. E ln 12230-12281) and the bore (G27X, G27Y, ln 12551-12644), sets fixture
// offset H1 from the measured centre (FXC, as FINDBORE does, part 2 ex. 9-10 ln 10055-10114), waits on an
// input, closes the file (G37) and copies it to HOST (RCP, ln 8316-8356); then MACH on the same pallet moves
// to the nominal centre with H1. The inspection writer is killed with SIGKILL while the file is still open;
// the close waits for it and the file is stored once it is back. Checks: every line of the file (numbers by
// hand below), the QIF export against the QIF 3.0 schema, H1 kept on the station, MACH's motion at the
// measured centre.
//
// By hand (6 mm ball, L1003 = L1004 = 3 its effective radius, tool 1 150 mm long; as the corpus cases
// appE_g26z_surface and appE_g27xy_bore work them out): G26Z from Z40 finds the face at Z 10: "Z SURFACE =
// 10.000000". G27X220. at Y100 (0.04 off the bore's axis): the ball's centre touches 20.05 - 3 = 17.05 from
// the axis at dX = sqrt(17.05^2 - .04^2) = 17.049953 each way, so the centre is X200.05 and L1005 =
// 34.099906 + 2*3 = 40.099906, rounded to .001 (L858): "X SURFACE SEPARATION = 40.100000", "X CENTER =
// 200.05000". G27Y120. on the axis X200.05: +-17.05 about Y99.96: "Y SURFACE SEPARATION = 40.100000",
// "Y CENTER = 99.960000". FXC H1: X .05, Y -.04 mm. MACH's X200. Y100. with H1: machine X200.05 Y99.96.
#include <signal.h>

#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/idl/motion.h"
#include "cell/testing/local_cell.h"
#include "cell/testing/process.h"
#include "cell/testing/qif.h"

using namespace cell::testing;
using nlohmann::json;

namespace {

constexpr const char* kPart =
    R"(# A block whose top is Z 10 with a 40.1 mm bore centred at X200.05 Y99.96, 30 deep (mm).
[[plane]]
point = [0, 0, 10]
normal = [0, 0, 1]
[[bore]]
top = [200.05, 99.96, 10]
axis = [0, 0, 1]
diameter = 40.1
depth = 30
)";

constexpr const char* kProbe = R"(%
(UCY,5)
N10 G71 G90 G0 X150. Y100. Z40. F0 T1
N20 M06
N22 Z40. ! the probe's length applies from the next Z move
N25 (PAR,L1003=3.,L1004=3.)
N30 G36
N40 (OIF,BORE1)
N50 G26Z-20.
N60 G0 X200. Y100. Z40.
N70 Z0.
N80 G27X220.
N90 G27Y120.
N100 (PAR,L1=X-200.,L2=Y-100.)
N110 (FXC,H1XL1YL2)
N115 G0 Z40.
N120 (WAI,I04D,1=1)
N130 G37
N140 (RCP,BORE1,TO,HOST,BORE1)
N150 M30
%
)";

constexpr const char* kMach = R"(%
(UCY,5)
N10 G71 G90 G48
N20 G0 X200. Y100. Z40. F0 H1
N30 M30
%
)";

class ProbeInspection : public ::testing::Test {
 protected:
  void SetUp() override {
    auto r = cell_.Up("KT01", "virtual");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    // The spindle probe as tool 1 in socket 10, 150 mm to the stylus tip (TLD, manual ln 3975-4097).
    const std::string tld = cell_.data_dir() + "/probe.tld";
    std::ofstream(tld) << "%\n(TLD,S10T1P150.D6.L1000)\n%\n";
    auto t = Ctl({"tools", "load", "KT01", tld});
    ASSERT_EQ(t.code, 0) << t.err;
  }
  void TearDown() override {
    if (cell_.is_up()) {
      EXPECT_EQ(cell_.Down().code, 0);
    }
  }
  RunResult Ctl(std::vector<std::string> args) { return cell_.Ctl(std::move(args)); }
  void Put(const std::string& name, const std::string& text) {
    std::string path = cell_.data_dir() + "/" + name + ".ktapl";
    std::ofstream(path) << text;
    auto r = Ctl({"program", "put", path, "--name", name, "--dialect", "ktapl"});
    ASSERT_EQ(r.code, 0) << name << ": " << r.err;
  }
  json Station(const std::string& id) {
    for (auto& s : cell_.Json({"station", "ls", "--json"}))
      if (s["id"] == id) return s;
    return nullptr;
  }

  LocalCell cell_{"cell-probe-inspection-"};
};

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

// YY:MM:DD HH:MM (ln 7904-7908).
bool IsStamp(const std::string& s) {
  if (s.size() != 14) return false;
  for (size_t i = 0; i < s.size(); ++i) {
    const char want = i == 8 ? ' ' : (i % 3 == 2 ? ':' : '0');
    if (want == '0' ? !std::isdigit(static_cast<unsigned char>(s[i])) : s[i] != want) return false;
  }
  return true;
}

// "LABEL = number": the label and the number, which must be within `tol` of `want`.
void ExpectResult(const std::string& line, const std::string& label, double want, double tol) {
  ASSERT_EQ(line.rfind(label + " = ", 0), 0u) << line;
  EXPECT_NEAR(std::stod(line.substr(label.size() + 3)), want, tol) << line;
}

TEST_F(ProbeInspection, ProbesABoreWritesTheInspectionFileAndTheNextProgramUsesTheOffset) {
  Put("PROBE", kProbe);
  Put("MACH", kMach);
  // The part model is checked when it is stored: a malformed one is refused with its line and column.
  const std::string bad = cell_.data_dir() + "/bad.toml";
  std::ofstream(bad) << "[[bore]]\ntop = [200, 100\n";
  auto refused = Ctl({"program", "put", bad, "--name", "BAD_PART", "--type", "part_model"});
  EXPECT_NE(refused.code, 0);
  EXPECT_NE(refused.err.find("BAD_PART:2:"), std::string::npos) << refused.err;
  const std::string part = cell_.data_dir() + "/bore.toml";
  std::ofstream(part) << kPart;
  auto stored = Ctl({"program", "put", part, "--name", "BORE_PART", "--type", "part_model"});
  ASSERT_EQ(stored.code, 0) << stored.err;
  cell::bus::Participant bus("probe-inspection-test");
  cell::bus::Reader<cell::AxisState> axes(bus, cell::bus::topics::kAxisState, cell::bus::QosKind::kTelemetry);
  ASSERT_EQ(Ctl({"pallet", "set", "1", "BORE_PART", "PROBE", "MACH"}).code, 0);
  auto run = Ctl({"pallet", "run", "1", "--station", "KT01"});
  ASSERT_EQ(run.code, 0) << run.err;
  const std::string job = run.out.substr(0, run.out.find('\n'));

  // The file is open (its lines are with the run) while KT01 waits on I04D.1: the writer dies now.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  json st;
  for (;;) {
    st = Station("KT01");
    if (st.is_object() && st["execution"] == "WAIT") break;
    ASSERT_TRUE(st.is_object() && st["execution"] != "STOPPED") << st;
    ASSERT_LT(std::chrono::steady_clock::now(), deadline) << st;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  auto pids = cell_.Pids();
  auto writer = pids.find("cell-inspection-writer");
  ASSERT_NE(writer, pids.end());
  ASSERT_EQ(kill(writer->second, SIGKILL), 0);
  ASSERT_EQ(Ctl({"station", "input", "KT01", "I04D.1=1"}).code, 0);
  // G37 cannot be durable without a writer: the run waits (L1050 not set, nothing lost), then goes on once
  // the writer is back.
  EXPECT_EQ(Ctl({"job", "wait", job, "--timeout", "3"}).code, 3);
  auto restart = Ctl({"restart", "cell-inspection-writer"});
  ASSERT_EQ(restart.code, 0) << restart.err;
  auto wait = Ctl({"job", "wait", job, "--timeout", "120"});
  ASSERT_EQ(wait.out, "COMPLETED\n") << wait.err;

  // The file on the station and its copy on HOST, line by line.
  auto ls = Ctl({"inspect", "ls"});
  EXPECT_NE(ls.out.find("BORE1"), std::string::npos) << ls.out;
  auto cat = Ctl({"inspect", "cat", "HOST/BORE1"});
  ASSERT_EQ(cat.code, 0) << cat.err;
  EXPECT_EQ(Ctl({"inspect", "cat", "KT01/BORE1"}).out, cat.out);
  auto l = Lines(cat.out);
  ASSERT_EQ(l.size(), 15u) << cat.out;
  EXPECT_EQ(l[0], "CONTROL SERIAL NUMBER = 345879");  // KT01.toml [params] L3060
  EXPECT_EQ(l[1], "PALLET CODE/PART NUMBER = 1");     // L3020, the pallet (no NAM)
  EXPECT_TRUE(IsStamp(l[2])) << l[2];
  EXPECT_EQ(l[3], std::string(30, '-'));
  EXPECT_EQ(l[4], "N50");
  ExpectResult(l[5], "Z SURFACE", 10.0, 1e-4);
  EXPECT_EQ(l[6], "");
  EXPECT_EQ(l[7], "N80");
  ExpectResult(l[8], "X SURFACE SEPARATION", 40.1, 1e-9);  // rounded to .001 by the cycle
  ExpectResult(l[9], "X CENTER", 200.05, 1e-4);
  EXPECT_EQ(l[10], "");
  EXPECT_EQ(l[11], "N90");
  ExpectResult(l[12], "Y SURFACE SEPARATION", 40.1, 1e-9);
  ExpectResult(l[13], "Y CENTER", 99.96, 1e-4);
  EXPECT_EQ(l[14], "");

  // The program store has the file too, as a revision in each namespace, typed as an inspection file.
  auto show = cell_.Json({"program", "show", "BORE1", "--node", "HOST", "--json"});
  ASSERT_TRUE(show.is_object()) << show;
  EXPECT_EQ(show.value("type", ""), "inspection") << show;
  EXPECT_EQ(show.value("dialect", ""), "ktapl") << show;
  EXPECT_EQ(Ctl({"program", "get", "BORE1", "--node", "KT01"}).out, cat.out);

  // Exports: CSV rows per quantity, QIF valid against the QIF 3.0 schema.
  auto csv = Ctl({"inspect", "export", "HOST/BORE1", "--format", "csv", "--units", "mm"});
  ASSERT_EQ(csv.code, 0) << csv.err;
  EXPECT_NE(csv.out.find("X CENTER"), std::string::npos) << csv.out;
  auto qif = Ctl({"inspect", "export", "HOST/BORE1", "--format", "qif", "--units", "mm"});
  ASSERT_EQ(qif.code, 0) << qif.err;
  EXPECT_NE(qif.out.find("<QIFDocument"), std::string::npos);
  EXPECT_EQ(ValidateQif(qif.out), "");

  // H1 stays on the station; MACH ran with it: machine X200.05 Y99.96.
  auto vars = cell_.Json({"station", "vars", "KT01", "--json"});
  ASSERT_TRUE(vars.is_object()) << vars;
  EXPECT_NEAR(vars.value("H1.X", 0.0), 0.05, 1e-4) << vars;
  EXPECT_NEAR(vars.value("H1.Y", 0.0), -0.04, 1e-4) << vars;
  // The same line as the control's fixture offset table (`station offsets`).
  auto table = cell_.Json({"station", "offsets", "KT01", "--json"});
  ASSERT_TRUE(table.is_object() && table.contains("H1")) << table;
  EXPECT_NEAR(table["H1"].value("X", 0.0), 0.05, 1e-4) << table;
  EXPECT_NEAR(table["H1"].value("Y", 0.0), -0.04, 1e-4) << table;
  auto shown = Ctl({"station", "offsets", "KT01"});
  EXPECT_EQ(shown.out.rfind("H ", 0), 0u) << shown.out;
  EXPECT_NE(shown.out.find("\nH1 "), std::string::npos) << shown.out;
  auto at = axes.WaitFor(
      [](const cell::AxisState& a) {
        return a.station() == "KT01" && std::abs(a.commanded()[0] - 200.05) < 1e-3 &&
               std::abs(a.commanded()[1] - 99.96) < 1e-3;
      },
      cell::bus::Millis(10000));
  EXPECT_TRUE(at.has_value()) << "KT01 never stood at X200.05 Y99.96 (MACH with H1)";
}

}  // namespace
