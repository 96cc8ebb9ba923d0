// DNC through real processes (issue 42 items 3 and 5, domain 35): cell-program-store, one cell-dnc per
// station on a pseudo-terminal pair with the simulated control on the master (services/dnc/test/
// sim_control.h), and cellctl. KT01 (KT-APL, ISO 7-bit even parity, NUL end) and EM01 (EMCOTRONIC, ISO
// 7-bit even parity, CR LF blocks, ctrl-Z end): `cellctl dnc send` delivers the stored program byte-exact in
// the control's code; `receive` stores what the control punches as a new revision; a parity-damaged receive
// stores nothing and exits 1 naming the byte; a kill -9 of cell-dnc mid-receive or mid-send leaves the store
// as it was and a restarted cell-dnc serves again; `dnc status` lists every line, one without a process as
// such; the dashboard's view (its CellView fed from the bus by its Feed) shows a transfer and a killed line.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/dashboard/cell_view.h"
#include "cell/dashboard/feed.h"
#include "cell/dnc/codes.h"
#include "cell/dnc/line.h"
#include "cell/dnc/settings.h"
#include "cell/health/health.h"
#include "cell/idl/dnc.h"
#include "cell/testing/process.h"
#include "sim_control.h"

namespace fs = std::filesystem;
using cell::testing::Process;
using cell::testing::RunResult;
using namespace cell::dnc;
using ::testing::HasSubstr;

