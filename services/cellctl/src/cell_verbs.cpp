// cellctl up|restart|down|watch: a local cell from the systemd units' own command lines.
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include "cell/bus/topics.h"
#include "cell/config/config.h"
#include "cell/config/dds.h"
#include "cell/config/units.h"
#include "cell/dashboard/feed.h"
#include "cell/dashboard/text_view.h"
#include "cell/dnc/settings.h"
#include "cell/interp/station_rules.h"
#include "cell/names/names.h"
#include "cell/security/pki.h"
#include "context.h"
#include "processes.h"

namespace cellctl {

namespace fs = std::filesystem;

namespace {

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

std::string Env(const CellProcess& p, const std::string& name) {
  for (auto& e : p.env)
    if (e.rfind(name + "=", 0) == 0) return e.substr(name.size() + 1);
  return "";
}

// The station whose interpreter a service id names ("cell-interpreter/KT01" -> "KT01"); "" for any other.
std::string InterpreterStation(const std::string& service) {
  const std::string prefix = "cell-interpreter/";
  return service.rfind(prefix, 0) == 0 ? service.substr(prefix.size()) : std::string();
}

// The cell's scheduler as recorded; nullptr in a cell without one.
const CellProcess* RecordedScheduler(const std::vector<CellProcess>& procs) {
  auto it = std::find_if(procs.begin(), procs.end(),
                         [](const CellProcess& p) { return p.service == "cell-scheduler"; });
  return it == procs.end() ? nullptr : &*it;
}

bool RunsScheduler(const std::vector<CellProcess>& procs) {
  return RecordedScheduler(procs) != nullptr;
}

// A station's table that a unit asks for (X-CellStationTable): [serial] makes cell-dnc@ID run.
bool HasTable(const std::string& station, const std::string& table) {
  return table == "serial" && cell::interp::LoadStation(station).serial.has_value();
}

// The station's file, and its [serial] line checked as its cell-dnc will check it (cell::dnc::Resolve), so
// that `up` refuses a bad line before it starts anything rather than waiting 30 s for a cell-dnc that exits.
void CheckStation(const std::string& station) {
  const auto cfg = cell::interp::LoadStation(station);
  if (!cfg.serial) return;
  try {
    cell::dnc::Resolve(cell::dnc::ControlOf(cfg.dialect), *cfg.serial);
  } catch (const cell::Error& e) {
    throw Exit{1, cfg.file.string() + ": " + e.what()};
  }
}

// The cell's processes as this invocation would start them. `only` "host": the plain units (the cell host's
// services: program store, scheduler, inspection writer, dashboard); "stations": the stations' template units
// (interpreter, axis servo, DNC); empty: both. A cell across hosts starts each part on its own host
// (docs/operations.md §9.2, deploy/hosts).
std::vector<CellProcess> Planned(const std::vector<std::string>& stations, const std::string& clock,
                                 const std::string& only = "") {
  fs::path bin = fs::read_symlink("/proc/self/exe").parent_path();
  fs::path logs = cell::config::DataDir() / "logs";
  std::vector<std::string> env = CurrentEnvironment();
  env.erase(std::remove_if(env.begin(), env.end(), [](auto& e) { return e.rfind("CELL_CLOCK=", 0) == 0; }),
            env.end());
  env.push_back("CELL_CLOCK=" + clock);
  std::vector<CellProcess> out;
  for (auto& c : cell::config::CellCommands(cell::config::SourceTreeDir() / "deploy/systemd", stations, bin,
                                            HasTable)) {
    const bool station_unit = c.unit.find('@') != std::string::npos;
    if ((only == "host" && station_unit) || (only == "stations" && !station_unit)) continue;
    CellProcess p;
    p.unit = c.unit;
    p.service = ServiceId(c.argv);
    p.argv = c.argv;
    p.env = env;
    p.log = (logs / (c.unit + ".log")).string();
    out.push_back(std::move(p));
  }
  return out;
}

// `up --secure`: refuses a cell that mixes DDS stacks (a secured Fast DDS 2.9.1 and a secured Cyclone 0.10
// never complete the handshake: bus_security_test), makes what is missing of the PKI in
// $CELL_DATA_DIR/security, and turns security on for this cellctl and, through its environment, every
// process it starts.
void Secure(const std::vector<std::string>& stations) {
  const std::string cell_vendor = cell::config::DdsVendor().vendor;
  for (auto& s : stations) {
    const std::string v = cell::config::DdsVendor(cell::interp::LoadStation(s).dds).vendor;
    if (v != cell_vendor)
      throw Exit{1, "a secured cell uses one DDS stack: station " + s + " runs " + v + ", the cell " +
                        cell_vendor +
                        " (Fast DDS 2.9.1 and Cyclone DDS 0.10 do not complete a secure handshake; "
                        "docs/security.md)"};
  }
  cell::security::PkiOptions po;
  po.dir = cell::config::DataDir() / "security";
  po.identities = cell::security::CellIdentities(stations);
  cell::security::InitPki(po);
  setenv("CELL_SECURITY", "on", 1);
}

// The scheduler's latest view of which stations are online (its state topic): a station it does not see is
// not dispatchable, whatever this cellctl hears.
class SchedulerView {
 public:
  explicit SchedulerView(bus::Participant& bus)
      : reader_(bus, bus::topics::kSchedulerState, bus::QosKind::kState,
                [this](const cell::SchedulerState& st, const bus::SampleInfo&) {
                  std::lock_guard lk(mu_);
                  online_.clear();
                  for (auto& b : st.backlog()) online_[b.station().to_string()] = b.online();
                }) {}
  bool Online(const std::string& station) const {
    std::lock_guard lk(mu_);
    auto it = online_.find(station);
    return it != online_.end() && it->second;
  }

