// cellctl up|down|watch: a local cell from the systemd units' own command lines.
#include <fcntl.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "cell/bus/topics.h"
#include "cell/config/config.h"
#include "cell/config/units.h"
#include "cell/dashboard/feed.h"
#include "cell/dashboard/text_view.h"
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
    if (std::ifstream url(cell::config::DataDir() / "dashboard.url"); url) {
      std::string u;
      std::getline(url, u);
      if (!u.empty()) std::cout << "dashboard: " << u << " (MTConnect: " << u << "probe)\n";
    }
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

  auto* watch =
      app.add_subcommand("watch", "live view of the cell: stations, backlog, waiting pallets, jobs");
  watch->add_option("--count", o->count, "stop after N frames (0: never; 1: one frame for scripts)");
  watch->callback([o, &ctx] {
    // The same view the dashboard serves (services/dashboard), fed from the same topics.
    cell::dashboard::CellView view(cell::dashboard::LoadStationDefs());
    cell::dashboard::Feed feed(ctx.Bus(), view, {.axes = false});
    const bool tty = isatty(STDOUT_FILENO) != 0;
    cell::dashboard::TextStyle style;
    style.color = tty && !std::getenv("NO_COLOR");
    const auto t0 = std::chrono::steady_clock::now();
    while (!feed.Settled(std::chrono::duration_cast<bus::Millis>(std::chrono::steady_clock::now() - t0)) &&
           std::chrono::steady_clock::now() - t0 < std::chrono::seconds(4)) {
      feed.Tick();
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    for (int n = 0; o->count == 0 || n < o->count; ++n) {
      if (n > 0) {
        // Refresh on a change (at most 4 times a second) or once a second for the heartbeats.
        auto last = view.LastEvent();
        view.WaitEvent(last, std::chrono::milliseconds(1000));
        std::this_thread::sleep_for(std::chrono::milliseconds(250));
      }
      feed.Tick();
      winsize ws{};
      style.width = tty && ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0 ? ws.ws_col : 100;
      std::string frame = cell::dashboard::RenderText(view.Snapshot(), style);
      if (tty) {
        // Home, each line cleared to its end, the rest of the screen cleared: no flicker over ssh.
        std::string out = "\x1b[H";
        for (size_t a = 0, b; (b = frame.find('\n', a)) != std::string::npos; a = b + 1)
          out += frame.substr(a, b - a) + "\x1b[K\n";
        std::cout << out << "\x1b[J" << std::flush;
      } else {
        std::cout << frame << (o->count == 1 ? "" : "--\n") << std::flush;
      }
    }
  });
}

}  // namespace cellctl
