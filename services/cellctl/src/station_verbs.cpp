// cellctl station ls|tools|vars|input|io|reset|hold|resume|override
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <set>
#include <thread>

#include "cell/bus/topics.h"
#include "cell/config/config.h"
#include "cell/dashboard/feed.h"
#include "cell/idl/health.h"
#include "cell/idl/scheduler.h"
#include "cell/interp/station_rules.h"
#include "cell/names/names.h"
#include "cell/records/station.h"
#include "cell/tooltable/wire.h"
#include "context.h"

namespace cellctl {

namespace {

void RequireConfigured(const std::string& id) {
  cell::names::CheckStation(id);
  auto ids = cell::config::ListStations();
  if (std::find(ids.begin(), ids.end(), id) == ids.end()) {
    std::string list;
    for (auto& s : ids) list += (list.empty() ? "" : ", ") + s;
    throw Exit{1, "unknown station '" + id + "' (configured: " + list + ")"};
  }
}

// name=value with a decimal number on the right (an optional sign, digits, at most one '.'; no hexadecimal,
// no exponent, no inf or nan: std::stod alone would take them all).
std::pair<std::string, double> Assignment(const std::string& text) {
  auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw Exit{2, "expected NAME=VALUE, got " + cell::names::Shown(text)};
  std::string v = text.substr(eq + 1);
  std::string digits = !v.empty() && (v[0] == '-' || v[0] == '+') ? v.substr(1) : v;
  bool ok =
      !digits.empty() && digits.size() <= 24 && std::count(digits.begin(), digits.end(), '.') <= 1 &&
      std::any_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }) &&
      std::all_of(digits.begin(), digits.end(), [](char c) { return (c >= '0' && c <= '9') || c == '.'; });
  if (!ok) throw Exit{2, cell::names::Shown(v) + " is not a decimal number in " + cell::names::Shown(text)};
  return {text.substr(0, eq), std::stod(v)};
}

// The station's kept variables as published (revision `min_rev` or later: after a --set), or a one-line
// reason.
cell::StationVariables Variables(Context& ctx, const std::string& id, uint32_t min_rev = 0) {
  bus::Reader<cell::StationVariables> r(ctx.Bus(), bus::topics::kVariables, bus::QosKind::kState);
  auto v =
      r.WaitFor([&](const cell::StationVariables& x) { return x.station() == id && x.revision() >= min_rev; },
                bus::Millis(3000));
  if (!v) throw Exit{1, "station " + id + " has not published its variables (is it online?)"};
  return *v;
}

// The options of every station verb: one invocation parses one verb.
struct Opts {
  std::string id;
  std::vector<std::string> sets;
  std::string input;
  double feed_pct = -1, rapid_pct = -1;
  int socket = 0;
  bool mend = false;
  std::string switch_to;
};
using OptsPtr = std::shared_ptr<Opts>;

