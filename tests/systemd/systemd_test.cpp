// The cell's systemd deployment (deploy/systemd, deploy/install), checked without systemd as PID 1.
//
// Binaries: each unit's ExecStart names /usr/local/bin/<service>. The tests use the real executable in
// $CELL_BIN_DIR when it has been built, else the stand-in cell-daemon-probe (the smallest service on
// cell_daemon), and say which on stdout ("[binary] ..."), so a green run tells what it covered.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "cell/config/units.h"
#include "cell/daemon/notify_listener.h"

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cell::daemon::testing::NotifyListener;

namespace {

struct Unit {
  std::string file;     // e.g. "cell-interpreter@.service"
  std::string service;  // the executable, e.g. "cell-interpreter"
  bool station;         // a per-station template
};
const std::vector<Unit> kUnits = {
    {"cell-program-store.service", "cell-program-store", false},
    {"cell-scheduler.service", "cell-scheduler", false},
    {"cell-inspection-writer.service", "cell-inspection-writer", false},
    {"cell-dashboard.service", "cell-dashboard", false},
    {"cell-interpreter@.service", "cell-interpreter", true},
    {"cell-axis-servo@.service", "cell-axis-servo", true},
    {"cell-dnc@.service", "cell-dnc", true},
};

std::string EnvOr(const char* name, const std::string& fallback) {
  const char* v = getenv(name);
  return v != nullptr && *v != '\0' ? v : fallback;
}
fs::path SourceDir() {
  return EnvOr("CELL_SOURCE_DIR", CELL_SOURCE_DIR_FALLBACK);
}
fs::path UnitDir() {
  return SourceDir() / "deploy" / "systemd";
}
fs::path BinDir() {
  return EnvOr("CELL_BIN_DIR", "");
}

// The executable standing for `service`: the real one if built, else the probe.
fs::path BinaryFor(const std::string& service) {
  fs::path real = BinDir() / service;
  if (!BinDir().empty() && fs::exists(real)) {
    std::cout << "[binary] " << service << ": real executable " << real << "\n";
    return real;
  }
  std::cout << "[binary] " << service << ": not built yet; stand-in " << CELL_DAEMON_PROBE << "\n";
  return CELL_DAEMON_PROBE;
}

struct ShellResult {
  int status = -1;
  std::string output;  // stdout and stderr
};
ShellResult Shell(const std::string& cmd) {
  ShellResult r;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (p == nullptr) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
  int st = pclose(p);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}
std::string Quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// `text` with the first occurrence of the line starting with `prefix` replaced by `line`. (No
// std::regex: GCC 12 warns inside it under the sanitizer build.)
std::string ReplaceLine(std::string text, const std::string& prefix, const std::string& line) {
  size_t at = text.find("\n" + prefix);
  if (at == std::string::npos) throw std::runtime_error("no line " + prefix);
  size_t end = text.find('\n', at + 1);
  return text.replace(at + 1, end - at - 1, line);
}

std::string ReadFile(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
void WriteFile(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

class TempDir {
 public:
  TempDir() {
    char tmpl[] = "/tmp/cell-systemd-test-XXXXXX";
    if (mkdtemp(tmpl) == nullptr) throw std::runtime_error("mkdtemp");
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// systemd-analyze verify: rc 0 and not a single line of output (warnings such as unknown keys or
// missing man pages do not change the exit code, so any output fails the check).
void ExpectVerifies(const std::string& args) {
  ShellResult r = Shell("SYSTEMD_LOG_COLOR=0 systemd-analyze verify --man=no " + args);
  EXPECT_EQ(r.status, 0) << "systemd-analyze verify " << args << "\n" << r.output;
  EXPECT_EQ(r.output, "") << "systemd-analyze verify " << args;
}

std::string VerifyArgs(const fs::path& dir) {
  std::string args = Quote((dir / "cell.target").string());
  for (const auto& u : kUnits) {
    if (u.station) {
      for (const char* id : {"KT01", "OK01"}) {
        args += " " + Quote((dir / cell::config::UnitName(u.file, id)).string());
      }
    } else {
      args += " " + Quote((dir / u.file).string());
    }
  }
  return args;
}

// Copies of the units with ExecStart pointing at existing executables.
void CopyUnits(const fs::path& dir) {
  fs::copy_file(UnitDir() / "cell.target", dir / "cell.target");
  for (const auto& u : kUnits) {
    std::string text = ReadFile(UnitDir() / u.file);
    std::string install_path = "/usr/local/bin/" + u.service;
    size_t at = text.find("ExecStart=" + install_path);
    ASSERT_NE(at, std::string::npos) << u.file << " has no ExecStart=" << install_path;
    text.replace(at + 10, install_path.size(), BinaryFor(u.service).string());
    WriteFile(dir / u.file, text);
  }
}

TEST(Units, DeclareTheCellPolicy) {
  const std::map<std::string, std::string> kService = {
      {"Type", "notify"},
      {"NotifyAccess", "main"},
      {"WatchdogSec", "10"},
      {"Restart", "on-failure"},
      {"RestartSec", "1"},
      {"StateDirectory", "cell"},
      {"User", "cell"},
      {"ProtectSystem", "strict"},
      {"ProtectHome", "yes"},
      {"NoNewPrivileges", "yes"},
      {"PrivateTmp", "yes"},
      {"ProtectKernelTunables", "yes"},
      {"ProtectControlGroups", "yes"},
      {"ReadWritePaths", "/var/lib/cell"},
      {"EnvironmentFile", "-/etc/cell/cell.env"},
  };
  for (const auto& u : kUnits) {
    SCOPED_TRACE(u.file);
    auto unit = cell::config::ParseUnitFile(UnitDir() / u.file);
    for (const auto& [k, v] : kService) EXPECT_EQ(unit.Value("Service", k), v) << k;
    EXPECT_EQ(unit.Value("Unit", "PartOf"), "cell.target");
    EXPECT_EQ(unit.Value("Install", "WantedBy"), "cell.target");
    auto families = cell::config::SplitWords(unit.Value("Service", "RestrictAddressFamilies").value_or(""));
    std::set<std::string> fam(families.begin(), families.end());
    for (const char* f : {"AF_UNIX", "AF_INET", "AF_INET6"}) EXPECT_TRUE(fam.contains(f)) << f;
    auto env = cell::config::EnvironmentFor(UnitDir() / u.file, u.station ? "KT01" : "");
    std::map<std::string, std::string> envmap(env.begin(), env.end());
    EXPECT_EQ(envmap["CELL_DATA_DIR"], "/var/lib/cell");
    EXPECT_EQ(envmap["CELL_CONFIG_DIR"], "/etc/cell");
    std::vector<std::string> want = {"/usr/local/bin/" + u.service};
    if (u.station) want.insert(want.end(), {"--station", "KT01"});
    EXPECT_EQ(cell::config::ExecStartFor(UnitDir() / u.file, "KT01", ""), want);
  }
}

TEST(Verify, UnitsPointingAtTheBuildTree) {
  ASSERT_EQ(Shell("command -v systemd-analyze").status, 0)
      << "systemd-analyze missing: run deploy/install-deps";
  TempDir tmp;
  CopyUnits(tmp.path());
  ExpectVerifies(VerifyArgs(tmp.path()));
}

// The check above is only worth something if verify complains about broken units: show that it does.
TEST(Verify, CatchesBrokenUnits) {
  TempDir tmp;
  CopyUnits(tmp.path());
  fs::path f = tmp.path() / "cell-scheduler.service";
  std::string good = ReadFile(f);
  WriteFile(f, ReplaceLine(good, "WatchdogSec=", "WatchdogSecs=10"));
  ShellResult typo = Shell("systemd-analyze verify --man=no " + Quote(f.string()));
  EXPECT_NE(typo.output.find("Unknown key 'WatchdogSecs'"), std::string::npos) << typo.output;
  WriteFile(f, ReplaceLine(good, "ExecStart=", "ExecStart=/nonexistent/cell-scheduler"));
  ShellResult missing = Shell("systemd-analyze verify --man=no " + Quote(f.string()));
  EXPECT_NE(missing.status, 0);
  EXPECT_NE(missing.output.find("is not executable"), std::string::npos) << missing.output;
}

// deploy/install into a --destdir with another --prefix, then verify the installed units there (with
// --root, and the host's system units copied in so that default dependencies resolve).
TEST(Install, DestdirPrefixIdempotentAndVerified) {
  TempDir tmp;
  fs::path build = tmp.path() / "build", dest = tmp.path() / "root";
  for (const auto& u : kUnits) {
    fs::create_directories(build / "bin");
    fs::copy_file(BinaryFor(u.service), build / "bin" / u.service);
  }
  fs::copy_file(CELL_DAEMON_PROBE, build / "bin" / "scheduler_bench");  // not a cell executable
  const std::string cmd = Quote((SourceDir() / "deploy" / "install").string()) +
                          " --prefix /opt/cell --destdir " + Quote(dest.string()) + " --build-dir " +
                          Quote(build.string());
  ShellResult first = Shell(cmd);
  ASSERT_EQ(first.status, 0) << first.output;
  for (const auto& u : kUnits) {
    SCOPED_TRACE(u.file);
    EXPECT_TRUE(fs::exists(dest / "opt/cell/bin" / u.service));
    std::string unit = ReadFile(dest / "etc/systemd/system" / u.file);
    EXPECT_NE(unit.find("ExecStart=/opt/cell/bin/" + u.service), std::string::npos);
    EXPECT_EQ(unit.find("/usr/local"), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(dest / "opt/cell/bin/scheduler_bench"));
  EXPECT_TRUE(fs::exists(dest / "etc/systemd/system/cell.target"));
  for (const char* id : {"BS01", "EM01", "KT01", "KT02", "KT03", "KT04", "OK01"}) {
    EXPECT_EQ(ReadFile(dest / "etc/cell/stations" / (std::string(id) + ".toml")),
              ReadFile(SourceDir() / "deploy/stations" / (std::string(id) + ".toml")));
  }
  EXPECT_TRUE(fs::exists(dest / "etc/cell/cell.env"));
  for (const char* f : {"lan.fastdds.xml", "lan.cyclonedds.xml", "lan-multicast.fastdds.xml",
                        "lan-multicast.cyclonedds.xml", "fastdds.env", "cyclonedds.env"})
    EXPECT_EQ(ReadFile(dest / "etc/cell/dds" / f), ReadFile(SourceDir() / "deploy/dds" / f)) << f;

  ShellResult again = Shell(cmd);
  ASSERT_EQ(again.status, 0) << again.output;
  EXPECT_EQ(again.output.find("  installed "), std::string::npos) << again.output;
  EXPECT_NE(again.output.find("everything was up to date"), std::string::npos) << again.output;

  // A locally edited station file is kept; the shipped one lands beside it.
  fs::path kt01 = dest / "etc/cell/stations/KT01.toml";
  WriteFile(kt01, ReadFile(kt01) + "# site edit\n");
  ShellResult edited = Shell(cmd);
  ASSERT_EQ(edited.status, 0) << edited.output;
  EXPECT_NE(ReadFile(kt01).find("# site edit"), std::string::npos);
  EXPECT_EQ(ReadFile(dest / "etc/cell/stations/KT01.toml.dist"),
            ReadFile(SourceDir() / "deploy/stations/KT01.toml"));

  fs::create_directories(dest / "usr/lib/systemd");
  ShellResult cp = Shell("cp -a /usr/lib/systemd/system " + Quote((dest / "usr/lib/systemd").string()));
  ASSERT_EQ(cp.status, 0) << cp.output;
  // One unit on the other DDS stack, as docs/operations.md §8.2 says: a drop-in reading a shipped env file.
  fs::create_directories(dest / "etc/systemd/system/cell-scheduler.service.d");
  WriteFile(dest / "etc/systemd/system/cell-scheduler.service.d/dds.conf",
            "[Service]\nEnvironmentFile=/etc/cell/dds/cyclonedds.env\n");
  std::string names = "cell.target";
  for (const auto& u : kUnits) names += " " + (u.station ? cell::config::UnitName(u.file, "KT03") : u.file);
  ExpectVerifies("--root=" + Quote(dest.string()) + " " + names);

  ShellResult bad =
      Shell(Quote((SourceDir() / "deploy" / "install").string()) + " --prefix relative --destdir " +
            Quote(dest.string()) + " --build-dir " + Quote(build.string()));
  EXPECT_NE(bad.status, 0);
}

// Each unit's own command line (as `cellctl up` runs it: install path mapped to the build tree, %i to the
// station) under a test-owned NOTIFY_SOCKET with WATCHDOG_USEC=200000: READY=1, at least two WATCHDOG=1,
// and after SIGTERM, STOPPING=1 and exit code 0. (The dashboard listens on any free port: CELL_HTTP.)
// A configuration directory whose KT01 has a [serial] table on a pseudo-terminal, for cell-dnc@KT01 (a
// station without one has no DNC line; docs/dnc.md).
class SerialStation {
 public:
  explicit SerialStation(const fs::path& dir) {
    master_ = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (master_ < 0 || grantpt(master_) != 0 || unlockpt(master_) != 0)
      throw std::runtime_error("posix_openpt");
    fs::copy(SourceDir() / "deploy", dir, fs::copy_options::recursive);
    std::ofstream(dir / "stations" / "KT01.toml", std::ios::app)
        << "\n[serial]\ndevice = \"" << ptsname(master_) << "\"\n";
  }
  ~SerialStation() { close(master_); }

 private:
  int master_ = -1;
};

TEST(Notify, EveryUnitCommandLineIsReadyWatchdogAndStops) {
  TempDir data;
  SerialStation serial(data.path() / "config-serial");
  for (const auto& u : kUnits) {
    SCOPED_TRACE(u.file);
    bool needs_serial = cell::config::ParseUnitFile(UnitDir() / u.file).Value("Unit", "X-CellStationTable") ==
                        std::optional<std::string>("serial");
    fs::path config = needs_serial ? data.path() / "config-serial" : SourceDir() / "deploy";
    std::vector<std::string> argv = cell::config::ExecStartFor(UnitDir() / u.file, "KT01", BinDir());
    fs::path chosen = BinaryFor(u.service);  // reports which binary runs
    if (!fs::exists(argv[0])) argv[0] = chosen;
    NotifyListener l;
    pid_t pid = cell::daemon::testing::Spawn(argv, {{"NOTIFY_SOCKET", l.path().string()},
                                                    {"WATCHDOG_USEC", "200000"},
                                                    {"WATCHDOG_PID", "self"},
                                                    {"CELL_DATA_DIR", (data.path() / u.service).string()},
                                                    {"CELL_HTTP", "127.0.0.1:0"},
                                                    {"CELL_CONFIG_DIR", config.string()}});
    std::vector<std::string> seen;
    bool ready = l.WaitFor("READY=1", 30s, seen);
    EXPECT_TRUE(ready) << argv[0] << ": no READY=1 within 30 s (READY must not wait for other services)";
    if (ready) {
      EXPECT_TRUE(l.WaitFor("WATCHDOG=1", 3s, seen)) << argv[0] << ": no first WATCHDOG=1";
      EXPECT_TRUE(l.WaitFor("WATCHDOG=1", 3s, seen)) << argv[0] << ": no second WATCHDOG=1";
    }
    kill(pid, SIGTERM);
    if (ready) {
      EXPECT_TRUE(l.WaitFor("STOPPING=1", 10s, seen)) << argv[0] << ": no STOPPING=1 after SIGTERM";
    }
    auto status = cell::daemon::testing::WaitExit(pid, 15s);
    ASSERT_TRUE(status.has_value()) << argv[0] << ": still running 15 s after SIGTERM (killed)";
    EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << argv[0] << ": wait status " << *status;
  }
}

}  // namespace