namespace {

// Each line's [serial] table beyond the device: KT01 at its default 9600 baud (960 bytes/s, 7E1 in the eighth
// bit, docs/dnc.md), EM01 at the EMCOTRONIC's highest, 4800 (480 bytes/s: alarm 870, ln 7225), XON/XOFF (a
// pty carries no RTS/CTS). Real rates, not scaled: the simulated control's 192 bytes above its XOFF mark are
// then 200 ms (KT01) and 400 ms (EM01) of the machine's scheduling delays, which a test on a loaded machine
// needs.
struct Line {
  std::string station, dialect;
  int baud;
};
const Line kKt{"KT01", "ktapl", 9600};
const Line kEm{"EM01", "emco", 4800};

// A program both controls' codes carry (upper case, no '=' or '!'): 20 blocks, several XOFFs' worth.
std::string Program(const std::string& start, int blocks) {
  std::string p = start + "\n";
  for (int i = 1; i <= blocks; ++i)
    p += fmt::format("N{:04d} G01 X{}.{:03d} Z-{}.500 F0.2\n", i * 10, i, i * 7 % 1000, i % 40);
  return p + "M30\n";
}

// The dashboard's view of the lines, fed from the bus as cell-dashboard feeds it (docs/dashboard.md).
struct Dashboard {
  explicit Dashboard(cell::bus::Participant& p)
      : view({{"KT01", "ktapl", "", "", {}}, {"EM01", "emco", "", "", {}}}),
        feed(p, view, cell::dashboard::FeedOptions{false, {}}) {}
  // The station's row on the page ("" when the view has none), the feed's heartbeats followed first.
  nlohmann::json Row(const std::string& station) {
    feed.Tick();
    const nlohmann::json snap = view.Snapshot();
    for (auto& row : snap["dnc"])
      if (row["station"] == station) return row;
    return {};
  }
  // Waits until the station's row satisfies `ok`; the last row seen otherwise.
  bool WaitRow(const std::string& station, const std::function<bool(const nlohmann::json&)>& ok,
               nlohmann::json* last = nullptr) {
    nlohmann::json row;
    bool got = cell::bus::WaitUntil(
        [&] {
          row = Row(station);
          return !row.is_null() && ok(row);
        },
        std::chrono::seconds(30));
    if (last) *last = row;
    return got;
  }
  cell::dashboard::CellView view;
  cell::dashboard::Feed feed;
};

class DncTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = cell::testing::MakeTempDir("cell-dnc-test-");
    fs::copy(cell::testing::SourceDir() + "/deploy", dir_ + "/config", fs::copy_options::recursive);
    for (const Line& l : {kKt, kEm}) {
      ptys_[l.station] = std::make_unique<test::Pty>();
      std::ofstream(dir_ + "/config/stations/" + l.station + ".toml", std::ios::app) << fmt::format(
          "\n[serial]\ndevice = \"{}\"\nbaud = {}\nflow = \"xonxoff\"\n", ptys_[l.station]->slave(), l.baud);
    }
    // OK01 has a line and no cell-dnc: `dnc status` says so.
    std::ofstream(dir_ + "/config/stations/OK01.toml", std::ios::app)
        << "\n[serial]\ndevice = \"/dev/null\"\n";
    env_ = {{"CELL_CONFIG_DIR", dir_ + "/config"}, {"CELL_DATA_DIR", dir_ + "/data"}};
    bus_ = std::make_unique<cell::bus::Participant>("dnc_test");
    live_ = std::make_unique<cell::health::Liveness>(*bus_);
    status_ = std::make_unique<cell::bus::Reader<cell::DncStatus>>(*bus_, cell::bus::topics::kDncStatus,
                                                                   cell::bus::QosKind::kState);
    store_ =
        std::make_unique<Process>(std::vector<std::string>{cell::testing::BinDir() + "/cell-program-store"},
                                  env_, "", dir_ + "/store.log");
    Launch(kKt);
    Launch(kEm);
    WaitReady(kKt, 0);
    WaitReady(kEm, 0);
    ASSERT_TRUE(
        cell::bus::WaitUntil([&] { return live_->Online("cell-program-store"); }, std::chrono::seconds(30)))
        << cell::testing::ReadFile(dir_ + "/store.log");
  }
  void TearDown() override {
    if (HasFailure())
      for (const char* log : {"store.log", "KT01.log", "EM01.log"})
        std::fprintf(stderr, "%s:\n%s\n", log, cell::testing::ReadFile(dir_ + "/" + log).c_str());
    dnc_.clear();
    store_.reset();
    status_.reset();
    live_.reset();
    bus_.reset();
    ptys_.clear();
    fs::remove_all(dir_);
  }

  // Starts the station's cell-dnc and waits until it has announced itself ready (a new process: another
  // boot id than the one before).
  void StartDnc(const Line& l) {
    auto before = live_->Snapshot();
    const std::string id = "cell-dnc/" + l.station;
    const uint64_t old_boot = before.count(id) ? before[id].boot_id() : 0;
    Launch(l);
    WaitReady(l, old_boot);
  }
  void Launch(const Line& l) {
    dnc_[l.station] = std::make_unique<Process>(
        std::vector<std::string>{cell::testing::BinDir() + "/cell-dnc", "--station", l.station}, env_, "",
        dir_ + "/" + l.station + ".log");
  }
  void WaitReady(const Line& l, uint64_t old_boot) {
    const std::string id = "cell-dnc/" + l.station;
    ASSERT_TRUE(cell::bus::WaitUntil(
        [&] {
          auto s = live_->Snapshot();
          return live_->Online(id) && s[id].boot_id() != old_boot;
        },
        std::chrono::seconds(30)))
        << cell::testing::ReadFile(dir_ + "/" + l.station + ".log");
  }

  RunResult Ctl(std::vector<std::string> args) {
    args.insert(args.begin(), cell::testing::BinDir() + "/cellctl");
    return cell::testing::RunCommand(args, env_, std::chrono::seconds(120));
  }
  std::unique_ptr<Process> CtlInBackground(std::vector<std::string> args, const std::string& name) {
    args.insert(args.begin(), cell::testing::BinDir() + "/cellctl");
    return std::make_unique<Process>(args, env_, dir_ + "/" + name + ".out", dir_ + "/" + name + ".err");
  }
  void Put(const std::string& name, const std::string& node, const std::string& text) {
    const std::string file = dir_ + "/" + name + ".txt";
    std::ofstream(file) << text;
    RunResult r = Ctl({"program", "put", file, "--name", name, "--node", node, "--force"});
    ASSERT_EQ(r.code, 0) << r.err;
  }
  // The line's format as cell-dnc resolves it from the station file.
  Format FormatOf(const Line& l) {
    cell::config::SerialTable keys;
    keys.device = ptys_[l.station]->slave();
    keys.baud = l.baud;
    return Resolve(ControlOf(l.dialect), keys).format;
  }
  test::SimOptions Sim(const Line& l) {
    test::SimOptions so;
    so.format = FormatOf(l);
    so.line_bytes_per_s = l.baud / 10.0;  // start, 7 data bits, the parity bit, stop
    return so;
  }
  // Forgets the line states heard so far: the next WaitState waits for a new one.
  void ForgetStates() {
    while (status_->Take(std::chrono::milliseconds(0))) {
    }
  }
  // Waits until the station's line reports `state` with at least `bytes` moved.
  bool WaitState(const std::string& station, cell::DncState state, uint64_t bytes = 0) {
    return status_
        ->WaitFor(
            [&](const cell::DncStatus& s) {
              return s.station() == station && s.state() == state && s.bytes() >= bytes;
            },
            std::chrono::seconds(30))
        .has_value();
  }
  nlohmann::json Show(const std::string& name, const std::string& node) {
    RunResult r = Ctl({"program", "show", name, "--node", node, "--json"});
    return r.code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
  }

  // Sends `name` to the station's simulated control and returns what it pulled off the line.
  std::vector<uint8_t> SendTo(const Line& l, const std::string& name, RunResult& r) {
    test::SimControl sim(*ptys_[l.station], Sim(l));
    sim.StartReading();
    r = Ctl({"dnc", "send", l.station, name});
    sim.Join();
    EXPECT_EQ(sim.error(), "");
    EXPECT_EQ(sim.lost(), 0u);
    return sim.wire();
  }

  std::string dir_;
  std::map<std::string, std::string> env_;
  std::map<std::string, std::unique_ptr<test::Pty>> ptys_;
  std::unique_ptr<cell::bus::Participant> bus_;
  std::unique_ptr<cell::health::Liveness> live_;
  std::unique_ptr<cell::bus::Reader<cell::DncStatus>> status_;
  std::unique_ptr<Process> store_;
  std::map<std::string, std::unique_ptr<Process>> dnc_;
};

