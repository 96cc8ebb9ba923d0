// cellctl up|down|watch: a local cell from the systemd units' own command lines.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "cell/bus/topics.h"
#include "cell/config/config.h"
#include "cell/config/units.h"
#include "context.h"

namespace cellctl {

namespace fs = std::filesystem;

namespace {

fs::path PidFile() {
  return cell::config::DataDir() / "cell-up.json";
}

bool Alive(pid_t pid) {
  return pid > 0 && kill(pid, 0) == 0;
}

// The service id a process announces: "<exe>" or "<exe>/<station>".
std::string ServiceId(const std::vector<std::string>& argv) {
  std::string id = fs::path(argv[0]).filename().string();
  for (size_t i = 1; i + 1 < argv.size(); ++i)
    if (argv[i] == "--station") id += "/" + argv[i + 1];
  return id;
}

std::vector<std::string> Split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string x; std::getline(ss, x, ',');)
    if (!x.empty()) out.push_back(x);
  return out;
}

std::string LastLine(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

pid_t Launch(const std::vector<std::string>& argv, const fs::path& log, const std::string& clock) {
  pid_t pid = fork();
  if (pid < 0) throw cell::Error(cell::Errc::kInternal, "fork failed");
  if (pid == 0) {
    setsid();  // its own session: survives cellctl, stopped by `cellctl down`
    int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    int null = open("/dev/null", O_RDONLY);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
    }
    if (null >= 0) dup2(null, 0);
    setenv("CELL_CLOCK", clock.c_str(), 1);
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  return pid;
}

void StopAll(const nlohmann::json& procs) {
  for (auto& p : procs) {
    pid_t pid = p["pid"].get<int>();
    if (Alive(pid)) kill(pid, SIGTERM);
  }
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  for (auto& p : procs) {
    pid_t pid = p["pid"].get<int>();
    while (Alive(pid) && std::chrono::steady_clock::now() < deadline) {
      waitpid(pid, nullptr, WNOHANG);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (Alive(pid)) kill(pid, SIGKILL);
    waitpid(pid, nullptr, WNOHANG);
  }
}

}  // namespace

void AddCellVerbs(CLI::App& app, Context& ctx) {
  struct Opts {
    std::string stations = "KT01,KT02";
    std::string clock = "real";
    int count = 0;
  };
  auto o = std::make_shared<Opts>();

  auto* up = app.add_subcommand("up", "start a local cell from the systemd units' command lines");
  up->add_option("--stations", o->stations, "comma-separated station ids (default KT01,KT02)");
  up->add_option("--clock", o->clock, "real or virtual machine clock")
      ->check(CLI::IsMember({"real", "virtual"}));
  up->callback([o, &ctx] {
    auto stations = Split(o->stations);
    if (stations.empty()) throw Exit{2, "--stations names no station"};
    for (auto& s : stations) cell::config::LoadStation(s);  // unknown station: a clear error now
    if (fs::exists(PidFile())) {
      std::ifstream in(PidFile());
      auto old = nlohmann::json::parse(in, nullptr, false);
      if (old.is_array())
        for (auto& p : old)
          if (Alive(p["pid"].get<int>()))
            throw Exit{1, "a local cell is already running (cellctl down first)"};
    }
    fs::path bin = fs::read_symlink("/proc/self/exe").parent_path();
    auto commands =
        cell::config::CellCommands(cell::config::SourceTreeDir() / "deploy/systemd", stations, bin);
    fs::path logs = cell::config::DataDir() / "logs";
    fs::create_directories(logs);
    nlohmann::json procs = nlohmann::json::array();
    cell::health::Liveness live(ctx.Bus());
    for (auto& c : commands) {
      fs::path log = logs / (c.unit + ".log");
      pid_t pid = Launch(c.argv, log, o->clock);
      procs.push_back(
          {{"unit", c.unit}, {"pid", pid}, {"service", ServiceId(c.argv)}, {"log", log.string()}});
    }
    std::ofstream(PidFile()) << procs.dump(2);
    // Ready = every process announced itself READY on the bus, within 30 s.
    std::vector<std::string> missing;
    bool ok = bus::WaitUntil(
        [&] {
          missing.clear();
          for (auto& p : procs) {
            if (!Alive(p["pid"].get<int>())) {
              missing.push_back(p["unit"].get<std::string>() +
                                " exited: " + LastLine(p["log"].get<std::string>()));
              return true;  // no point waiting
            }
            if (!live.Online(p["service"].get<std::string>()))
              missing.push_back(p["unit"].get<std::string>());
          }
          return missing.empty();
        },
        bus::Millis(30000));
    if (!ok || !missing.empty()) {
      StopAll(procs);
      fs::remove(PidFile());
      std::string what;
      for (auto& m : missing) what += (what.empty() ? "" : "; ") + m;
      throw Exit{1, "cell did not come up: " + what};
    }
    std::cout << "cell up on domain " << ctx.Bus().domain() << ": " << procs.size() << " processes ready ("
              << o->clock << " clock), logs in " << logs.string() << "\n";
  });

  auto* down = app.add_subcommand("down", "stop the local cell (SIGTERM, then SIGKILL after 10 s)");
  down->callback([] {
    if (!fs::exists(PidFile())) {
      std::cout << "no local cell is running\n";
      return;
    }
    std::ifstream in(PidFile());
    auto procs = nlohmann::json::parse(in, nullptr, false);
    if (!procs.is_array()) throw Exit{1, PidFile().string() + " is not a cellctl process list"};
    StopAll(procs);
    fs::remove(PidFile());
    std::cout << "cell down: " << procs.size() << " processes stopped\n";
  });

  auto* watch = app.add_subcommand("watch", "live view of stations (Ctrl-C to stop)");
  watch->add_option("--count", o->count, "stop after N refreshes (0: never)");
  watch->callback([o, &ctx] {
    bus::Reader<cell::StationStatus> r(ctx.Bus(), bus::topics::kStationStatus, bus::QosKind::kState);
    std::map<std::string, cell::StationStatus> last;
    for (int n = 0; o->count == 0 || n < o->count; ++n) {
      auto until = std::chrono::steady_clock::now() + std::chrono::seconds(1);
      while (auto s = r.Take(std::max(bus::Millis(0), std::chrono::duration_cast<bus::Millis>(
                                                          until - std::chrono::steady_clock::now()))))
        last[s->station().to_string()] = *s;
      for (auto& [id, s] : last)
        std::cout << id << "  exec=" << s.execution() << "  pallet=" << s.pallet()
                  << "  program=" << s.program() << "  line=" << s.line() << "  parts=" << s.part_count()
                  << "\n";
      std::cout << "--\n" << std::flush;
    }
  });
}

}  // namespace cellctl
