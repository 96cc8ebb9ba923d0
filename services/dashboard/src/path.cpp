#include "cell/dashboard/path.h"

#include <vector>

#include "cell/bus/topics.h"
#include "cell/config/config.h"
#include "cell/error/error.h"
#include "cell/interp/interp.h"
#include "cell/interp/station_rules.h"
#include "cell/machine/machine_config.h"
#include "cell/program_store/client.h"
#include "cell/tooltable/wire.h"

namespace cell::dashboard {

namespace {

using interp::Plot;

// A run that never ends (a program looping on an input it never gets offline) stops being drawn here.
constexpr int kMaxMoves = 20000;

nlohmann::json Xyz(const std::array<double, 3>& p) {
  return nlohmann::json::array({p[0], p[1], p[2]});
}

// As the station draws: its file's [machine] kind, else its dialect's.
interp::MachineKind StationMachine(const config::StationConfig& st, const interp::Dialect& d) {
  try {
    return machine::LoadMachineConfig(st.file).kind == interp::MachineKindName(interp::MachineKind::kLathe)
               ? interp::MachineKind::kLathe
               : interp::MachineKind::kMachiningCentre;
  } catch (const cell::Error&) {
    return d.machine();
  }
}

int HttpStatus(const cell::Error& e) {
  return e.code() == Errc::kNotFound ? 404 : e.code() == Errc::kInvalidArgument ? 400 : 503;
}

}  // namespace

nlohmann::json PathJson(const Plot& plot) {
  nlohmann::json moves = nlohmann::json::array();
  for (const Plot::Move& m : plot.moves()) {
    nlohmann::json j = {
        {"kind", Plot::KindName(m.kind)}, {"line", m.line}, {"from", Xyz(m.from)}, {"to", Xyz(m.to)}};
    if (m.kind == Plot::MoveKind::kArc && m.first >= 0 && m.second >= 0 && m.first != m.second) {
      j["center"] = Xyz(m.center);
      j["plane"] = {m.first, m.second};
      j["cw"] = m.cw;
    }
    moves.push_back(std::move(j));
  }
  const size_t ops = plot.started() ? plot.moves().size() + 1 : 0;
  return {{"svg", plot.Svg()},
          {"start", plot.started() ? Xyz(plot.start()) : nlohmann::json()},
          {"moves", std::move(moves)},
          {"motion_ops", ops}};
}

Paths::Paths(bus::Participant& p)
    : p_(p),
      tools_reader_(p, bus::topics::kToolTable, bus::QosKind::kState,
                    [this](const cell::ToolTable& t, const bus::SampleInfo&) {
                      std::lock_guard lk(data_mu_);
                      tools_[t.station().to_string()] = t;
                    }),
      vars_reader_(p, bus::topics::kVariables, bus::QosKind::kState,
                   [this](const cell::StationVariables& v, const bus::SampleInfo&) {
                     std::lock_guard lk(data_mu_);
                     vars_[v.station().to_string()] = v;
                   }) {}

Paths::~Paths() = default;

// The store's client, made on first use: a viewer under DDS Security may not write its request topic, and
// the page says so instead of the dashboard failing to start.
program_store::Client* Paths::Store(std::string& why) {
  if (store_) return store_.get();
  try {
    store_ = std::make_unique<program_store::Client>(p_, bus::Millis(5000));
  } catch (const std::exception& e) {
    why = std::string("the dashboard cannot read the program store: ") + e.what();
  }
  return store_.get();
}

PathAnswer Paths::Path(const std::string& station, const std::string& program) {
  std::lock_guard lk(mu_);
  try {
    return Build(station, program);
  } catch (const cell::Error& e) {
    return {HttpStatus(e), {{"error", e.what()}}};
  } catch (const std::exception& e) {
    return {500, {{"error", e.what()}}};
  }
}

PathAnswer Paths::Build(const std::string& station, const std::string& program) {
  if (program.empty()) return {404, {{"error", station + " has run no program yet"}}};
  const config::StationConfig st = interp::LoadStation(station);
  std::string why;
  program_store::Client* store = Store(why);
  if (!store) return {503, {{"error", why}}};
  // As the station looks a program up (docs/station.md): its namespace, then HOST.
  const std::vector<std::string> namespaces = {st.id, "HOST"};
  std::optional<program_store::Client::File> file;
  std::string node;
  for (const auto& ns : namespaces)
    if ((file = store->Fetch(ns, program))) {
      node = ns;
      break;
    }
  if (!file) return {404, {{"error", "no program '" + program + "' in " + st.id + " or HOST"}}};
  interp::RunOptions opt;
  opt.tools = tooltable::ToolTable(st.tools);
  uint32_t tools_rev = 0;
  {
    std::lock_guard lk(data_mu_);
    if (auto t = tools_.find(st.id); t != tools_.end())
      opt.tools = tooltable::FromWire(t->second), tools_rev = t->second.revision();
    if (auto v = vars_.find(st.id); v != vars_.end())
      for (const auto& x : v->second.variables()) opt.variables[x.name().to_string()] = x.value();
  }
  const uint32_t revision = file->info.value("revision", 0u);
  const std::string key = st.id + "\n" + node + "\n" + program + "\n" + std::to_string(revision) + "\n" +
                          std::to_string(tools_rev);
  if (auto c = cache_.find(key); c != cache_.end()) return {200, c->second};
  const interp::Dialect& d = interp::DialectOrThrow(st.dialect);
  opt.dialect = std::string(d.name());
  opt.program_name = program;
  opt.program_text = std::move(file->content);
  opt.params = st.params;
  opt.library = [store, namespaces](const std::string& lib) -> std::optional<std::string> {
    for (const auto& ns : namespaces)
      if (auto text = store->Get(ns, lib)) return text;
    return std::nullopt;
  };
  const interp::MachineKind machine = StationMachine(st, d);
  Plot plot({machine, program + " (" + opt.dialect + ", " + node + ", station " + st.id + ")"});
  auto run = interp::StartRun(opt);
  interp::Step s;
  for (run->NextInto(s); s.kind == interp::Step::kCanon && plot.moves().size() < kMaxMoves; run->NextInto(s))
    plot.Add(s.canon);
  std::string note = s.kind == interp::Step::kError ? s.diag.Format() : "";
  if (s.kind == interp::Step::kCanon) note = "drawn up to its first " + std::to_string(kMaxMoves) + " moves";
  if (!note.empty()) plot.SetNote(note);
  nlohmann::json j = PathJson(plot);
  j.update({{"station", st.id},
            {"program", program},
            {"node", node},
            {"revision", revision},
            {"dialect", opt.dialect},
            {"machine", machine == interp::MachineKind::kLathe ? "lathe" : "machining centre"},
            {"note", note}});
  if (cache_.size() >= 64) cache_.clear();  // a handful of stations and programs; bounded all the same
  cache_[key] = j;
  return {200, std::move(j)};
}

}  // namespace cell::dashboard