TEST_F(DncTest, SendDeliversTheStoredProgramByteExactInEachControlsCode) {
  const std::string kt = Program("%", 40), em = Program("%12", 20);
  Put("PART-A", "HOST", kt);  // KT01 finds it in HOST (nothing of that name in its own namespace)
  Put("O12", "EM01", em);
  RunResult r;
  std::vector<uint8_t> wire = SendTo(kKt, "PART-A", r);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("sent HOST:PART-A to KT01"));
  EXPECT_EQ(wire, Encode(FormatOf(kKt), kt));
  // By hand (ISO 840, even parity in the eighth bit): 50 NUL of leader, '%' 0x25 has three ones -> 0xA5,
  // then LF 0x0A (two ones) ends the block; 'N' 0x4E has four -> 0x4E; the trailer is 50 NUL.
  ASSERT_GT(wire.size(), 104u);
  EXPECT_EQ(std::count(wire.begin(), wire.begin() + 50, 0), 50);
  EXPECT_EQ(wire[50], 0xA5);
  EXPECT_EQ(wire[51], 0x0A);
  EXPECT_EQ(wire[52], 0x4E);
  EXPECT_EQ(std::count(wire.end() - 50, wire.end(), 0), 50);

  wire = SendTo(kEm, "O12", r);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("sent EM01:O12 to EM01"));
  EXPECT_EQ(wire, Encode(FormatOf(kEm), em));
  // EMCOTRONIC (ln 5659-5661, 5576): '%' 0xA5, '1' 0x31 and '2' 0x32 (three ones each) -> 0xB1 0xB2, the
  // end of block CR 0x0D (three) -> 0x8D and LF 0x0A, and after M30's CR LF the end of data ctrl-Z 0x1A
  // (three) -> 0x9A.
  const std::vector<uint8_t> head{0xA5, 0xB1, 0xB2, 0x8D, 0x0A};
  EXPECT_TRUE(std::equal(head.begin(), head.end(), wire.begin() + 50));
  EXPECT_EQ(wire[wire.size() - 51], 0x9A);

  // A program that is not stored: one line, exit 1, nothing on the line.
  r = Ctl({"dnc", "send", "KT01", "NOPE"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("no program 'NOPE' in KT01 or HOST"));

  // Longer than the EMCOTRONIC's 20 kB program memory (ln 608: 20 x 1024 = 20,480 characters): refused before
  // a byte goes out, one line naming the size and the limit and the drip feed.
  const std::string big = Program("%13", 700);
  ASSERT_GT(big.size(), 20480u);
  Put("O13", "EM01", big);
  r = Ctl({"dnc", "send", "EM01", "O13"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr(fmt::format("EM01:O13: {} characters, more than the EMCOTRONIC memory holds "
                                           "(20480 characters, [serial] memory): feed it with `cellctl dnc "
                                           "drip EM01 O13`",
                                           big.size())));
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  pollfd pfd{ptys_["EM01"]->master(), POLLIN, 0};
  EXPECT_EQ(::poll(&pfd, 1, 200), 0) << "bytes on the line";
}

TEST_F(DncTest, ReceiveStoresWhatTheControlPunchesAsANewRevisionAndADamagedOneNothing) {
  for (const Line& l : {kKt, kEm}) {
    SCOPED_TRACE(l.station);
    const std::string old = Program(l.station == "EM01" ? "%77" : "%", 3);
    const std::string punched = Program(l.station == "EM01" ? "%77" : "%", 25);
    Put("P77", l.station, old);
    ForgetStates();
    auto recv = CtlInBackground({"dnc", "receive", l.station, "P77"}, "recv-" + l.station);
    ASSERT_TRUE(WaitState(l.station, cell::DNC_RECEIVING));
    test::SimControl sim(*ptys_[l.station], Sim(l));
    sim.StartPunching(Encode(FormatOf(l), punched));
    auto code = recv->Wait(std::chrono::seconds(60));
    sim.Stop();
    ASSERT_EQ(code, std::optional<int>(0)) << cell::testing::ReadFile(dir_ + "/recv-" + l.station + ".err");
    EXPECT_THAT(cell::testing::ReadFile(dir_ + "/recv-" + l.station + ".out"),
                HasSubstr(fmt::format("stored {}:P77 revision 2", l.station)));
    EXPECT_EQ(Show("P77", l.station).value("revision", 0), 2);
    RunResult got = Ctl({"program", "get", "P77", "--node", l.station});
    EXPECT_EQ(got.out, punched);

    // The same punched with byte 120 damaged (its low bit flipped: the parity is wrong): exit 1 naming the
    // device and the byte, and the store keeps revision 2.
    ForgetStates();
    recv = CtlInBackground({"dnc", "receive", l.station, "P77"}, "bad-" + l.station);
    ASSERT_TRUE(WaitState(l.station, cell::DNC_RECEIVING));
    test::SimOptions so = Sim(l);
    so.damage_at = 120;
    test::SimControl bad(*ptys_[l.station], so);
    bad.StartPunching(Encode(FormatOf(l), punched));
    code = recv->Wait(std::chrono::seconds(60));
    bad.Stop();
    EXPECT_EQ(code, std::optional<int>(1));
    const std::string err = cell::testing::ReadFile(dir_ + "/bad-" + l.station + ".err");
    EXPECT_THAT(err, HasSubstr(fmt::format("device {}: byte 120: parity", ptys_[l.station]->slave())));
    EXPECT_THAT(err, HasSubstr("nothing stored"));
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_EQ(Show("P77", l.station).value("revision", 0), 2);
  }
}

TEST_F(DncTest, AKilledDncMidReceiveStoresNothingAndARestartedOneServesAgain) {
  Put("P88", "KT01", Program("%", 3));
  ForgetStates();
  auto recv = CtlInBackground({"dnc", "receive", "KT01", "P88"}, "recv");
  ASSERT_TRUE(WaitState("KT01", cell::DNC_RECEIVING));
  test::SimOptions so = Sim(kKt);
  so.stop_after = 400;  // the control punches 400 bytes and pauses, the line up
  test::SimControl sim(*ptys_["KT01"], so);
  sim.StartPunching(Encode(FormatOf(kKt), Program("%", 60)));
  ASSERT_TRUE(WaitState("KT01", cell::DNC_RECEIVING, 100));  // the state follows within a second
  dnc_["KT01"]->Signal(SIGKILL);
  ASSERT_TRUE(dnc_["KT01"]->Wait(std::chrono::seconds(10)).has_value());
  // cellctl hears the process go (its heartbeat ends) and says so.
  auto code = recv->Wait(std::chrono::seconds(30));
  EXPECT_EQ(code, std::optional<int>(1));
  EXPECT_THAT(cell::testing::ReadFile(dir_ + "/recv.err"),
              HasSubstr("cell-dnc/KT01 stopped during the transfer"));
  sim.Stop();
  EXPECT_EQ(Show("P88", "KT01").value("revision", 0), 1);
  EXPECT_EQ(Ctl({"program", "get", "P88", "--node", "KT01"}).out, Program("%", 3));

  StartDnc(kKt);
  RunResult r;
  std::vector<uint8_t> wire = SendTo(kKt, "P88", r);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(wire, Encode(FormatOf(kKt), Program("%", 3)));
}

// Issue 42 item 5: a kill -9 of cell-dnc during `dnc send`. cellctl exits 1 with one line, the store is as it
// was (the same revision, the same bytes), the page shows the line without its process, and a restarted
// cell-dnc sends the program again byte-exact. The kill comes once the control has pulled bytes off the line
// (no fixed sleep).
TEST_F(DncTest, AKilledDncMidSendLeavesTheStoreAsItWasAndARestartedOneSendsAgain) {
  const std::string text = Program("%", 150);  // about 5 KB: 5 s at 960 bytes/s
  Put("P99", "KT01", text);
  const nlohmann::json before = Show("P99", "KT01");
  Dashboard page(*bus_);
  {
    test::SimControl sim(*ptys_["KT01"], Sim(kKt));
    sim.StartReading();
    auto send = CtlInBackground({"dnc", "send", "KT01", "P99"}, "send");
    ASSERT_TRUE(cell::bus::WaitUntil([&] { return sim.pulled() >= 300; }, std::chrono::seconds(30)))
        << cell::testing::ReadFile(dir_ + "/send.err");
    dnc_["KT01"]->Signal(SIGKILL);
    ASSERT_TRUE(dnc_["KT01"]->Wait(std::chrono::seconds(10)).has_value());
    auto code = send->Wait(std::chrono::seconds(30));
    EXPECT_EQ(code, std::optional<int>(1));
    const std::string err = cell::testing::ReadFile(dir_ + "/send.err");
    EXPECT_THAT(err, HasSubstr("cell-dnc/KT01 stopped during the transfer"));
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    sim.Stop();
    EXPECT_LT(sim.wire().size(), Encode(FormatOf(kKt), text).size());  // it was cut short
  }
  // The page: KT01's line has no process (its last state said "sending").
  nlohmann::json row;
  EXPECT_TRUE(page.WaitRow(
      "KT01", [](const nlohmann::json& r) { return r["state"] == "offline"; }, &row))
      << row;
  // The store: a send reads, never writes, and a killed one leaves nothing behind.
  const nlohmann::json after = Show("P99", "KT01");
  EXPECT_EQ(after.value("revision", 0), before.value("revision", -1));
  EXPECT_EQ(after.value("size", 0), before.value("size", -1));
  EXPECT_EQ(Ctl({"program", "get", "P99", "--node", "KT01"}).out, text);

  StartDnc(kKt);
  RunResult r;
  std::vector<uint8_t> wire = SendTo(kKt, "P99", r);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(wire, Encode(FormatOf(kKt), text));
  EXPECT_TRUE(page.WaitRow(
      "KT01", [&](const nlohmann::json& x) { return x["state"] == "idle" && x["bytes"] == wire.size(); },
      &row))
      << row;
}

TEST_F(DncTest, DripKeepsASmallControlBufferFedWhileTheControlExecutes) {
  // 150 blocks (about 5 KB), 20 times the control's 256-byte buffer, which it empties at 3/4 of the line
  // rate and with a 50 ms pause every 512 bytes (a long block): the cell must stop and go on with every
  // XOFF/XON.
  const std::string big = Program("%", 150);
  Put("BIG", "HOST", big);
  test::SimOptions so = Sim(kKt);
  so.exec_bytes_per_s = so.line_bytes_per_s * 0.75;
  so.pause_every = 512;
  so.pause_s = 0.05;
  test::SimControl sim(*ptys_["KT01"], so);
  sim.StartReading();
  Dashboard page(*bus_);
  const uint64_t total = Encode(FormatOf(kKt), big).size();
  ForgetStates();
  auto drip = CtlInBackground({"dnc", "drip", "KT01", "BIG"}, "drip");
  EXPECT_TRUE(WaitState("KT01", cell::DNC_DRIPPING, 1000));  // under way, as `dnc status` shows it
  // The page shows it too: dripping, bytes done of the total, a rate.
  nlohmann::json row;
  EXPECT_TRUE(page.WaitRow(
      "KT01",
      [](const nlohmann::json& r) { return r["state"] == "dripping" && r["bytes"].get<int>() >= 1000; },
      &row))
      << row;
  EXPECT_EQ(row["total"], total);
  EXPECT_EQ(row["program"], "HOST:BIG");
  EXPECT_GT(row["rate"].get<double>(), 0.0);
  auto code = drip->Wait(std::chrono::seconds(90));
  // A drip that failed or hangs never sends the end of data the control waits for: stop it, and say why.
  if (code != std::optional<int>(0)) sim.Stop();
  sim.Join();
  ASSERT_EQ(code, std::optional<int>(0))
      << cell::testing::ReadFile(dir_ + "/drip.err") << cell::testing::ReadFile(dir_ + "/drip.out")
      << " control: " << sim.error() << ", " << sim.wire().size() << " bytes read, " << sim.xoffs()
      << " XOFFs";
  EXPECT_THAT(cell::testing::ReadFile(dir_ + "/drip.out"), HasSubstr("dripped HOST:BIG to KT01"));
  EXPECT_EQ(sim.error(), "");
  EXPECT_EQ(sim.lost(), 0u);
  EXPECT_GT(sim.xoffs(), 10u);
  EXPECT_LE(sim.max_fill(), 256u);
  EXPECT_EQ(sim.text(), big);
  EXPECT_EQ(sim.wire(), Encode(FormatOf(kKt), big));
  EXPECT_TRUE(page.WaitRow(
      "KT01", [&](const nlohmann::json& r) { return r["state"] == "idle" && r["bytes"] == total; }, &row))
      << row;
  EXPECT_EQ(row["stalls"], sim.xoffs());
  EXPECT_EQ(row["errors"], 0);
}

TEST_F(DncTest, StatusListsEveryLineAndOneWithoutAProcessAsSuch) {
  Put("S1", "KT01", Program("%", 10));
  RunResult r;
  std::vector<uint8_t> wire = SendTo(kKt, "S1", r);
  ASSERT_EQ(r.code, 0) << r.err;
  r = Ctl({"dnc", "status", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  std::map<std::string, nlohmann::json> rows;
  for (auto& row : nlohmann::json::parse(r.out)) rows[row["station"]] = row;
  ASSERT_EQ(rows.size(), 3u) << r.out;
  EXPECT_EQ(rows["KT01"]["dnc"], true);
  EXPECT_EQ(rows["KT01"]["state"], "idle");
  EXPECT_EQ(rows["KT01"]["device"], ptys_["KT01"]->slave());
  EXPECT_EQ(rows["KT01"]["program"], "KT01:S1");
  EXPECT_EQ(rows["KT01"]["bytes"], wire.size());
  EXPECT_EQ(rows["KT01"]["transfers"], 1);
  EXPECT_EQ(rows["KT01"]["errors"], 0);
  EXPECT_GT(rows["KT01"]["rate"].get<double>(), 0.0);
  EXPECT_EQ(rows["EM01"]["state"], "idle");
  EXPECT_EQ(rows["EM01"]["transfers"], 0);
  EXPECT_EQ(rows["OK01"]["dnc"], false);
  EXPECT_EQ(rows["OK01"]["state"], "no DNC process");
  // A station without a [serial] table has no line: one line, exit 1.
  r = Ctl({"dnc", "send", "KT02", "S1"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("station KT02 has no [serial] table"));
}

// `cellctl up` checks every [serial] line as cell-dnc would before it starts anything: EM01 at 9600 baud
// (the EMCOTRONIC accepts 150-4800, ln 5315, alarm 870 ln 7225) is refused in one line, nothing runs.
TEST(DncUp, ABadSerialLineIsRefusedBeforeAnythingStarts) {
  const std::string dir = cell::testing::MakeTempDir("cell-dnc-up-");
  fs::copy(cell::testing::SourceDir() + "/deploy", dir + "/config", fs::copy_options::recursive);
  std::ofstream(dir + "/config/stations/EM01.toml", std::ios::app)
      << "\n[serial]\ndevice = \"/dev/ttyS0\"\nbaud = 9600\n";
  const std::map<std::string, std::string> env{{"CELL_CONFIG_DIR", dir + "/config"},
                                               {"CELL_DATA_DIR", dir + "/data"}};
  const auto start = std::chrono::steady_clock::now();
  RunResult r = cell::testing::RunCommand({cell::testing::BinDir() + "/cellctl", "up", "--stations", "EM01"},
                                          env, std::chrono::seconds(60));
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("EM01.toml: [serial] baud = 9600"));
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  EXPECT_FALSE(fs::exists(dir + "/data/cell-up.json"));
  fs::remove_all(dir);
}

}  // namespace
