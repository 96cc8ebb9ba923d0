// The dashboard's read-only view of the cell: the latest state of every station, tool table, backlog, job
// (with its decisions), axis positions, cycle times and inspection record, fed from the bus (feed.h) or by
// tests. It renders three things from one state under one lock:
//   - the page's state as JSON (Snapshot) and the changes since as a numbered event log (for SSE);
//   - the MTConnect agent's observations in a sequence buffer (Probe, Current, Sample, Assets);
//   - the same state for `cellctl watch` (text_view.h renders the snapshot).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cell/dashboard/mtconnect.h"
#include "cell/dashboard/sequence_buffer.h"
#include "cell/dashboard/stations.h"
#include "cell/records/job.h"
#include "cell/records/station.h"
#include "cell/tooltable/tooltable.h"

namespace cell::dashboard {

// ---- inputs: plain copies of the cell's topics (feed.h converts the DDS types) ----
// The station's status, the job and its decisions are the cell's records (common/records): the page and
// MTConnect render them through the same module as `cellctl` and the scheduler.
using StatusIn = records::StationStatus;  // cell/station/status

struct AxesIn {  // cell/motion/axes
  std::string station;
  double actual[9] = {};
  double spindle_rpm = 0;
  double path_feed = 0;      // units/min
  double live_tool_rpm = 0;  // a lathe's live tool, signed as spindle_rpm
  bool c_joined = false;     // the work spindle is joined as the C axis (Okuma M110)
  std::int64_t time_ns = 0;
};

using DecisionStationIn = records::DecisionStation;
using DecisionIn = records::Decision;
using JobIn = records::Job;  // cell/job/state

struct RunIn {  // cell/run/status
  int dispatch_id = 0;
  std::string station, program, state;  // state: QUEUED, ACTIVE, COMPLETED, FAILED, CANCELLED
  int job_id = 0, pallet = 0, programs_done = 0;
  double machine_s = 0;
  std::int64_t time_ns = 0;     // when it finished (0: not yet)
  std::int64_t started_ns = 0;  // when it started (0: not yet, or not said)
};

struct StoredIn {    // cell/inspection/stored
  std::string kind;  // "run" or "inspection"
  std::string name, station;
  int job_id = 0, pallet = 0, dispatch_id = 0;
  std::vector<std::string> programs;
  bool completed = false;
  std::string reason;
  double machine_s = 0;
  std::string excerpt;
  std::int64_t time_ns = 0;
};

struct EventIn {  // cell/station/event: what a program recorded (KT-APL EVT)
  std::string station, program, text;
  int dispatch_id = 0, pallet = 0, line = 0;
  std::int64_t time_ns = 0;
};

struct DncIn {  // cell/dnc/status: a station's serial line, as its cell-dnc publishes it (docs/dnc.md)
  std::string station, device;
  std::string state;                   // idle, sending, receiving, dripping, reading, writing
  std::string program;                 // "NODE:NAME" of the transfer running or last run
  std::uint64_t bytes = 0, total = 0;  // total 0: not known (a receive)
  double seconds = 0, rate = 0, stopped_s = 0;
  std::uint32_t stalls = 0, transfers = 0, errors = 0;
  std::string last_error;
  bool failed = false;  // the last transfer ended with last_error
  std::int64_t time_ns = 0;
};

struct ViewOptions {
  std::size_t buffer_size = 16384;  // MTConnect observations kept for /sample (~120 B each: 2 MB)
  std::size_t event_log = 4096;     // page events kept for reconnecting browsers
  std::size_t jobs_kept = 1024;     // finished jobs kept (live ones always)
  double axis_window_s = 60;        // the page's axis plot
  double axis_period_s = 0.2;       // one page point per station per period
  double mtc_axis_period_s = 0.1;   // MTConnect position samples at most this often per station
  double dnc_grace_s = 3;           // a DNC line's sample this young outweighs a heartbeat not heard yet
  // The page's words for what the station files name: {"dialects": {name: title}, "kinds": {kind: title}}
  // (the interpreter registry's and the machine tables' own; the page keeps no list of them).
  nlohmann::json vocabulary = nlohmann::json::object();
};

class CellView {
 public:
  CellView(std::vector<StationDef> stations, ViewOptions opts = {});

  // ---- inputs (any thread) ----
  void Status(const StatusIn& s);
  void Online(const std::string& station, bool online);                    // the interpreter's heartbeat
  void Alarm(const std::string& station, const records::StationAlarm& a);  // cell/alarm on a station
  void Service(const std::string& service_id, bool online);  // host services, for the page's header
  void Tools(const std::string& station, const tooltable::ToolTable& tools);  // cell/station/tools
  void Backlog(const std::map<std::string, double>& backlog_s);
  void Job(const JobIn& j);
  void Axes(const AxesIn& a);
  void Run(const RunIn& r);
  void Stored(const StoredIn& s);
  void ProgramEvent(const EventIn& e);
  // DNC lines (dnc_view.cpp): a line's state, and whether its cell-dnc still heartbeats (a killed one's last
  // state stays on the topic; a sample younger than dnc_grace_s outweighs a heartbeat not heard yet).
  void Dnc(const DncIn& d);
  void DncOnline(const std::string& station, bool online);
  std::vector<std::string> DncStations() const;