void AddStationLs(CLI::App& st, Context& ctx) {
  auto* ls = st.add_subcommand("ls", "configured and announced stations");
  ls->add_flag("--json", ctx.json);
  ls->callback([&ctx] {
    cell::health::Liveness live(ctx.Bus());
    bus::Reader<cell::SchedulerState> sched(ctx.Bus(), bus::topics::kSchedulerState, bus::QosKind::kState);
    bus::Reader<cell::StationStatus> status(ctx.Bus(), bus::topics::kStationStatus, bus::QosKind::kState);
    // The scheduler's conditions on a station (two processes claiming its interpreter or servo).
    bus::Reader<cell::Alarm> alarms(ctx.Bus(), bus::topics::kAlarm, bus::QosKind::kEvent);
    std::map<std::string, cell::records::StationAlarm> alarm;  // station -> the latest scheduler alarm
    const auto ids = cell::config::ListStations();
    std::map<std::string, double> backlog;
    std::map<std::string, cell::records::StationStatus> by_id;
    // All three topics are transient-local: each announced service's last sample arrives soon after this
    // process discovers it. Gather until every station that heartbeats has sent its status and a running
    // scheduler its backlog (discovery is slower on a loaded machine, so no fixed window). A station not
    // heard at all is offline at once when a settled scheduler says so (it has watched the heartbeats for
    // longer than this process could); only without a scheduler does a grace period stand in for
    // discovery, under an overall bound.
    bool sched_seen = false;
    cell::dashboard::SchedulerView sched_view;  // what a settled scheduler says of each station
    // Nothing else on the domain, when cellctl may conclude that (Context::Bus): asked only once the
    // discovery window has passed, not on every pass of the loop.
    auto lone = [&] { return ctx.Bus().lone_means_down() && ctx.Bus().RemoteParticipants() == 0; };
    const auto t0 = std::chrono::steady_clock::now();
    for (;;) {
      while (auto st = status.Take(bus::Millis(0)))
        by_id[st->station().to_string()] = cell::records::FromWire(*st);
      while (auto a = alarms.Take(bus::Millis(0))) {
        auto& last = alarm[a->station().to_string()];
        if (a->time_ns() >= last.time_ns) last = cell::records::FromWire(*a);
      }
      while (auto sc = sched.Take(bus::Millis(0))) {
        sched_seen = true;
        backlog.clear();
        for (auto& b : sc->backlog()) backlog[b.station().to_string()] = b.backlog_s();
        sched_view = cell::dashboard::SettledSchedulerView(*sc);
      }
      const auto heard = cell::dashboard::HeardStations(
          ids, live, [&](const std::string& id) { return by_id.count(id) > 0; }, sched_view);
      bool waiting = heard == cell::dashboard::Heard::kWaiting;
      if (live.Online("cell-scheduler") && !sched_seen) waiting = true;
      // Participants found whose heartbeats have not arrived yet, and no scheduler's word: discovery is still
      // under way (a newcomer to a 68-process cell hears the last heartbeat seconds after the first).
      if (!sched_seen && static_cast<int>(live.Snapshot().size()) < ctx.Bus().RemoteParticipants())
        waiting = true;
      auto waited = std::chrono::steady_clock::now() - t0;
      if (waited >= bus::kLoneWindow && lone()) break;  // nothing on the domain
      if (!waiting &&
          (heard == cell::dashboard::Heard::kComplete || waited >= std::chrono::milliseconds(1500)))
        break;
      if (waited >= std::chrono::milliseconds(8000)) break;  // a large cell: discovery takes seconds
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    // A table of offline stations would say the cell runs without them (issue 39 item 6): without its
    // scheduler and its program store there is no cell to list.
    auto cell_up = [&] { return live.Online("cell-scheduler") || live.Online("cell-program-store"); };
    if (!cell_up() && !lone()) bus::WaitUntil(cell_up, bus::Millis(2000));
    if (!cell_up()) {
      throw Exit{1, fmt::format("no cell on DDS domain {}: neither the scheduler nor the program store runs "
                                "(cellctl up starts the cell)",
                                ctx.Bus().domain())};
    }
    nlohmann::json arr = nlohmann::json::array();
    for (auto& id : ids) {
      auto cfg = cell::interp::LoadStation(id);
      bool online =
          live.StationOnline(id) ||
          (by_id.count(id) && bus::WaitUntil([&] { return live.StationOnline(id); }, bus::Millis(1500)));
      // The row and its state rules are the records module's: the dashboard prints the same.
      auto st = by_id.find(id);
      auto a = alarm.find(id);
      auto b = backlog.find(id);
      nlohmann::json j = cell::records::StationRow(
          {id, cfg.dialect, online, st == by_id.end() ? nullptr : &st->second,
           a == alarm.end() ? nullptr : &a->second, b == backlog.end() ? 0.0 : b->second});
      arr.push_back(j);
    }
    Print(ctx, arr,
          {"id", "dialect", "online", "execution", "condition", "backlog_s", "pallet", "program", "line",
           "status_text"});
  });
}

void AddStationTools(CLI::App& st, Context& ctx, const OptsPtr& o) {
  auto* tools = st.add_subcommand("tools", "the station's tool table as it publishes it");
  tools->add_option("ID", o->id)->required();
  tools->add_flag("--json", ctx.json);
  tools->callback([o, &ctx] {
    RequireConfigured(o->id);
    auto t = ctx.Tools(o->id, bus::Millis(3000));
    if (!t) throw Exit{1, "station " + o->id + " has not published a tool table (is it online?)"};
    // DESIGN §6 keys for every entry; the other dialects' fields where they apply (tooltable::EntryJson).
    nlohmann::json arr = nlohmann::json::array();
    const cell::tooltable::ToolTable table = cell::tooltable::FromWire(*t);
    for (const auto& e : table.entries()) {
      nlohmann::json j = cell::tooltable::EntryJson(e);
      // KT-APL TLD W: this data set's process compensations, per pallet.
      nlohmann::json process = nlohmann::json::array();
      for (const auto& c : table.process_comps())
        if (c.tool == e.tool)
          process.push_back({{"pallet", c.pallet}, {"length", c.length}, {"diameter", c.diameter}});
      if (!process.empty()) j["process"] = process;
      arr.push_back(j);
    }
    Print(ctx, arr, {"tool", "socket", "length", "diameter", "life_left_min", "worn", "broken"});
  });
}

void AddStationVars(CLI::App& st, Context& ctx, const OptsPtr& o) {
  auto* vars = st.add_subcommand("vars", "station variables (KT-APL parameters, Okuma common variables)");
  vars->add_option("ID", o->id)->required();
  vars->add_option("--set", o->sets, "NAME=VALUE (repeatable)");
  vars->add_flag("--json", ctx.json);
  vars->callback([o, &ctx] {
    RequireConfigured(o->id);
    uint32_t min_rev = 0;
    if (!o->sets.empty()) {
      cell::StationRequest req;
      req.op(cell::STATION_SET_VARIABLES);
      for (auto& s : o->sets) {
        auto [n, v] = Assignment(s);
        cell::Variable var;
        cell::names::Assign(var.name(), n, "variable name");
        var.value(v);
        req.variables().push_back(var);
      }
      min_rev = ctx.StationCommand(o->id, req).revision();
    }
    const cell::StationVariables v = Variables(ctx, o->id, min_rev);
    nlohmann::json j = nlohmann::json::object();
    for (auto& x : v.variables()) j[x.name().to_string()] = x.value();
    if (ctx.json) return Print(ctx, j, {});
    // 10 significant digits, as a parameter display shows them (0.05, not 0.05000000000001137).
    for (auto& [k, val] : j.items()) std::cout << fmt::format("{} = {:.10g}\n", k, val.get<double>());
  });
}

// The fixture offset table (KT-APL FXC/UFX/ULF, manual ch. 6): the station keeps line n as the variables
// H<n>.X ... H<n>.C and H<n>.I (docs/dialects/ktapl.md call 61); shown here as the control's table.
void AddStationOffsets(CLI::App& st, Context& ctx, const OptsPtr& o) {
  auto* offsets = st.add_subcommand("offsets", "fixture offset table (KT-APL H lines set by FXC, UFX, ULF)");
  offsets->add_option("ID", o->id)->required();
  offsets->add_flag("--json", ctx.json);
  offsets->callback([o, &ctx] {
    RequireConfigured(o->id);
    const cell::StationVariables v = Variables(ctx, o->id);
    static const std::vector<std::string> kCols = {"X", "Y", "Z", "A", "B", "C", "I"};
    std::map<int, nlohmann::json> lines;  // H number -> {axis: value}
    for (auto& x : v.variables()) {
      const std::string name = x.name().to_string();
      const std::size_t dot = name.find('.');
      if (name.size() < 4 || name[0] != 'H' || dot == std::string::npos) continue;
      const std::string num = name.substr(1, dot - 1), col = name.substr(dot + 1);
      if (num.empty() || !std::all_of(num.begin(), num.end(), [](char c) { return c >= '0' && c <= '9'; }))
        continue;
      if (std::find(kCols.begin(), kCols.end(), col) == kCols.end()) continue;
      lines[std::stoi(num)][col] = x.value();
    }
    if (ctx.json) {
      nlohmann::json j = nlohmann::json::object();
      for (auto& [n, l] : lines) j["H" + std::to_string(n)] = l;
      return Print(ctx, j, {});
    }
    if (lines.empty()) {
      std::cout << "no fixture offsets set on " << o->id << "\n";
      return;
    }
    // mm and degrees; I is the B position the line was taken at (G49).
    std::cout << fmt::format("{:<4}", "H");
    for (const auto& c : kCols) std::cout << fmt::format(" {:>12}", c);
    std::cout << "\n";
    for (auto& [n, l] : lines) {
      std::cout << fmt::format("{:<4}", "H" + std::to_string(n));
      for (const auto& c : kCols)
        std::cout << (l.contains(c) ? fmt::format(" {:>12.10g}", l[c].get<double>())
                                    : fmt::format(" {:>12}", "-"));
      std::cout << "\n";
    }
  });
}

void AddStationInput(CLI::App& st, Context& ctx, const OptsPtr& o) {
  auto* input =
      st.add_subcommand("input", "set a discrete input (for KT-APL WAI): I<word>.<bit>=0|1, e.g. I04D.1=1");
  input->add_option("ID", o->id)->required();
  input->add_option("BIT=VALUE", o->input)->required();
  input->callback([o, &ctx] {
    RequireConfigured(o->id);
    auto [bit, v] = Assignment(o->input);
    if (v != 0 && v != 1) throw Exit{2, "an input is 0 or 1"};
    // The old form named a bare bit number ("3=1"); inputs are KT-APL word bits now (docs/station.md).
    if (!bit.empty() && std::all_of(bit.begin(), bit.end(), [](char c) { return c >= '0' && c <= '9'; }))
      throw Exit{2, "an input is named I<word>.<bit>, e.g. I04D.1 (word address in hexadecimal, bit 0-15)"};
    cell::StationRequest req;
    req.op(cell::STATION_SET_INPUT);
    cell::Variable var;
    cell::names::Assign(var.name(), bit, "input");
    var.value(v);
    req.variables().push_back(var);
    const uint32_t rev = ctx.StationCommand(o->id, req).revision();
    // Returns once the station publishes the change, so a following `station io` shows it.
    bus::Reader<cell::StationIoState> r(ctx.Bus(), bus::topics::kStationIo, bus::QosKind::kState);
    if (!r.WaitFor([&](const cell::StationIoState& x) { return x.station() == o->id && x.revision() >= rev; },
                   bus::Millis(3000)))
      throw Exit{1, "input set, but station " + o->id + " has not published it within 3 s"};
  });
}

void AddStationIo(CLI::App& st, Context& ctx, const OptsPtr& o) {
  auto* io = st.add_subcommand("io", "the station's discrete inputs and outputs");
  io->add_option("ID", o->id)->required();
  io->add_flag("--json", ctx.json);
  io->callback([o, &ctx] {
    RequireConfigured(o->id);
    bus::Reader<cell::StationIoState> r(ctx.Bus(), bus::topics::kStationIo, bus::QosKind::kState);
    auto s =
        r.WaitFor([&](const cell::StationIoState& x) { return x.station() == o->id; }, bus::Millis(3000));
    if (!s) throw Exit{1, "station " + o->id + " has not published its I/O (is it online?)"};
    // One row per point: inputs first, then outputs with their power-up state (KT-APL (SET)).
    nlohmann::json arr = nlohmann::json::array();
    for (auto& p : s->inputs())
      arr.push_back(
          {{"name", p.name().to_string()}, {"kind", "input"}, {"value", p.value()}, {"power_up", nullptr}});
    for (auto& p : s->outputs())
      arr.push_back({{"name", p.name().to_string()},
                     {"kind", "output"},
                     {"value", p.value()},
                     {"power_up", p.power_up()}});
    Print(ctx, arr, {"kind", "name", "value", "power_up"});
  });
}

void AddStationReset(CLI::App& st, Context& ctx, const OptsPtr& o) {
  auto* reset = st.add_subcommand("reset", "clear the station's alarm condition");
  reset->add_option("ID", o->id)->required();
  reset->callback([o, &ctx] {
    RequireConfigured(o->id);
    cell::StationRequest req;
    req.op(cell::STATION_RESET);
    ctx.StationCommand(o->id, req);
  });
}

// The panel's feed hold and cycle start: each returns once the station reports the hold in effect or
// released (execution FEED_HOLD in `station ls`, from the servo's own report), or fails saying the
// servo has not confirmed it; the request stands either way (a servo that comes back applies it).
void Panel(Context& ctx, const std::string& id, bool hold) {
  RequireConfigured(id);
  bus::Reader<cell::StationStatus> status(ctx.Bus(), bus::topics::kStationStatus, bus::QosKind::kState);
  cell::StationRequest req;
  req.op(hold ? cell::STATION_FEED_HOLD : cell::STATION_CYCLE_START);
  ctx.StationCommand(id, req);
  auto s = status.WaitFor(
      [&](const cell::StationStatus& x) {
        return x.station() == id && (x.execution() == cell::EXECUTION_FEED_HOLD) == hold;
      },
      bus::Millis(5000));
  if (!s)
    throw Exit{1, std::string(hold ? "feed hold" : "cycle start") + " recorded, but the axis servo of " + id +
                      " has not confirmed it within 5 s (is it running?)"};
}

void AddStationPanel(CLI::App& st, Context& ctx, const OptsPtr& o) {
  auto* hold = st.add_subcommand("hold", "feed hold: motion stops on its path until resume");
  hold->add_option("ID", o->id)->required();
  hold->callback([o, &ctx] { Panel(ctx, o->id, true); });
  // One CYCLE START button, two names: `start` after a program stop (M00, M01, M99 M00), `resume` after a
  // hold. On an idle Balt-System station START runs the program SPG selected (docs/dialects/balt.md).
  auto* start =
      st.add_subcommand("start",
                        "cycle start: a run stopped at M00 / M01 goes on (and a hold is released); an "
                        "idle Balt-System station runs the program selected with SPG");
  start->add_option("ID", o->id)->required();
  start->callback([o, &ctx] { Panel(ctx, o->id, false); });
  auto* resume = st.add_subcommand("resume", "cycle start: release the feed hold (the same button as start)");
  resume->add_option("ID", o->id)->required();
  resume->callback([o, &ctx] { Panel(ctx, o->id, false); });
}

// The machine's tool model, for a G38 check (and the tests that need a tool to break): the tool in SOCKET
// is broken until mended; the check sets the tool table's broken flag and stops the run.
void AddStationBreak(CLI::App& st, Context& ctx, const OptsPtr& o) {
  auto* brk = st.add_subcommand("break", "the tool in a magazine socket is broken (a G38 check finds it so)");
  brk->add_option("ID", o->id)->required();
  brk->add_option("SOCKET", o->socket, "magazine socket")->required()->check(CLI::Range(1, 1000));
  brk->add_flag("--mend", o->mend, "the tool there is whole again (replaced)");
  brk->callback([o, &ctx] {
    RequireConfigured(o->id);
    cell::StationRequest req;
    req.op(cell::STATION_BREAK_TOOL);
    req.socket(o->socket);
    req.mend(o->mend);
    ctx.StationCommand(o->id, req);
  });
}

// The panel's [ENABLE OPTION STOP] switch: M01 stops the next programs (OPTIONAL_STOP) while it is on.
void AddStationOptionalStop(CLI::App& st, Context& ctx, const OptsPtr& o) {
  auto* opt_stop = st.add_subcommand("optional-stop", "the optional-stop switch: M01 stops while it is on");
  opt_stop->add_option("ID", o->id)->required();
  opt_stop->add_option("STATE", o->switch_to, "on or off")->required()->check(CLI::IsMember({"on", "off"}));
  opt_stop->callback([o, &ctx] {
    RequireConfigured(o->id);
    cell::StationRequest req;
    req.op(cell::STATION_OPTIONAL_STOP);
    req.optional_stop(o->switch_to == "on");
    ctx.StationCommand(o->id, req);
  });
}

void AddStationOverride(CLI::App& st, Context& ctx, const OptsPtr& o) {
  auto* ovr = st.add_subcommand("override", "feed (0-200 %) and rapid (0-100 %) override");
  ovr->add_option("ID", o->id)->required();
  ovr->add_option("--feed", o->feed_pct, "feed override, percent")->check(Real() & CLI::Range(0.0, 200.0));
  ovr->add_option("--rapid", o->rapid_pct, "rapid override, percent")->check(Real() & CLI::Range(0.0, 100.0));
  ovr->callback([o, &ctx] {
    RequireConfigured(o->id);
    if (o->feed_pct < 0 && o->rapid_pct < 0) throw Exit{2, "give --feed PCT, --rapid PCT or both"};
    cell::StationRequest req;
    req.op(cell::STATION_OVERRIDE);
    req.feed_override(o->feed_pct < 0 ? -1 : o->feed_pct / 100);
    req.rapid_override(o->rapid_pct < 0 ? -1 : o->rapid_pct / 100);
    ctx.StationCommand(o->id, req);
  });
}

}  // namespace

void AddStationVerbs(CLI::App& app, Context& ctx) {
  auto* st =
      app.add_subcommand("station", "stations: state, tools, variables, inputs")->require_subcommand(1);
  auto o = std::make_shared<Opts>();
  AddStationLs(*st, ctx);
  AddStationTools(*st, ctx, o);
  AddStationVars(*st, ctx, o);
  AddStationOffsets(*st, ctx, o);
  AddStationInput(*st, ctx, o);
  AddStationIo(*st, ctx, o);
  AddStationReset(*st, ctx, o);
  AddStationPanel(*st, ctx, o);
  AddStationBreak(*st, ctx, o);
  AddStationOptionalStop(*st, ctx, o);
  AddStationOverride(*st, ctx, o);
}

}  // namespace cellctl
