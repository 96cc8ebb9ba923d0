// cellctl dnc send|receive|drip STATION NAME [--node X], cellctl dnc status [--json] (DESIGN §6b,
// docs/dnc.md): programs to and from a station's control over its serial line, through its cell-dnc.
#include <fmt/format.h>

#include <chrono>
#include <map>

#include "cell/config/config.h"
#include "cell/dnc/client.h"
#include "cell/interp/station_rules.h"
#include "cell/names/names.h"
#include "context.h"

namespace cellctl {

namespace {

// The station, configured with a [serial] line; Exit{1} naming what is missing.
void RequireLine(const std::string& station) {
  cell::names::CheckStation(station);
  if (!cell::interp::LoadStation(station).serial)
    throw Exit{1, fmt::format("station {} has no [serial] table: it has no DNC line", station)};
}

// Stations whose file has a [serial] table (a broken station file is `station ls`'s to report).
std::vector<std::string> StationsWithLines() {
  std::vector<std::string> out;
  for (const auto& s : cell::config::ListStations()) {
    try {
      if (cell::interp::LoadStation(s).serial) out.push_back(s);
    } catch (const cell::Error&) {
    }
  }
  return out;
}

// Whether the station's cell-dnc went away while it ran our transfer: it stopped announcing itself, or a
// new process (another boot id) took its place and never got our request.
class Watch {
 public:
  Watch(Context& ctx, const std::string& station)
      : live_(ctx.Bus()), id_("cell-dnc/" + station), since_(std::chrono::steady_clock::now()) {}
  std::string Gone() {
    auto snap = live_.Snapshot();
    auto it = snap.find(id_);
    if (live_.Online(id_)) {
      if (boot_ == 0) boot_ = it->second.boot_id();
      if (it->second.boot_id() == boot_) return "";
      return id_ + " restarted during the transfer";
    }
    if (boot_ != 0) return id_ + " stopped during the transfer (its heartbeat ended)";
    if (std::chrono::steady_clock::now() - since_ > std::chrono::seconds(10))
      return id_ + " is not running (no heartbeat for 10 s)";
    return "";
  }

 private:
  cell::health::Liveness live_;
  std::string id_;
  uint64_t boot_ = 0;
  std::chrono::steady_clock::time_point since_;
};

struct Opts {
  std::string station, name, node;
};

// One transfer; its one-line reason and exit 1 when it fails (whatever the error's kind).
nlohmann::json Transfer(Context& ctx, cell::DncOp op, const Opts& o) {
  RequireLine(o.station);
  cell::names::CheckProgram(o.name);
  if (!o.node.empty()) cell::names::CheckNode(o.node);
  Watch watch(ctx, o.station);
  cell::dnc::Client client(ctx.Bus(), o.station);
  try {
    auto rep = client.Run(op, o.node, o.name, [&watch] { return watch.Gone(); });
    return nlohmann::json::parse(rep.info().to_string(), nullptr, false);
  } catch (const cell::Error& e) {
    throw Exit{1, fmt::format("dnc {} {}: {}", cell::dnc::OpName(op), o.station, ctx.Explain(e))};
  }
}

std::string Figures(const nlohmann::json& j) {
  return fmt::format("{} bytes in {:.1f} s ({:.0f} bytes/s, {} stops)", j.value("bytes", 0),
                     j.value("seconds", 0.0), j.value("rate", 0.0), j.value("stalls", 0));
}

void AddTransfer(CLI::App& dnc, Context& ctx, cell::DncOp op, const std::string& help) {
  auto o = std::make_shared<Opts>();
  auto* v = dnc.add_subcommand(std::string(cell::dnc::OpName(op)), help);
  v->add_option("STATION", o->station, "station id (its file has a [serial] table)")->required();
  v->add_option("NAME", o->name, "program name")->required();
  v->add_option("--node", o->node,
                op == cell::DNC_RECEIVE ? "namespace to store it in (default: the station's)"
                                        : "namespace to read it from (default: the station's, then HOST)");
  v->add_flag("--json", ctx.json);
  v->callback([&ctx, op, o] {
    const nlohmann::json j = Transfer(ctx, op, *o);
    if (ctx.json) return Print(ctx, j, {});
    if (op == cell::DNC_RECEIVE) {
      std::cout << fmt::format("stored {} revision {}: {}\n", j.value("program", o->name),
                               j.value("revision", 0), Figures(j));
    } else {
      std::cout << fmt::format("{} {} to {}: {}\n", op == cell::DNC_DRIP ? "dripped" : "sent",
                               j.value("program", o->name), o->station, Figures(j));
    }
  });
}

nlohmann::json NoProcess(const std::string& station) {
  return {{"station", station}, {"dnc", false}, {"state", "no DNC process"}};
}

void AddStatus(CLI::App& dnc, Context& ctx) {
  auto* st = dnc.add_subcommand("status", "every DNC line: state, bytes, rate, stalls, errors");
  st->add_flag("--json", ctx.json);
  st->callback([&ctx] {
    const std::vector<std::string> lines = StationsWithLines();
    // Returns as soon as every expected line is heard. The bound is for a line whose cell-dnc is not running:
    // a secured participant's handshakes on a loaded host take several seconds (3 s missed a running one).
    auto heard = cell::dnc::Statuses(ctx.Bus(), lines, bus::Millis(lines.empty() ? 1500 : 10000));
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& s : lines)
      rows.push_back(heard.count(s) ? cell::dnc::StatusJson(heard[s]) : NoProcess(s));
    for (const auto& [s, status] : heard)  // a cell-dnc of a station this host has no file for
      if (std::find(lines.begin(), lines.end(), s) == lines.end())
        rows.push_back(cell::dnc::StatusJson(status));
    Print(ctx, rows,
          {"station", "state", "device", "program", "bytes", "total", "rate", "stalls", "stopped_s", "errors",
           "last_error"});
  });
}

}  // namespace

void AddDncVerbs(CLI::App& app, Context& ctx) {
  auto* dnc = app.add_subcommand("dnc", "programs to and from the controls over their serial lines");
  dnc->require_subcommand(1);
  AddTransfer(*dnc, ctx, cell::DNC_SEND,
              "send a stored program to the control (returns when it is on the line)");
  AddTransfer(*dnc, ctx, cell::DNC_RECEIVE,
              "store what the control punches as a new revision, once complete and checked");
  AddTransfer(*dnc, ctx, cell::DNC_DRIP,
              "feed a stored program while the control executes it (behind the tape reader)");
  AddStatus(*dnc, ctx);
}

}  // namespace cellctl