 private:
  mutable std::mutex mu_;
  std::map<std::string, bool> online_;
  bus::Reader<cell::SchedulerState> reader_;  // last: its callback uses the members above
};

// Our child that has ended: how, with its last log line (a signal leaves no line of its own).
std::string HowItEnded(const CellProcess& p) {
  int status = 0;
  std::string how = "exited";
  if (waitpid(p.pid, &status, WNOHANG) == p.pid) {
    if (WIFEXITED(status)) how = "exited with status " + std::to_string(WEXITSTATUS(status));
    if (WIFSIGNALED(status)) how = std::string("was killed by signal ") + strsignal(WTERMSIG(status));
  }
  return p.unit + " " + how + ": " + LastLine(p.log);
}

// A restarted station service (interpreter, axis servo, DNC line) is up once it has sent READY=1 to
// `listener` (after it joined the bus, claimed its station and started serving), and an interpreter of a cell
// with a scheduler once the scheduler sees its station online, read by `ctx` as a client of the host
// services: this cellctl meets no station (a newcomer to the whole cell is what took over a minute, §9.6 of
// docs/operations.md). Returns what is missing.
std::vector<std::string> WaitRestarted(Context& ctx, const std::vector<CellProcess>& procs,
                                       const CellProcess& target, ReadyListener& listener,
                                       std::chrono::steady_clock::time_point deadline) {
  if (!listener.Wait(target, deadline)) {
    if (!StartTime(target.pid)) return {HowItEnded(target)};
    return {target.unit + " (no READY=1 from pid " + std::to_string(target.pid) + ")"};
  }
  const std::string station = InterpreterStation(target.service);
  // The recorded scheduler, while it runs: one that is down (killed with this station, not restarted yet)
  // sees nothing; its own restart waits for what it must see.
  const CellProcess* scheduler = RecordedScheduler(procs);
  const auto down = [&] { return scheduler == nullptr || !IsRunning(*scheduler); };
  if (station.empty() || down()) return {};
  SchedulerView sched(ctx.Bus());  // ctx.host_services_only: the caller's
  const auto left = std::chrono::duration_cast<bus::Millis>(deadline - std::chrono::steady_clock::now());
  if (bus::WaitUntil([&] { return sched.Online(station) || down(); }, std::max(left, bus::Millis(0)),
                     bus::Millis(25)))
    return {};
  return {target.unit + " (ready, but the scheduler does not see station " + station + ")"};
}

// Waits until every process in `procs` has announced itself READY on the bus (its own pid, so an older
// process's last heartbeat does not count) and, in a cell with a scheduler, until the scheduler sees every
// station online (a station it does not see is not dispatchable: in a cell too large for its discovery,
// processes announced READY to cellctl while the scheduler saw 6 of 24 stations), or one of `started` has
// exited. Returns what is missing.
std::vector<std::string> WaitReady(Context& ctx, const std::vector<CellProcess>& procs,
                                   const std::set<std::string>& started, bus::Millis timeout) {
  // The bus is joined only now, after every fork: no DDS socket or thread of cellctl's reaches a service.
  cell::health::Liveness live(ctx.Bus());
  std::optional<SchedulerView> sched;
  if (RunsScheduler(procs)) sched.emplace(ctx.Bus());
  std::vector<std::string> missing;
  bus::WaitUntil(
      [&] {
        missing.clear();
        auto seen = live.Snapshot();
        for (auto& p : procs) {
          if (started.count(p.service) && !StartTime(p.pid)) {
            missing.assign(1, HowItEnded(p));
            return true;  // no point waiting
          }
          if (p.service == "cell-dashboard" && Env(p, "CELL_SECURITY") == "on") {
            // Secured, the dashboard is a viewer and announces nothing: ready once it serves its page.
            if (!fs::exists(cell::config::DataDir() / "dashboard.url")) missing.push_back(p.unit);
            continue;
          }
          auto it = seen.find(p.service);
          if (!live.Online(p.service) || it == seen.end() || it->second.pid() != p.pid) {
            missing.push_back(p.unit);
          } else if (const std::string station = InterpreterStation(p.service);
                     sched && !station.empty() && !sched->Online(station)) {
            missing.push_back(p.unit + " (ready, but the scheduler does not see station " + station + ")");
          }
        }
        return missing.empty();
      },
      // A 52-process cell's check reads /proc for each: at 2 ms, cellctl alone took 1.5 cores.
      timeout, bus::Millis(25));
  return missing;
}

std::string Join(const std::vector<std::string>& v, const std::string& sep) {
  std::string out;
  for (auto& s : v) out += (out.empty() ? "" : sep) + s;
  return out;
}

// The services the frame shows (the view's host services, the stations' interpreters) that the local cell's
// record (cellctl up) has running now on this domain: ones a watch of that cell must hear before it prints.
// Empty without a record.
std::vector<std::string> RecordedShown(const nlohmann::json& snap) {
  std::set<std::string> shown;
  for (auto& s : snap.at("services").items()) shown.insert(s.key());
  for (auto& st : snap.at("stations")) shown.insert("cell-interpreter/" + st["id"].get<std::string>());
  const char* domain = std::getenv("CELL_DOMAIN");
  std::vector<std::string> out;
  try {
    for (auto& p : LoadRecord())
      if (shown.count(p.service) && Env(p, "CELL_DOMAIN") == (domain ? domain : "") && IsRunning(p))
        out.push_back(p.service);
  } catch (const Exit&) {  // an unreadable record: watch as without one
  }
  return out;
}

// Those of `services` the view does not show online yet.
std::vector<std::string> Unheard(const nlohmann::json& snap, const std::vector<std::string>& services) {
  std::set<std::string> online;
  for (auto& s : snap.at("services").items())
    if (s.value().get<bool>()) online.insert(s.key());
  for (auto& st : snap.at("stations"))
    if (st["online"].get<bool>()) online.insert("cell-interpreter/" + st["id"].get<std::string>());
  std::vector<std::string> out;
  for (auto& s : services)
    if (!online.count(s)) out.push_back(s);
  return out;
}

// The options of every cell verb: one invocation parses one verb.
struct Opts {
  std::string stations = "KT01,KT02";
  std::string clock = "real";
  std::string only;
  std::string service;
  int count = 0;
  bool secure = false;
  double ready_s = 30;  // up, restart: how long to wait for every process and station to be ready
};
using OptsPtr = std::shared_ptr<Opts>;

void AddCellUp(CLI::App& app, Context& ctx, const OptsPtr& o) {
  auto* up = app.add_subcommand("up",
                                "start a local cell from the systemd units' command lines (or what is "
                                "missing of one that is partly down)");
  auto* stations_opt = up->add_option(
      "--stations", o->stations,
      "comma-separated station ids, or all (every station file of the configuration; default KT01,KT02)");
  auto* clock_opt = up->add_option("--clock", o->clock, "real or virtual machine clock")
                        ->check(CLI::IsMember({"real", "virtual"}));
  up->add_option("--only", o->only,
                 "start only the cell host's services (host) or only the stations' (stations): one part of a "
                 "cell across hosts")
      ->check(CLI::IsMember({"host", "stations"}));
  up->add_option("--timeout", o->ready_s,
                 "seconds to wait for every process to announce itself and every station to be online to the "
                 "scheduler (default 30; a cell across hosts starting at once may want its settle time)")
      ->check(CLI::Range(1.0, 3600.0));
  up->add_flag("--secure", o->secure,
               "DDS Security: a PKI in $CELL_DATA_DIR/security (made if missing), every process with "
               "CELL_SECURITY=on (docs/security.md)");
  up->callback([o, &ctx, stations_opt, clock_opt] {
    auto stations = o->stations == "all" ? cell::config::ListStations() : Split(o->stations);
    if (stations.empty()) throw Exit{2, "--stations names no station"};
    for (auto& s : stations) CheckStation(s);  // an unknown station or a bad [serial] line: said now
    umask(077);  // the data directory, the record and the logs are the owner's only
    if (o->secure) Secure(stations);
    std::vector<CellProcess> procs;
    std::set<std::string> started;
    {
      RecordLock lock;
      std::vector<CellProcess> recorded = LoadRecord();
      const bool partly_up = std::any_of(recorded.begin(), recorded.end(), IsRunning);
      if (partly_up) {
        // Bring back what is missing, each exactly as it was started. Other stations or another clock would
        // be another cell.
        std::set<std::string> units;
        for (auto& p : recorded) units.insert(p.unit);
        std::set<std::string> wanted;
        for (auto& p : Planned(stations, o->clock, o->only)) wanted.insert(p.unit);
        if ((stations_opt->count() > 0 &&
             !std::includes(units.begin(), units.end(), wanted.begin(), wanted.end())) ||
            (clock_opt->count() > 0 && Env(recorded.front(), "CELL_CLOCK") != o->clock))
          throw Exit{1, "a local cell with other stations or another clock is running (cellctl down first)"};
        procs = recorded;
        // A secured cell is watched through a secured participant (its PKI is in the data directory).
        if (Env(recorded.front(), "CELL_SECURITY") == "on") setenv("CELL_SECURITY", "on", 1);
      } else {
        procs = Planned(stations, o->clock, o->only);
      }
      fs::create_directories(cell::config::DataDir() / "logs");
      for (auto& p : procs) {
        if (partly_up && IsRunning(p)) continue;
        Launch(p);
        started.insert(p.service);
      }
      SaveRecord(procs);
    }
    // Ready = every process announced itself READY on the bus and every station online in the scheduler's
    // view (WaitReady), within --timeout (30 s).
    auto missing = WaitReady(ctx, procs, started, bus::Millis(static_cast<std::int64_t>(o->ready_s * 1000)));
    if (!missing.empty()) {
      std::vector<CellProcess> ours;
      for (auto& p : procs)
        if (started.count(p.service)) ours.push_back(p);
      Stop(ours, std::chrono::seconds(10));
      {
        RecordLock lock;
        auto now = LoadRecord();
        if (std::none_of(now.begin(), now.end(), IsRunning)) fs::remove(RecordFile());
      }
      throw Exit{1, "cell did not come up: " + Join(missing, "; ")};
    }
    std::cout << "cell up on domain " << ctx.Bus().domain() << ": " << procs.size() << " processes ready";
    const auto station_count = std::count_if(procs.begin(), procs.end(), [](const CellProcess& p) {
      return !InterpreterStation(p.service).empty();
    });
    if (RunsScheduler(procs) && station_count > 0)
      std::cout << ", " << station_count << " stations online to the scheduler";
    if (started.size() != procs.size()) std::cout << ", " << started.size() << " of them started now";
    std::cout << " (" << Env(procs.front(), "CELL_CLOCK") << " clock), logs in "
              << (cell::config::DataDir() / "logs").string() << "\n";
    if (std::ifstream url(cell::config::DataDir() / "dashboard.url"); url) {
      std::string u;
      std::getline(url, u);
      if (!u.empty()) std::cout << "dashboard: " << u << " (MTConnect: " << u << "probe)\n";
    }
  });
}

void AddCellRestart(CLI::App& app, Context& ctx, const OptsPtr& o) {
  auto* restart = app.add_subcommand("restart", "restart one service of the local cell: SERVICE[/ID]");
  restart->add_option("SERVICE", o->service, "e.g. cell-scheduler, cell-interpreter/KT01")->required();
  restart
      ->add_option("--timeout", o->ready_s,
                   "seconds to wait for the new process to be ready (default 30): a host service heard on "
                   "the bus, a station's service by its READY=1 and, for an interpreter, online to the "
                   "scheduler")
      ->check(CLI::Range(1.0, 3600.0));
  restart->callback([o, &ctx] {
    umask(077);
    std::vector<CellProcess> procs;
    CellProcess target;
    bool host_service = false;
    std::optional<ReadyListener> listener;  // a station's service: its READY=1 comes here
    {
      RecordLock lock;
      procs = LoadRecord();
      if (procs.empty())
        throw Exit{1, "no local cell is recorded in " + RecordFile().string() + " (cellctl up)"};
      auto it = std::find_if(procs.begin(), procs.end(), [&](const CellProcess& p) {
        return p.service == o->service || p.unit == o->service || p.unit == o->service + ".service";
      });
      if (it == procs.end()) {
        std::vector<std::string> known;
        for (auto& p : procs) known.push_back(p.service);
        throw Exit{2, "no service " + cell::names::Shown(o->service) + " in the local cell (" +
                          Join(known, ", ") + ")"};
      }
      if (it->argv.empty())
        throw Exit{1, it->unit + " was recorded without its command line (cellctl down; up)"};
      host_service = bus::HostServiceSlot(it->service) >= 0;
      if (!host_service) listener.emplace();
      // A process that is still the one started is stopped first; a PID that now belongs to another process
      // is left alone.
      Stop({*it}, std::chrono::seconds(10));
      if (Env(*it, "CELL_SECURITY") == "on") setenv("CELL_SECURITY", "on", 1);
      Launch(*it, host_service ? std::vector<std::string>{} : listener->Env());
      target = *it;
      SaveRecord(procs);
    }
    const auto timeout = bus::Millis(static_cast<std::int64_t>(o->ready_s * 1000));
    // Either way this cellctl is a client of the host services alone: a host service restarted is heard on
    // its own slot (the week restarts the scheduler under load; docs/operations.md §9.4, "A client of the
    // host services"), a station's service says READY=1 to this cellctl and the scheduler says whether it
    // sees the station (WaitRestarted). No station need meet this cellctl.
    ctx.host_services_only = true;
    auto missing = host_service ? WaitReady(ctx, {target}, {target.service}, timeout)
                                : WaitRestarted(ctx, procs, target, *listener,
                                                std::chrono::steady_clock::now() + timeout);
    if (!missing.empty()) throw Exit{1, target.service + " did not come up: " + Join(missing, "; ")};
    std::cout << target.service << " restarted: pid " << target.pid << "\n";
  });
}

void AddCellDown(CLI::App& app) {
  auto* down = app.add_subcommand("down", "stop the local cell (SIGTERM, then SIGKILL after 10 s)");
  down->callback([] {
    RecordLock lock;
    auto procs = LoadRecord();
    if (procs.empty()) {
      std::cout << "no local cell is running\n";
      return;
    }
    for (auto& line : Stop(procs, std::chrono::seconds(10))) std::cerr << "cellctl: " << line << "\n";
    fs::remove(RecordFile());
    std::cout << "cell down: " << procs.size() << " processes stopped\n";
  });
}

void AddCellWatch(CLI::App& app, Context& ctx, const OptsPtr& o) {
  auto* watch =
      app.add_subcommand("watch", "live view of the cell: stations, backlog, waiting pallets, jobs");
  watch->add_option("--count", o->count, "stop after N frames (0: never; 1: one frame for scripts)")
      ->transform(Decimal());
  watch->callback([o, &ctx] {
    // The same view the dashboard serves (services/dashboard), fed from the same topics.
    cell::dashboard::CellView view(cell::dashboard::LoadStationDefs());
    cell::dashboard::Feed feed(ctx.Bus(), view, {.axes = false, .on_job = {}});
    const bool tty = isatty(STDOUT_FILENO) != 0;
    cell::dashboard::TextStyle style;
    style.color = tty && !std::getenv("NO_COLOR");
    // With a finite --count a script reads only these frames: a service the local cell runs must have been
    // heard (and then, by Settled, its data) first, as discovery can take seconds on a loaded machine.
    // Without a record only Settled's grace period stands in for discovery. At the deadline: what is known.
    feed.Tick();
    const auto expected = o->count > 0 ? RecordedShown(view.Snapshot()) : std::vector<std::string>{};
    const auto limit = std::chrono::seconds(expected.empty() ? 4 : 10);
    const auto t0 = std::chrono::steady_clock::now();
    for (;;) {
      feed.Tick();  // first: a service the view shows online is one Settled has seen and waits on
      const auto waited = std::chrono::steady_clock::now() - t0;
      if (feed.Settled(std::chrono::duration_cast<bus::Millis>(waited)) &&
          Unheard(view.Snapshot(), expected).empty())
        break;
      if (waited >= limit) {
        if (auto u = Unheard(view.Snapshot(), expected); !u.empty())
          std::cerr << "cellctl: watch: not heard within " << limit.count()
                    << " s, shown offline: " << Join(u, ", ") << "\n";
        break;
      }
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

}  // namespace

void AddCellVerbs(CLI::App& app, Context& ctx) {
  auto o = std::make_shared<Opts>();
  AddCellUp(app, ctx, o);
  AddCellRestart(app, ctx, o);
  AddCellDown(app);
  AddCellWatch(app, ctx, o);
}

}  // namespace cellctl
