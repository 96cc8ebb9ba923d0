// Binds a CellView to the bus: subscribes to the cell's state and event topics (never a request, never a
// write), converts the DDS samples into the view's plain inputs, and follows heartbeats for online state.
// Used by cell-dashboard and by `cellctl watch`, so both show the same state.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cell/bus/bus.h"
#include "cell/dashboard/cell_view.h"
#include "cell/health/health.h"
#include "cell/idl/dnc.h"
#include "cell/idl/health.h"
#include "cell/idl/inspection.h"
#include "cell/idl/motion.h"
#include "cell/idl/run.h"
#include "cell/idl/scheduler.h"
#include "cell/idl/station.h"

namespace cell::dashboard {

struct FeedOptions {
  bool axes = true;  // cellctl watch does not plot, so it skips the 50 Hz telemetry
  // Called on the bus thread after each job state sample (the dashboard's PlanSource asks for the plan
  // again); must not block.
  std::function<void()> on_job;
};

// What a settled scheduler says of each station (SettledSchedulerView).
struct SchedulerView {
  std::set<std::string> online, offline;  // by a settled scheduler's heartbeats; both empty before it settles
};

class Feed {
 public:
  Feed(bus::Participant& p, CellView& view, FeedOptions opts = {});
  // Heartbeats: stations and host services going online or offline. Call every 250 ms or so.
  void Tick();
  // The first picture is complete: every station whose heartbeat is heard has sent its status, and a
  // running scheduler its backlog; stations not heard at all are offline by the scheduler's word, or after
  // a grace period without one (HeardStations, as `station ls` does).
  bool Settled(std::chrono::milliseconds waited) const;

 private:
  bus::Participant& p_;
  CellView& view_;
  // What the readers' callbacks write: constructed before the readers, whose callbacks run on the bus thread
  // as soon as each reader exists (a transient-local sample can arrive during the constructor).
  mutable std::mutex mu_;
  const std::function<void()> on_job_;
  std::set<std::string> status_seen_;
  bool backlog_seen_ = false;
  SchedulerView sched_;
  std::chrono::steady_clock::time_point backlog_at_;
  health::Liveness live_;
  bus::Reader<cell::StationStatus> status_;
  bus::Reader<cell::ToolTable> tools_;
  bus::Reader<cell::SchedulerState> backlog_;
  bus::Reader<cell::Alarm> alarms_;  // conditions raised on a station (station ls shows them too)
  bus::Reader<cell::JobInfo> jobs_;
  bus::Reader<cell::RunStatus> runs_;
  bus::Reader<cell::InspectionStored> stored_;
  bus::Reader<cell::StationEvent> events_;
  bus::Reader<cell::DncStatus> dnc_;  // the stations' serial lines (cell-dnc)
  std::optional<bus::Reader<cell::AxisState>> axes_;
};

// What a one-shot reader (`station ls`, `watch --count 1`) knows of the configured stations. kWaiting: an
// announced station's status has not arrived yet; kPartial: some station is neither heard nor reported
// offline by a settled scheduler (only discovery time, or a grace period without a scheduler, tells);
// kComplete: every station is known, so an absent one is offline without waiting for discovery.
enum class Heard { kWaiting, kPartial, kComplete };
// A station a settled scheduler reports online that this reader has not heard yet is kWaiting too: in a
// large cell a newcomer discovers the stations over seconds, and the scheduler's word says one is coming.
Heard HeardStations(const std::vector<std::string>& ids, const health::Liveness& live,
                    const std::function<bool(const std::string&)>& has_status, const SchedulerView& sched);
// What a settled scheduler says of each station (SchedulerState.settled: it has watched longer than its
// discovery window).
SchedulerView SettledSchedulerView(const cell::SchedulerState& s);

}  // namespace cell::dashboard
