// Binds a CellView to the bus: subscribes to the cell's state and event topics (never a request, never a
// write), converts the DDS samples into the view's plain inputs, and follows heartbeats for online state.
// Used by cell-dashboard and by `cellctl watch`, so both show the same state.
#pragma once

#include <memory>
#include <optional>

#include "cell/bus/bus.h"
#include "cell/dashboard/cell_view.h"
#include "cell/health/health.h"
#include "cell/idl/inspection.h"
#include "cell/idl/motion.h"
#include "cell/idl/run.h"
#include "cell/idl/scheduler.h"
#include "cell/idl/station.h"

namespace cell::dashboard {

struct FeedOptions {
  bool axes = true;  // cellctl watch does not plot, so it skips the 50 Hz telemetry
};

class Feed {
 public:
  Feed(bus::Participant& p, CellView& view, FeedOptions opts = {});
  // Heartbeats: stations and host services going online or offline. Call every 250 ms or so.
  void Tick();
  // Readers matched with at least one writer each on the state topics the page needs first.
  int Matched() const;

 private:
  bus::Participant& p_;
  CellView& view_;
  health::Liveness live_;
  bus::Reader<cell::StationStatus> status_;
  bus::Reader<cell::ToolTable> tools_;
  bus::Reader<cell::SchedulerState> backlog_;
  bus::Reader<cell::JobInfo> jobs_;
  bus::Reader<cell::RunStatus> runs_;
  bus::Reader<cell::InspectionStored> stored_;
  std::optional<bus::Reader<cell::AxisState>> axes_;
};

// Conversions (exposed for tests).
const char* ExecutionName(cell::Execution e);
const char* ConditionName(cell::Condition c);
const char* JobStateName(cell::JobState s);
const char* RunStateName(cell::RunState s);
StatusIn FromWire(const cell::StationStatus& s);
JobIn FromWire(const cell::JobInfo& j);

}  // namespace cell::dashboard
