// Discrete I/O through the cell (docs/station.md, "Discrete I/O"), with real processes: a KT-APL program on
// KT01 waits in WAI (manual ln 4343-4359) with the station in WAIT and the awaited inputs in its status text
// until `cellctl station input` sets them; an Okuma program on OK01 clamps the chuck with M83 (OSP-E100L
// manual ln 1977-1978; the station file deploy/stations/OK01.toml maps it to the output CHUCK) and
// `cellctl station io OK01` shows it.
#include <chrono>
#include <fstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cell/testing/cell_fixture.h"

using namespace cell::testing;
using nlohmann::json;

namespace {

std::string FirstLine(const std::string& s) {
  return s.substr(0, s.find('\n'));
}

class StationIo : public CellFixture {
 protected:
  StationIo() : CellFixture("cell-station-io-") {}
  void SetUp() override { Up("KT01,OK01"); }
  void Put(const std::string& name, const std::string& text, const std::string& dialect) {
    std::string path = cell_.data_dir() + "/" + name;
    std::ofstream(path) << text;
    auto r = Ctl({"program", "put", path, "--name", name, "--dialect", dialect});
    ASSERT_EQ(r.code, 0) << name << ": " << r.out << r.err;
  }
  // Starts pallet `pallet` (one program) on `station`; its job id.
  std::string RunPallet(const std::string& pallet, const std::string& program, const std::string& station) {
    auto set = Ctl({"pallet", "set", pallet, program});
    EXPECT_EQ(set.code, 0) << set.err;
    auto run = Ctl({"pallet", "run", pallet, "--station", station});
    EXPECT_EQ(run.code, 0) << run.err;
    return FirstLine(run.out);
  }
  json Station(const std::string& id) {
    for (auto& s : CtlJson({"station", "ls", "--json"}))
      if (s["id"] == id) return s;
    return nullptr;
  }
  // The row of `name` in `cellctl station io ID --json`, or null.
  json Point(const std::string& id, const std::string& name) {
    for (auto& p : CtlJson({"station", "io", id, "--json"}))
      if (p["name"] == name) return p;
    return nullptr;
  }
};

TEST_F(StationIo, WaiBlocksUntilTheInputIsSetAndM83ClampsTheChuck) {
  // ln 4357: N40(WAI,I04D,1=1, I03D,3=0); here one bit, then a move that must wait for it.
  Put("WAITER", "%\n(UCY,10)\nG71 G90\nG01 X0 Y0 Z100. F0\n(WAI,I04D,1=1)\nG01 X50. F2000.\nM30\n%\n",
      "ktapl");
  const std::string job = RunPallet("3", "WAITER", "KT01");
  ASSERT_FALSE(job.empty());

  // The station shows WAIT with the awaited bit while the job stays running.
  json st;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  for (;;) {
    st = Station("KT01");
    if (st.is_object() && st["execution"] == "WAIT") break;
    ASSERT_LT(std::chrono::steady_clock::now(), deadline) << st;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(st["status_text"], "waiting for I04D.1=1") << st;
  EXPECT_EQ(Ctl({"job", "wait", job, "--timeout", "1"}).code, 3);  // still running: the wait holds it

  // The old bare-number form is refused with the new one named; the KT-APL bit releases the run.
  auto old = Ctl({"station", "input", "KT01", "3=1"});
  EXPECT_EQ(old.code, 2);
  EXPECT_NE(old.err.find("I<word>.<bit>"), std::string::npos) << old.err;
  auto in = Ctl({"station", "input", "KT01", "I04D.1=1"});
  ASSERT_EQ(in.code, 0) << in.err;
  auto w = Ctl({"job", "wait", job, "--timeout", "60"});
  EXPECT_EQ(w.out, "COMPLETED\n") << w.err;
  json p = Point("KT01", "I04D.1");
  ASSERT_TRUE(p.is_object());
  EXPECT_EQ(p["kind"], "input");
  EXPECT_EQ(p["value"], 1);

  // OK01: the station file's chuck (M83 clamp, interlock M184/M185) before any program: unclamped.
  p = Point("OK01", "CHUCK");
  ASSERT_TRUE(p.is_object());
  EXPECT_EQ(p["value"], 0);
  Put("CLAMP.MIN", "%\nO100\nN1 M83\nN2 G00 X100 Z50 S500 M03\nN3 M05\nN4 M02\n%\n", "okuma");
  const std::string clamp = RunPallet("4", "CLAMP.MIN", "OK01");
  ASSERT_FALSE(clamp.empty());
  w = Ctl({"job", "wait", clamp, "--timeout", "60"});
  ASSERT_EQ(w.out, "COMPLETED\n") << w.err;
  p = Point("OK01", "CHUCK");
  ASSERT_TRUE(p.is_object());
  EXPECT_EQ(p["kind"], "output");
  EXPECT_EQ(p["value"], 1);
  // The human table names it too.
  auto table = Ctl({"station", "io", "OK01"});
  ASSERT_EQ(table.code, 0) << table.err;
  EXPECT_NE(table.out.find("CHUCK"), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("TAILSTOCK"), std::string::npos) << table.out;
}

}  // namespace
