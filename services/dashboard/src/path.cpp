#include "cell/dashboard/path.h"

#include <algorithm>
#include <functional>
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
                   }),
      programs_reader_(p, bus::topics::kStationProgram, bus::QosKind::kState,
                       [this](const cell::StationProgram& r, const bus::SampleInfo&) {
                         std::lock_guard lk(data_mu_);
                         programs_[r.station().to_string()] = r;
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

// What the station published as its run started (topics::kStationProgram): the text it runs, readable by
// a viewer under DDS Security; nullopt when the station runs another program or published it without its
// text (too long), with the reason in `why`.
std::optional<Paths::Source> Paths::FromStation(const std::string& station, const std::string& program,
                                                std::string& why) {
  std::lock_guard lk(data_mu_);
  auto it = programs_.find(station);
  if (it == programs_.end() || it->second.program().to_string() != program) return std::nullopt;
  const cell::StationProgram& p = it->second;
  if (p.size() > p.text().size()) {
    why = program + " is " + std::to_string(p.size()) + " characters, more than the " +
          std::to_string(p.text().max_size) + " a station publishes";
    return std::nullopt;
  }
  Source s;
  s.text = p.text().to_string();
  s.node = p.node().to_string();
  s.label = "run " + std::to_string(p.dispatch_id());
  s.key = s.label + "\n" + std::to_string(std::hash<std::string>{}(s.text));
  return s;
}

// From the program store, as the station looks a program up (docs/station.md): its namespace, then HOST.
Paths::Source Paths::FromStore(const std::string& station, const std::string& program,
                               const std::string& prefix) {
  std::string why;
  program_store::Client* store = Store(why);
  if (!store) throw Error(Errc::kUnavailable, prefix + why);
  for (const std::string& ns : {station, std::string("HOST")})
    if (auto file = store->Fetch(ns, program)) {
      const uint32_t revision = file->info.value("revision", 0u);
      Source s;
      s.text = std::move(file->content);
      s.node = ns;
      s.revision = revision;
      s.label = ns + " revision " + std::to_string(revision);
      s.key = s.label;
      return s;
    }
  throw Error(Errc::kNotFound, prefix + "no program '" + program + "' in " + station + " or HOST");
}

PathAnswer Paths::Build(const std::string& station, const std::string& program) {
  if (program.empty()) return {404, {{"error", station + " has run no program yet"}}};
  const config::StationConfig st = interp::LoadStation(station);
  std::string why;
  // The text the station runs, as it published it; another program (?program=) from the store.
  std::optional<Source> from = FromStation(st.id, program, why);
  if (!from) from = FromStore(st.id, program, why.empty() ? why : why + "; ");
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
  const std::string key = st.id + "\n" + program + "\n" + from->key + "\n" + std::to_string(tools_rev);
  if (auto c = cache_.find(key); c != cache_.end()) return {200, c->second};
  const interp::Dialect& d = interp::DialectOrThrow(st.dialect);
  opt.dialect = std::string(d.name());
  opt.program_name = program;
  opt.program_text = std::move(from->text);
  opt.params = st.params;
  // A library the program calls comes from the store: the program's namespace, the station's, then HOST,
  // each asked once (a viewer under DDS Security may not ask: the path then stops at the call, the note says
  // why).
  std::vector<std::string> namespaces;
  for (const std::string& ns : {from->node, st.id, std::string("HOST")})
    if (std::find(namespaces.begin(), namespaces.end(), ns) == namespaces.end()) namespaces.push_back(ns);
  opt.library = [this, namespaces](const std::string& lib) -> std::optional<std::string> {
    std::string why;
    program_store::Client* store = Store(why);
    if (!store) return std::nullopt;
    for (const std::string& ns : namespaces)
      if (auto text = store->Get(ns, lib)) return text;
    return std::nullopt;
  };
  const interp::MachineKind machine = StationMachine(st, d);
  Plot plot({machine, program + " (" + opt.dialect + ", " + from->label + ", station " + st.id + ")"});
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
            {"node", from->node},
            {"revision", from->revision ? nlohmann::json(*from->revision) : nlohmann::json()},
            {"source", from->label},
            {"dialect", opt.dialect},
            {"machine", machine == interp::MachineKind::kLathe ? "lathe" : "machining centre"},
            {"note", note}});
  if (cache_.size() >= 64) cache_.clear();  // a handful of stations and programs; bounded all the same
  cache_[key] = j;
  return {200, std::move(j)};
}

}  // namespace cell::dashboard