  // ---- the page ----
  nlohmann::json Snapshot() const;                        // whole state; "event" = the last event id in it
  std::optional<nlohmann::json> JobDetail(int id) const;  // a job with its decisions
  // What actually ran, for the Gantt chart beside the plan (gantt.h): the newest 200 visits, each a dispatch
  // from its start to its end (null while it runs): [{job, pallet, op, station, start, end, state}].
  nlohmann::json Ran() const;
  struct Event {
    std::uint64_t id;
    std::string data;  // JSON text
  };
  // Events after `after` (at most `max`); nullopt when some of them already left the log (resync).
  std::optional<std::vector<Event>> EventsAfter(std::uint64_t after, std::size_t max) const;
  // Blocks until an event after `after` exists or the timeout passes; true if one exists.
  bool WaitEvent(std::uint64_t after, std::chrono::milliseconds timeout) const;
  std::uint64_t LastEvent() const;

  // ---- MTConnect ----
  const mtc::DeviceModel& model() const { return model_; }
  std::string Probe(int device) const;
  std::string Current(int device) const;
  struct SampleResult {
    int status;        // HTTP status
    std::string body;  // MTConnectStreams or MTConnectError
  };
  SampleResult Sample(std::optional<std::int64_t> from, std::int64_t count, int device) const;
  std::string AssetsDoc(const std::string& id) const;  // "" = all; unknown id: an error document
  bool HasAsset(const std::string& id) const;
  std::string ErrorDoc(std::string_view code, std::string_view text) const;
  std::uint64_t NextSequence() const;

 private:
  struct StationState {
    bool online = false;
    bool seen = false;  // a status sample arrived
    StatusIn status;
    std::optional<records::StationAlarm> alarm;  // the latest raised on the station
    double backlog_s = 0;
    std::vector<tooltable::ToolEntry> tools;
    std::int64_t tools_ns = 0;  // when the table last arrived (the assets' timestamp)
    double feed = 0, spindle_rpm = 0, live_tool_rpm = 0;
    // Page plot: wall seconds and one position per configured axis.
    std::deque<std::pair<double, std::vector<double>>> trail;
    double last_trail = -1e18, last_mtc = -1e18;
    std::vector<double> last_pos;
    std::string card;  // the last station JSON sent to browsers
  };
  struct CycleTime {
    std::string program, station;
    double seconds;
    std::int64_t time_ns;
  };
  struct RunTrack {
    int done = 0;
    double end_s = 0;
  };
  struct Visit {  // one dispatch as it ran (Ran)
    int dispatch = 0, job = 0, pallet = 0, op = 1;
    std::string station, state;
    std::int64_t start_ns = 0, end_ns = 0;
  };
  void TrackVisit(const RunIn& r);  // with mu_ held

  std::int64_t Now() const;
  void Observe(int station, const std::string& key, std::string value, std::int64_t t,
               const std::string& level = "", const std::string& code = "");
  void ObserveStatus(int s, std::int64_t t);
  void Push(nlohmann::json ev);  // with mu_ held
  void PushStations();           // station cards that changed, with mu_ held
  records::StationFacts Facts(int s) const;
  nlohmann::json StationJson(int s) const;
  nlohmann::json StoredJson(const StoredIn& s) const;
  static nlohmann::json EventJson(const EventIn& e);
  nlohmann::json DncRows() const;  // with mu_ held
  std::vector<mtc::ToolAsset> ToolAssets() const;

  mtc::DeviceModel model_;
  ViewOptions opts_;
  mtc::AgentInfo agent_;
  mutable std::mutex mu_;
  mutable std::condition_variable cv_;
  std::vector<StationState> st_;
  std::map<std::string, bool> services_;
  std::map<std::int64_t, JobIn> jobs_;
  std::map<int, RunTrack> runs_;
  std::deque<CycleTime> cycles_;
  std::deque<Visit> visits_;
  std::deque<StoredIn> stored_;
  std::deque<EventIn> program_events_;  // newest first, the last 50
  std::set<std::string> stored_names_;
  struct DncLine {
    DncIn in;
    bool online = true;
    std::chrono::steady_clock::time_point heard;  // when the last sample arrived
  };
  std::map<std::string, DncLine> dnc_;  // by station
  SequenceBuffer buffer_;
  std::deque<Event> events_;
  std::uint64_t next_event_ = 1;
};

}  // namespace cell::dashboard
