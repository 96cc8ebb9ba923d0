#include "cell/dashboard/feed.h"

#include <utility>

#include "cell/bus/topics.h"
#include "cell/config/config.h"
#include "cell/dnc/client.h"
#include "cell/records/names.h"
#include "cell/tooltable/wire.h"

namespace cell::dashboard {

namespace topics = bus::topics;

namespace {

DncIn DncFromWire(const cell::DncStatus& d) {
  DncIn in;
  in.station = d.station().to_string();
  in.device = d.device().to_string();
  in.state = std::string(dnc::StateName(d.state()));
  in.program = d.program().to_string();
  in.bytes = d.bytes();
  in.total = d.total();
  in.seconds = d.seconds();
  in.rate = d.rate();
  in.stopped_s = d.stopped_s();
  in.stalls = d.stalls();
  in.transfers = d.transfers();
  in.errors = d.errors();
  in.last_error = d.last_error().to_string();
  in.failed = d.failed();
  in.time_ns = d.updated_ns();
  return in;
}

}  // namespace

Feed::Feed(bus::Participant& p, CellView& view, FeedOptions opts)
    : p_(p),
      view_(view),
      on_job_(std::move(opts.on_job)),
      live_(p),
      status_(p, topics::kStationStatus, bus::QosKind::kState,
              [this](const cell::StationStatus& s, const bus::SampleInfo&) {
                view_.Status(records::FromWire(s));
                std::lock_guard lk(mu_);
                status_seen_.insert(s.station().to_string());
              }),
      tools_(p, topics::kToolTable, bus::QosKind::kState,
             [this](const cell::ToolTable& t, const bus::SampleInfo&) {
               view_.Tools(t.station().to_string(), tooltable::FromWire(t));
             }),
      backlog_(p, topics::kSchedulerState, bus::QosKind::kState,
               [this](const cell::SchedulerState& s, const bus::SampleInfo&) {
                 std::map<std::string, double> b;
                 for (auto& x : s.backlog()) b[x.station().to_string()] = x.backlog_s();
                 view_.Backlog(b);
                 std::lock_guard lk(mu_);
                 if (!backlog_seen_) backlog_at_ = std::chrono::steady_clock::now();
                 backlog_seen_ = true;
                 sched_ = SettledSchedulerView(s);
               }),
      alarms_(p, topics::kAlarm, bus::QosKind::kEvent,
              [this](const cell::Alarm& a, const bus::SampleInfo&) {
                view_.Alarm(a.station().to_string(), records::FromWire(a));
              }),
      jobs_(p, topics::kJobState, bus::QosKind::kState,
            [this](const cell::JobInfo& j, const bus::SampleInfo&) {
              view_.Job(records::FromWire(j));
              if (on_job_) on_job_();
            }),
      runs_(p, topics::kRunStatus, bus::QosKind::kEvent,
            [this](const cell::RunStatus& r, const bus::SampleInfo&) {
              RunIn in;
              in.dispatch_id = r.dispatch_id();
              in.station = r.station().to_string();
              in.program = r.program().to_string();
              in.state = std::string(records::RunStateName(r.state()));
              in.job_id = r.job_id();
              in.pallet = r.pallet();
              in.programs_done = r.programs_done();
              in.machine_s = r.machine_s();
              in.time_ns = r.finished_ns() > 0 ? r.finished_ns() : 0;
              in.started_ns = r.started_ns() > 0 ? r.started_ns() : 0;
              view_.Run(in);
            }),
      stored_(p, topics::kInspectionStored, bus::QosKind::kEvent,
              [this](const cell::InspectionStored& s, const bus::SampleInfo&) {
                StoredIn in;
                in.kind = s.kind() == cell::STORED_RUN ? "run" : "inspection";
                in.name = s.name().to_string();
                in.station = s.station().to_string();
                if (s.kind() == cell::STORED_RUN) {
                  const auto& r = s.run();
                  in.job_id = r.job_id();
                  in.pallet = r.pallet();
                  in.dispatch_id = r.dispatch_id();
                  for (auto& prog : r.programs()) in.programs.push_back(prog.to_string());
                  in.completed = r.completed();
                  in.reason = r.reason().to_string();
                  in.machine_s = r.machine_s();
                }
                in.excerpt = s.excerpt().to_string();
                in.time_ns = s.time_ns();
                view_.Stored(in);
              }),
      events_(p, topics::kStationEvent, bus::QosKind::kEvent,
              [this](const cell::StationEvent& e, const bus::SampleInfo&) {
                EventIn in;
                in.station = e.station().to_string();
                in.program = e.program().to_string();
                in.text = e.text().to_string();
                in.dispatch_id = e.dispatch_id();
                in.pallet = e.pallet();
                in.line = e.line();
                in.time_ns = e.time_ns();
                view_.ProgramEvent(in);
              }),
      dnc_(p, topics::kDncStatus, bus::QosKind::kState,
           [this](const cell::DncStatus& d, const bus::SampleInfo&) { view_.Dnc(DncFromWire(d)); }) {
  if (opts.axes)
    axes_.emplace(p, topics::kAxisState, bus::QosKind::kTelemetry,
                  [this](const cell::AxisState& a, const bus::SampleInfo&) {
                    AxesIn in;
                    in.station = a.station().to_string();
                    for (size_t i = 0; i < 9; ++i) in.actual[i] = a.actual()[i];
                    in.spindle_rpm = a.spindle_rpm();
                    in.path_feed = a.path_feed();
                    in.live_tool_rpm = a.live_tool_rpm();
                    in.c_joined = a.c_joined();
                    in.time_ns = a.wall_ns();
                    view_.Axes(in);
                  });
}

void Feed::Tick() {
  for (auto& st : view_.model().stations()) view_.Online(st.id, live_.StationOnline(st.id));
  for (const char* s : {"cell-program-store", "cell-scheduler", "cell-inspection-writer"})
    view_.Service(s, live_.Online(s));
  for (auto& station : view_.DncStations()) view_.DncOnline(station, live_.Online("cell-dnc/" + station));
}

bool Feed::Settled(std::chrono::milliseconds waited) const {
  std::lock_guard lk(mu_);
  std::vector<std::string> ids;
  for (auto& st : view_.model().stations()) ids.push_back(st.id);
  const Heard heard = HeardStations(
      ids, live_, [this](const std::string& id) { return status_seen_.count(id) > 0; }, sched_);
  if (heard == Heard::kWaiting) return false;
  if (live_.Online("cell-scheduler")) {
    // The scheduler's job states come from another writer of the same process: matched, and the moment
    // its first transient-local samples take to follow the backlog's.
    if (!backlog_seen_ || jobs_.Matched() == 0) return false;
    if (std::chrono::steady_clock::now() - backlog_at_ < std::chrono::milliseconds(200)) return false;
  }
  return heard == Heard::kComplete || waited >= std::chrono::milliseconds(1500);
}

Heard HeardStations(const std::vector<std::string>& ids, const health::Liveness& live,
                    const std::function<bool(const std::string&)>& has_status, const SchedulerView& sched) {
  Heard heard = Heard::kComplete;
  for (auto& id : ids) {
    if (live.StationOnline(id)) {
      if (!has_status(id)) return Heard::kWaiting;
    } else if (sched.online.count(id)) {
      return Heard::kWaiting;
    } else if (!sched.offline.count(id)) {
      heard = Heard::kPartial;
    }
  }
  return heard;
}

SchedulerView SettledSchedulerView(const cell::SchedulerState& s) {
  SchedulerView out;
  if (!s.settled()) return out;
  for (auto& b : s.backlog()) (b.online() ? out.online : out.offline).insert(b.station().to_string());
  return out;
}

}  // namespace cell::dashboard
