#include "cell/dashboard/cell_view.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "cell/records/entries.h"
#include "cell/records/names.h"
#include "cell/records/time.h"
#include "cell/records/values.h"

namespace cell::dashboard {

using nlohmann::json;

namespace {

bool Terminal(const std::string& state) {
  return records::IsTerminalJobState(state);
}

std::string Fixed(double v, int digits) {
  std::string s = fmt::format("{:.{}f}", v, digits);
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  return s == "-0" ? "0" : s;
}

// Why a waiting pallet cannot go to this station, from the decision's view of it.
std::string WhyNot(const DecisionStationIn& c) {
  std::string why;
  auto add = [&](const std::string& s) { why += (why.empty() ? "" : "; ") + s; };
  if (!c.online) add("station offline");
  if (c.fault) add("station in fault");
  if (!c.missing_tools.empty()) {
    std::string tools;
    for (const auto& t : c.missing_tools) tools += (tools.empty() ? "" : ",") + t;
    add("missing tools " + tools);
  }
  return why.empty() ? "not eligible" : why;
}

}  // namespace

CellView::CellView(std::vector<StationDef> stations, ViewOptions opts)
    : model_(std::move(stations)),
      opts_(opts),
      st_(model_.stations().size()),
      buffer_(opts.buffer_size, static_cast<int>(model_.items().size())) {
  const std::int64_t now = Now();
  agent_.instance_id = static_cast<std::uint64_t>(now / 1000000000);
  agent_.model_time_ns = now;
  agent_.buffer_size = opts_.buffer_size;
  agent_.asset_buffer_size = 1024;
  // Every data item starts UNAVAILABLE, as an agent's do until its source reports.
  for (int i = 0; i < static_cast<int>(model_.items().size()); ++i) {
    Observation o;
    o.item = i;
    o.time_ns = now;
    o.value = model_.items()[static_cast<size_t>(i)].category == "CONDITION" ? "" : "UNAVAILABLE";
    if (model_.items()[static_cast<size_t>(i)].category == "CONDITION") o.level = "UNAVAILABLE";
    buffer_.Add(std::move(o));
  }
  for (size_t s = 0; s < st_.size(); ++s) st_[s].card = StationJson(static_cast<int>(s)).dump();
}

std::int64_t CellView::Now() const {
  return records::NowNs();
}

void CellView::Observe(int station, const std::string& key, std::string value, std::int64_t t,
                       const std::string& level, const std::string& code) {
  int item = model_.Find(station, key);
  if (item < 0) return;
  const Observation& last = buffer_.Latest()[static_cast<size_t>(item)];
  if (last.sequence != 0 && last.value == value && last.level == level && last.native_code == code) return;
  Observation o;
  o.item = item;
  o.time_ns = t > 0 ? t : Now();
  o.value = std::move(value);
  o.level = level;
  o.native_code = code;
  buffer_.Add(std::move(o));
}

// The Path's data items take the station's state from the record's rules (records::StateOf), the same
// words `station ls` and the page print.
void CellView::ObserveStatus(int s, std::int64_t t) {
  const StationState& x = st_[static_cast<size_t>(s)];
  const records::StationState state = records::StateOf(Facts(s));
  const std::string un(records::kUnavailable);
  Observe(s, "avail", x.online ? "AVAILABLE" : un, t);
  if (!state.live) {
    for (const char* k : {"exec", "mode", "program", "line", "parts", "tool", "pallet", "message"})
      Observe(s, k, un, t);
    Observe(s, "system", "", t, state.condition);
    return;
  }
  const StatusIn& st = x.status;
  Observe(s, "exec", state.execution, t);
  Observe(s, "mode", "AUTOMATIC", t);  // the cell's stations run what the scheduler dispatches
  Observe(s, "program", st.program.empty() ? un : st.program, t);
  Observe(s, "line", st.line > 0 ? std::to_string(st.line) : un, t);
  Observe(s, "parts", std::to_string(st.part_count), t);
  Observe(s, "tool", st.tool.empty() ? un : st.tool, t);
  Observe(s, "pallet", st.pallet > 0 ? std::to_string(st.pallet) : un, t);
  if (state.condition == "NORMAL")
    Observe(s, "system", "", t, "NORMAL");
  else
    Observe(s, "system", state.alarm_text, t, state.condition, state.alarm_code);
}

void CellView::Push(json ev) {
  ev["id"] = next_event_;
  events_.push_back({next_event_++, ev.dump()});
  while (events_.size() > opts_.event_log) events_.pop_front();
  cv_.notify_all();
}

void CellView::PushStations() {
  for (size_t s = 0; s < st_.size(); ++s) {
    json j = StationJson(static_cast<int>(s));
    std::string text = j.dump();
    if (text == st_[s].card) continue;
    st_[s].card = std::move(text);
    Push({{"type", "station"}, {"station", std::move(j)}});
  }
}

void CellView::Status(const StatusIn& in) {
  std::lock_guard lk(mu_);
  int s = model_.StationIndex(in.station);
  if (s < 0) return;
  StationState& x = st_[static_cast<size_t>(s)];
  x.status = in;
  x.seen = true;
  ObserveStatus(s, in.time_ns);
  PushStations();
}

void CellView::Online(const std::string& station, bool online) {
  std::lock_guard lk(mu_);
  int s = model_.StationIndex(station);
  if (s < 0 || st_[static_cast<size_t>(s)].online == online) return;
  st_[static_cast<size_t>(s)].online = online;
  ObserveStatus(s, Now());
  PushStations();
}

void CellView::Alarm(const std::string& station, const records::StationAlarm& a) {
  std::lock_guard lk(mu_);
  int s = model_.StationIndex(station);
  if (s < 0) return;
  auto& last = st_[static_cast<size_t>(s)].alarm;
  if (last && a.time_ns < last->time_ns) return;  // an older one, delivered late
  last = a;
  ObserveStatus(s, a.time_ns > 0 ? a.time_ns : Now());
  PushStations();
}

void CellView::Service(const std::string& id, bool online) {
  std::lock_guard lk(mu_);
  auto it = services_.find(id);
  if (it != services_.end() && it->second == online) return;
  services_[id] = online;
  Push({{"type", "services"}, {"services", services_}});
}

void CellView::Tools(const std::string& station, const tooltable::ToolTable& table) {
  const auto& tools = table.entries();
  std::lock_guard lk(mu_);
  int s = model_.StationIndex(station);
  if (s < 0) return;
  StationState& x = st_[static_cast<size_t>(s)];
  const std::int64_t t = Now();
  std::map<std::string, const tooltable::ToolEntry*> before;
  for (auto& e : x.tools) before[e.tool] = &e;
  for (auto& e : tools) {
    auto it = before.find(e.tool);
    bool same = it != before.end() && *it->second == e;
    if (!same) Observe(s, "asset_chg", station + ".T" + e.tool, t);
    if (it != before.end()) before.erase(it);
  }
  for (auto& [tool, e] : before) Observe(s, "asset_rem", station + ".T" + tool, t);
  x.tools.assign(tools.begin(), tools.end());
  x.tools_ns = t;
  PushStations();
}

void CellView::Backlog(const std::map<std::string, double>& backlog) {
  std::lock_guard lk(mu_);
  for (auto& [id, b] : backlog) {
    int s = model_.StationIndex(id);
    if (s >= 0) st_[static_cast<size_t>(s)].backlog_s = b;
  }
  PushStations();
}

void CellView::Job(const JobIn& j) {
  std::lock_guard lk(mu_);
  jobs_[j.id] = j;
  // Keep every live job and the newest finished ones.
  size_t finished = 0;
  for (auto& [id, x] : jobs_) finished += Terminal(x.state) ? 1 : 0;
  for (auto it = jobs_.begin(); finished > opts_.jobs_kept && it != jobs_.end();) {
    if (Terminal(it->second.state)) {
      it = jobs_.erase(it);
      --finished;
    } else {
      ++it;
    }
  }
  Push({{"type", "job"}, {"job", records::JobJson(j, false)}});
  PushStations();
}

void CellView::Axes(const AxesIn& a) {
  std::lock_guard lk(mu_);
  int s = model_.StationIndex(a.station);
  if (s < 0) return;
  StationState& x = st_[static_cast<size_t>(s)];
  const StationDef& def = model_.stations()[static_cast<size_t>(s)];
  const std::int64_t tns = a.time_ns > 0 ? a.time_ns : Now();
  const double t = static_cast<double>(tns) * 1e-9;
  x.feed = a.path_feed;
  x.spindle_rpm = a.spindle_rpm;
  x.live_tool_rpm = a.live_tool_rpm;
  std::vector<double> pos;
  for (auto& ax : def.axes) pos.push_back(a.actual[ax.index]);
  if (t - x.last_trail >= opts_.axis_period_s) {
    x.last_trail = t;
    x.trail.emplace_back(t, pos);
    while (!x.trail.empty() && x.trail.front().first < t - opts_.axis_window_s) x.trail.pop_front();
    Push({{"type", "axes"},
          {"station", def.id},
          {"t", t},
          {"pos", pos},
          {"feed", a.path_feed},
          {"spindle_rpm", a.spindle_rpm},
          {"live_tool_rpm", a.live_tool_rpm}});
  }
  if (t - x.last_mtc >= opts_.mtc_axis_period_s) {
    x.last_mtc = t;
    x.last_pos.resize(pos.size(), std::nan(""));
    for (size_t i = 0; i < pos.size(); ++i) {
      if (!std::isnan(x.last_pos[i]) && std::fabs(pos[i] - x.last_pos[i]) < 0.001) continue;
      x.last_pos[i] = pos[i];
      Observe(s, "pos:" + def.axes[i].name, Fixed(pos[i], 4), tns);
    }
    Observe(s, "spindle_speed", Fixed(std::fabs(a.spindle_rpm), 0), tns);
    // A lathe's spindle joined as C (M110) is a contouring axis (MTConnect RotaryMode CONTOUR).
    Observe(s, "spindle_mode", a.c_joined ? "CONTOUR" : "SPINDLE", tns);
    Observe(s, "live_tool_speed", Fixed(std::fabs(a.live_tool_rpm), 0), tns);  // none without a live tool
    Observe(s, "live_tool_mode", "SPINDLE", tns);
    Observe(s, "feed", Fixed(a.path_feed / 60.0, 2), tns);
  }
}

void CellView::Run(const RunIn& r) {
  std::lock_guard lk(mu_);
  TrackVisit(r);
  RunTrack& tr = runs_[r.dispatch_id];
  if (r.programs_done <= tr.done) return;  // an older or repeated sample
  // A sample at a program's end names that program and the machine seconds so far: the difference from
  // the previous end is that program's cycle.
  if (r.programs_done == tr.done + 1 && !r.program.empty()) {
    CycleTime c{r.program, r.station, r.machine_s - tr.end_s, r.time_ns > 0 ? r.time_ns : Now()};
    cycles_.push_back(c);
    while (cycles_.size() > 500) cycles_.pop_front();
    Push({{"type", "cycle"},
          {"cycle",
           {{"program", c.program},
            {"station", c.station},
            {"s", c.seconds},
            {"time", records::TimeOrNull(c.time_ns)}}}});
  }
  tr.done = r.programs_done;
  tr.end_s = r.machine_s;
  while (runs_.size() > 4096) runs_.erase(runs_.begin());
}

// A visit starts at the run's first ACTIVE sample (its started time, else now) and ends at its end; one
// first seen at its end (the dashboard started later) started its machine seconds before.
void CellView::TrackVisit(const RunIn& r) {
  const bool ended = r.state == "COMPLETED" || r.state == "FAILED" || r.state == "CANCELLED";
  auto it = std::find_if(visits_.begin(), visits_.end(),
                         [&](const Visit& v) { return v.dispatch == r.dispatch_id; });
  if (it == visits_.end()) {
    if (r.state != "ACTIVE" && !ended) return;  // QUEUED: not on the machine yet
    Visit v{r.dispatch_id, r.job_id, r.pallet, 1, r.station, r.state, r.started_ns, 0};
    if (auto j = jobs_.find(r.job_id); j != jobs_.end()) v.op = j->second.op_index;
    if (v.start_ns <= 0)
      v.start_ns = ended && r.time_ns > 0 ? r.time_ns - static_cast<std::int64_t>(r.machine_s * 1e9) : Now();
    visits_.push_back(v);
    if (visits_.size() > 200) visits_.pop_front();
    it = std::prev(visits_.end());
  }
  if (ended && it->end_ns == 0) {
    it->end_ns = r.time_ns > 0 ? r.time_ns : Now();
    it->state = r.state;
  }
}

json CellView::Ran() const {
  std::lock_guard lk(mu_);
  json out = json::array();
  for (const Visit& v : visits_)
    out.push_back({{"job", v.job},
                   {"pallet", v.pallet},
                   {"op", v.op},
                   {"station", v.station},
                   {"start", records::TimeOrNull(v.start_ns)},
                   {"end", records::TimeOrNull(v.end_ns)},
                   {"state", v.state}});
  return out;
}

void CellView::Stored(const StoredIn& in) {
  std::lock_guard lk(mu_);
  if (!stored_names_.insert(in.name).second) {  // a re-delivered notice, or a record stored again
    auto it =
        std::find_if(stored_.begin(), stored_.end(), [&](const StoredIn& x) { return x.name == in.name; });
    if (it != stored_.end()) stored_.erase(it);
  }
  stored_.push_front(in);
  while (stored_.size() > 50) {
    stored_names_.erase(stored_.back().name);
    stored_.pop_back();
  }
  Push({{"type", "inspection"}, {"record", StoredJson(in)}});
}

void CellView::ProgramEvent(const EventIn& in) {
  std::lock_guard lk(mu_);
  program_events_.push_front(in);
  while (program_events_.size() > 50) program_events_.pop_back();
  Push({{"type", "program_event"}, {"program_event", EventJson(in)}});
}

json CellView::EventJson(const EventIn& e) {
  return {{"station", e.station},
          {"program", e.program},
          {"line", e.line},
          {"pallet", e.pallet},
          {"dispatch", e.dispatch_id},
          {"text", e.text},
          {"time", records::TimeOrNull(e.time_ns)}};
}

records::StationFacts CellView::Facts(int s) const {
  const StationState& x = st_[static_cast<size_t>(s)];
  const StationDef& d = model_.stations()[static_cast<size_t>(s)];
  return {d.id,       d.dialect, x.online, x.seen ? &x.status : nullptr, x.alarm ? &*x.alarm : nullptr,
          x.backlog_s};
}

// The row `station ls --json` prints (records::StationRow), and what the page adds to it: the station's
// configuration, its tools, and the jobs waiting for it or queued on it.
json CellView::StationJson(int s) const {
  const StationState& x = st_[static_cast<size_t>(s)];
  const StationDef& d = model_.stations()[static_cast<size_t>(s)];
  json axes = json::array(), axis_defs = json::array();
  for (auto& a : d.axes) {
    const std::string label = a.name + (a.diameter ? " (dia)" : "");
    axes.push_back(label);
    axis_defs.push_back({{"name", a.name}, {"label", label}, {"rotary", a.rotary}, {"diameter", a.diameter}});
  }
  int worn = 0, broken = 0;
  for (auto& t : x.tools) {
    worn += t.worn ? 1 : 0;
    broken += t.broken ? 1 : 0;
  }
  json waiting = json::array(), queue = json::array();
  for (auto& [id, j] : jobs_) {
    if (j.state == "WAITING" && !j.decisions.empty()) {
      for (auto& c : j.decisions.back().considered)
        if (c.station == d.id)
          waiting.push_back({{"job", id},
                             {"pallet", j.pallet},
                             {"route", records::TextOrNull(j.route)},
                             {"why", WhyNot(c)}});
    } else if ((j.state == "DISPATCHED" || j.state == "RUNNING") && j.station == d.id) {
      queue.push_back(
          {{"job", id}, {"pallet", j.pallet}, {"route", records::TextOrNull(j.route)}, {"state", j.state}});
    }
  }
  json row = records::StationRow(Facts(s));
  row["description"] = d.description;
  row["kind"] = d.kind;
  row["axes"] = axes;
  row["axis_defs"] = axis_defs;
  row["live_tool"] = d.live_tool;
  row["queued"] = x.status.queued;
  row["tools"] = {{"count", x.tools.size()}, {"worn", worn}, {"broken", broken}};
  row["waiting"] = waiting;
  row["queue"] = queue;
  return row;
}

// The `inspect ls` row of the record (its size is the writer's to know: null here), and what the notice
// carries besides.
json CellView::StoredJson(const StoredIn& s) const {
  json row = records::InspectionRow({s.name, s.station, s.kind, std::nullopt});
  row["job"] = s.job_id;
  row["pallet"] = s.pallet;
  row["dispatch"] = s.dispatch_id;
  row["programs"] = s.programs;
  row["completed"] = s.completed;
  row["reason"] = records::TextOrNull(s.reason);
  row["machine_s"] = s.machine_s;
  row["excerpt"] = records::TextOrNull(s.excerpt);
  row["time"] = records::TimeOrNull(s.time_ns);
  return row;
}

json CellView::Snapshot() const {
  std::lock_guard lk(mu_);
  json stations = json::array(), axes = json::object();
  for (size_t s = 0; s < st_.size(); ++s) {
    stations.push_back(StationJson(static_cast<int>(s)));
    const StationState& x = st_[s];
    json t = json::array(), pos = json::array();
    for (auto& [ts, p] : x.trail) {
      t.push_back(ts);
      pos.push_back(p);
    }
    axes[model_.stations()[s].id] = {{"t", t},
                                     {"pos", pos},
                                     {"feed", x.feed},
                                     {"spindle_rpm", x.spindle_rpm},
                                     {"live_tool_rpm", x.live_tool_rpm}};
  }
  // Newest first: every live job, then finished ones up to 200 rows.
  json jobs = json::array();
  size_t finished = 0;
  for (auto it = jobs_.rbegin(); it != jobs_.rend(); ++it) {
    bool done = Terminal(it->second.state);
    if (done && finished >= 200) continue;
    finished += done ? 1 : 0;
    jobs.push_back(records::JobJson(it->second, false));
  }
  json cycles = json::array();
  for (auto& c : cycles_)
    cycles.push_back({{"program", c.program},
                      {"station", c.station},
                      {"s", c.seconds},
                      {"time", records::TimeOrNull(c.time_ns)}});
  json stored = json::array();
  for (auto& s : stored_) stored.push_back(StoredJson(s));
  json events = json::array();
  for (auto& e : program_events_) events.push_back(EventJson(e));
  return {{"stations", stations},
          {"program_events", events},
          {"jobs", jobs},
          {"cycles", cycles},
          {"inspections", stored},
          {"dnc", DncRows()},
          {"axes", axes},
          {"services", services_},
          {"vocabulary", opts_.vocabulary},
          {"event", next_event_ - 1},
          {"sequence", buffer_.next()},
          {"now", static_cast<double>(Now()) * 1e-9}};
}

std::optional<json> CellView::JobDetail(int id) const {
  std::lock_guard lk(mu_);
  auto it = jobs_.find(id);
  if (it == jobs_.end()) return std::nullopt;
  return records::JobJson(it->second, true);
}

std::optional<std::vector<CellView::Event>> CellView::EventsAfter(std::uint64_t after,
                                                                  std::size_t max) const {
  std::lock_guard lk(mu_);
  std::vector<Event> out;
  if (after + 1 >= next_event_) return out;
  if (events_.empty() || events_.front().id > after + 1) return std::nullopt;
  for (auto i = static_cast<size_t>(after + 1 - events_.front().id); i < events_.size() && out.size() < max;
       ++i)
    out.push_back(events_[i]);
  return out;
}

bool CellView::WaitEvent(std::uint64_t after, std::chrono::milliseconds timeout) const {
  std::unique_lock lk(mu_);
  return cv_.wait_for(lk, timeout, [&] { return next_event_ > after + 1; });
}

std::uint64_t CellView::LastEvent() const {
  std::lock_guard lk(mu_);
  return next_event_ - 1;
}

std::uint64_t CellView::NextSequence() const {
  std::lock_guard lk(mu_);
  return buffer_.next();
}

std::string CellView::Probe(int device) const {
  std::lock_guard lk(mu_);
  size_t assets = 0;
  for (auto& x : st_) assets += x.tools.size();
  return mtc::Devices(agent_, model_, device, assets);
}

std::string CellView::Current(int device) const {
  std::lock_guard lk(mu_);
  std::vector<const Observation*> obs;
  for (auto& o : buffer_.Latest())
    if (o.sequence != 0 && (device < 0 || model_.items()[static_cast<size_t>(o.item)].station == device))
      obs.push_back(&o);
  std::sort(obs.begin(), obs.end(), [](auto* a, auto* b) { return a->sequence < b->sequence; });
  return mtc::Streams(agent_, model_, obs, buffer_.first(), buffer_.last(), buffer_.next(), device);
}

CellView::SampleResult CellView::Sample(std::optional<std::int64_t> from, std::int64_t count,
                                        int device) const {
  std::lock_guard lk(mu_);
  const auto first = static_cast<std::int64_t>(buffer_.first()),
             next = static_cast<std::int64_t>(buffer_.next());
  if (count <= 0 || count > static_cast<std::int64_t>(buffer_.capacity()))
    return {404, mtc::Error(agent_, "OUT_OF_RANGE",
                            fmt::format("'count' must be in 1..{}, got {}", buffer_.capacity(), count))};
  std::int64_t f = from.value_or(first);
  if (f < first || f > next)
    return {404, mtc::Error(agent_, "OUT_OF_RANGE",
                            fmt::format("'from' must be in {}..{} (firstSequence..nextSequence), got {}",
                                        first, next, f))};
  std::uint64_t after = 0;
  auto obs = buffer_.Scan(
      static_cast<std::uint64_t>(f), static_cast<std::size_t>(count),
      [&](const Observation& o) {
        return device < 0 || model_.items()[static_cast<size_t>(o.item)].station == device;
      },
      &after);
  return {200, mtc::Streams(agent_, model_, obs, buffer_.first(), buffer_.last(), after, device)};
}

std::vector<mtc::ToolAsset> CellView::ToolAssets() const {
  std::vector<mtc::ToolAsset> out;
  for (size_t s = 0; s < st_.size(); ++s)
    for (auto& t : st_[s].tools)
      out.push_back({model_.stations()[s].id, t.tool, t.socket, t.length, t.diameter, t.life_left_min, t.worn,
                     t.broken, st_[s].tools_ns});
  return out;
}

bool CellView::HasAsset(const std::string& id) const {
  std::lock_guard lk(mu_);
  for (auto& t : ToolAssets())
    if (mtc::AssetId(t) == id) return true;
  return false;
}

std::string CellView::AssetsDoc(const std::string& id) const {
  std::lock_guard lk(mu_);
  auto all = ToolAssets();
  if (id.empty()) return mtc::Assets(agent_, all);
  std::vector<mtc::ToolAsset> one;
  for (auto& t : all)
    if (mtc::AssetId(t) == id) one.push_back(t);
  if (one.empty()) return mtc::Error(agent_, "ASSET_NOT_FOUND", "no asset " + id);
  return mtc::Assets(agent_, one);
}

std::string CellView::ErrorDoc(std::string_view code, std::string_view text) const {
  std::lock_guard lk(mu_);
  return mtc::Error(agent_, code, text);
}

}  // namespace cell::dashboard
