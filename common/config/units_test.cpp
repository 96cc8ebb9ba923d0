#include "cell/config/units.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>

#include "cell/error/error.h"

namespace fs = std::filesystem;
using cell::config::ExecStartFor;
using Argv = std::vector<std::string>;

namespace {

fs::path UnitDir() {
  const char* src = getenv("CELL_SOURCE_DIR");
  if (src == nullptr) throw std::runtime_error("run under ctest (CELL_SOURCE_DIR)");
  return fs::path(src) / "deploy" / "systemd";
}

class TempUnit : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/cell-units-test-XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  fs::path dir_;
};

TEST(RealUnits, HostServices) {
  for (const char* name : {"cell-program-store", "cell-scheduler", "cell-inspection-writer"}) {
    EXPECT_EQ(ExecStartFor(UnitDir() / (std::string(name) + ".service"), "", "/b/bin"),
              (Argv{std::string("/b/bin/") + name}));
    // Without a bin dir: the install path.
    EXPECT_EQ(ExecStartFor(UnitDir() / (std::string(name) + ".service"), "", ""),
              (Argv{std::string("/usr/local/bin/") + name}));
  }
}

TEST(RealUnits, StationTemplates) {
  EXPECT_EQ(ExecStartFor(UnitDir() / "cell-interpreter@.service", "KT01", "/w/build/bin"),
            (Argv{"/w/build/bin/cell-interpreter", "--station", "KT01"}));
  EXPECT_EQ(ExecStartFor(UnitDir() / "cell-axis-servo@.service", "OK01", "/w/build/bin"),
            (Argv{"/w/build/bin/cell-axis-servo", "--station", "OK01"}));
  EXPECT_THROW(ExecStartFor(UnitDir() / "cell-axis-servo@.service", "", "/w/build/bin"), cell::Error);
}

TEST(RealUnits, Environment) {
  auto env = cell::config::EnvironmentFor(UnitDir() / "cell-interpreter@.service", "KT02");
  using Env = std::vector<std::pair<std::string, std::string>>;
  EXPECT_EQ(env, (Env{{"CELL_DATA_DIR", "/var/lib/cell"}, {"CELL_CONFIG_DIR", "/etc/cell"}}));
  auto unit = cell::config::ParseUnitFile(UnitDir() / "cell-scheduler.service");
  EXPECT_EQ(unit.Value("Service", "Type"), "notify");
  EXPECT_EQ(unit.Value("Service", "WatchdogSec"), "10");
  EXPECT_EQ(unit.Value("Install", "WantedBy"), "cell.target");
}

TEST(RealUnits, CellCommandsForTwoStations) {
  auto cmds = cell::config::CellCommands(UnitDir(), {"KT01", "KT02"}, "/b");
  std::vector<std::string> units;
  for (const auto& c : cmds) units.push_back(c.unit);
  EXPECT_EQ(units,
            (Argv{"cell-dashboard.service", "cell-inspection-writer.service", "cell-program-store.service",
                  "cell-scheduler.service", "cell-axis-servo@KT01.service", "cell-interpreter@KT01.service",
                  "cell-axis-servo@KT02.service", "cell-interpreter@KT02.service"}));
  EXPECT_EQ(cmds[7].argv, (Argv{"/b/cell-interpreter", "--station", "KT02"}));
  EXPECT_EQ(cmds[2].argv, (Argv{"/b/cell-program-store"}));
  EXPECT_THROW(cell::config::CellCommands("/nonexistent", {}, "/b"), cell::Error);
  // cell-dnc@ runs for the stations with a [serial] table only.
  auto with_serial = [](const std::string& station, const std::string& table) {
    return station == "EM01" && table == "serial";
  };
  units.clear();
  for (const auto& c : cell::config::CellCommands(UnitDir(), {"KT01", "EM01"}, "/b", with_serial))
    units.push_back(c.unit);
  EXPECT_EQ(units,
            (Argv{"cell-dashboard.service", "cell-inspection-writer.service", "cell-program-store.service",
                  "cell-scheduler.service", "cell-axis-servo@KT01.service", "cell-interpreter@KT01.service",
                  "cell-axis-servo@EM01.service", "cell-dnc@EM01.service", "cell-interpreter@EM01.service"}));
}

TEST_F(TempUnit, QuotingSpecifiersVariablesAndContinuation) {
  auto unit = Write("x-demo@.service", R"(# comment
[Unit]
Description=demo
; another comment
[Service]
Environment="GREETING=hello world" MODE=fast
Environment=ARGS=-v\s-q
ExecStart=
ExecStart=-/opt/cell/bin/x-demo --station %i \
  # skipped comment inside a continuation
  --unit %n --name "%p %I" 'single q' --pct 100%% \
  --greet ${GREETING} $ARGS --mode=${MODE} ${UNSET}x
)");
  EXPECT_EQ(ExecStartFor(unit, "KT03", "/b"),
            (Argv{"/b/x-demo", "--station", "KT03", "--unit", "x-demo@KT03.service", "--name", "x-demo KT03",
                  "single q", "--pct", "100%", "--greet", "hello world", "-v", "-q", "--mode=fast", "x"}));
  EXPECT_EQ(cell::config::UnitName(unit, "KT03"), "x-demo@KT03.service");
}

TEST_F(TempUnit, EmptyAssignmentResetsAndMultipleIsAnError) {
  auto reset = Write("a.service", "[Service]\nExecStart=/bin/one\nExecStart=\nExecStart=/bin/two x\n");
  EXPECT_EQ(ExecStartFor(reset, "", "/b"), (Argv{"/b/two", "x"}));
  auto two = Write("b.service", "[Service]\nExecStart=/bin/one\nExecStart=/bin/two\n");
  EXPECT_THROW(ExecStartFor(two, "", "/b"), cell::Error);
  auto none = Write("c.service", "[Service]\nType=simple\n");
  EXPECT_THROW(ExecStartFor(none, "", "/b"), cell::Error);
}

TEST_F(TempUnit, MalformedInputIsAnError) {
  EXPECT_THROW(cell::config::ParseUnitFile(dir_ / "missing.service"), cell::Error);
  EXPECT_THROW(cell::config::ParseUnitFile(Write("d.service", "ExecStart=/bin/x\n")), cell::Error);
  EXPECT_THROW(cell::config::ParseUnitFile(Write("e.service", "[Service]\njust words\n")), cell::Error);
  EXPECT_THROW(ExecStartFor(Write("f.service", "[Service]\nExecStart=/bin/x \"open\n"), "", ""), cell::Error);
  EXPECT_THROW(ExecStartFor(Write("g.service", "[Service]\nExecStart=/bin/x %H\n"), "", ""), cell::Error);
}

TEST(SplitWords, SystemdQuoting) {
  EXPECT_EQ(cell::config::SplitWords("  a  \"b c\" 'd \"e\"' f\\x41 g\\\\ "),
            (Argv{"a", "b c", "d \"e\"", "fA", "g\\"}));
  EXPECT_EQ(cell::config::SplitWords(""), Argv{});
  EXPECT_THROW(cell::config::SplitWords("\"a\"b"), cell::Error);
  EXPECT_THROW(cell::config::SplitWords("a\\q"), cell::Error);
}

}  // namespace
