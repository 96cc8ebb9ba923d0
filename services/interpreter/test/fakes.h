// Fakes for driving the station core without DDS: a clock that advances only when the core waits (and lets
// the fake servo act then), a servo that takes segments in seq order and reports progress and probe results
// as cell-axis-servo does, and the station's outside world (publications, programs, the inspection writer).
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cell/station/station.h"

namespace cell::station::testing {

class FakeClock final : public Clock {
 public:
  TimePoint Now() override { return now_; }
  std::int64_t WallNs() override {
    return 1'800'000'000'000'000'000 +
           std::chrono::duration_cast<std::chrono::nanoseconds>(now_.time_since_epoch()).count();
  }
  // The core waits: time passes and the world (the fake servo, the test's script) gets its turn.
  void Wait(std::unique_lock<std::mutex>& lk, std::condition_variable& cv, Duration d) override {
    (void)cv;
    lk.unlock();
    now_ += std::min<Duration>(d, step_);
    // A core that waits for ever is a failed test, not a hung one.
    if (++waits_ > kMaxWaits) throw std::runtime_error("the core waited more than 200000 times");
    if (on_wait) on_wait();
    lk.lock();
  }
  void Advance(Duration d) { now_ += d; }
  int waits() const { return waits_; }

  std::function<void()> on_wait;

 private:
  static constexpr int kMaxWaits = 200000;
  TimePoint now_{std::chrono::hours(1)};
  Duration step_ = std::chrono::milliseconds(50);
  int waits_ = 0;
};

// The axis servo as seen over the segment stream (docs/axis-servo.md, "Over DDS"): takes only the next seq
// of its run (a new run only at seq 1), completes `per_wait` segments each time the core waits, grants
// completed + capacity credits, answers probe moves.
class FakeServo final : public ServoLink {
 public:
  explicit FakeServo(std::uint64_t capacity = 4) : capacity_(capacity) {}
  void Attach(Station* s) { station_ = s; }

  void Write(const cell::MotionSegment& seg) override {
    written.push_back(seg);
    if (seg.run_id() == run_ && seg.seq() > completed_)
      max_outstanding = std::max<std::uint64_t>(max_outstanding, seg.seq() - completed_);
    if (drop_writes > 0) {
      --drop_writes;
      return;
    }
    if (seg.run_id() != run_) {
      if (seg.seq() != 1) return;
      run_ = seg.run_id();
      received_ = completed_ = 0;
      queue_.clear();
    }
    if (seg.seq() != received_ + 1) return;  // duplicates and gaps: the re-send brings them in order
    received_ = seg.seq();
    queue_.push_back(seg);
    dirty_ = true;
  }
  std::size_t Matched() override { return matched; }
  std::uint64_t TotalMatched() override { return total_matched; }
  bool WaitForServo(Clock::Duration) override { return matched > 0; }
  // A rejoin heals a one-way deafness (deaf_until_rejoin) and is a new match.
  void Rejoin() override {
    ++rejoins;
    if (unmatched_until_rejoin) matched = 1;
    if (deaf_until_rejoin) {
      drop_writes = 0;
      silent = false;
    }
    ++total_matched;
  }
  void WritePart(const cell::PartModel& part) override {
    parts.push_back(part);
    if (takes_parts) part_run_ = part.run_id();
    dirty_ = true;
  }

  // One turn of the machine: runs up to per_wait queued segments and reports what changed (as the servo
  // does: a servo that takes and completes nothing says nothing).
  void Step() {
    if (!station_ || silent) return;
    if (hold != reported_hold_ || boot_id != reported_boot_ || alarm_code != reported_alarm_) dirty_ = true;
    for (int i = 0; i < per_wait && !queue_.empty() && !hold; ++i) {
      dirty_ = true;
      cell::MotionSegment seg = queue_.front();
      queue_.pop_front();
      ran.push_back(seg);
      completed_ = seg.seq();
      Machine(seg);
      if (seg.kind() == cell::SEGMENT_PROBE) {
        cell::ProbeResult r;
        r.station(seg.station());
        r.run_id(seg.run_id());
        r.seq(seg.seq());
        r.contact(seg.tool_check() ? !broken_sockets.count(tool_socket_) : probe_contact);
        for (size_t a = 0; a < 9; ++a) r.position()[a] = seg.target()[a];
        r.position()[2] = probe_contact_z;
        station_->OnProbe(r);
      }
    }
    if (dirty_) Report();
  }
  void Report() {
    dirty_ = false;
    reported_hold_ = hold;
    reported_boot_ = boot_id;
    reported_alarm_ = alarm_code;
    cell::SegmentProgress p;
    p.station(station_id);
    p.run_id(run_);
    p.completed_seq(completed_);
    p.received_seq(received_);
    p.credit_seq(completed_ + capacity_);
    p.run_machine_s(static_cast<double>(completed_));
    p.feed_hold(hold);
    p.boot_id(boot_id);
    p.part_run_id(part_run_);
    for (const auto& [key, secs] : cut_) {
      cell::ToolCutting c;
      c.tool(key.first);
      c.socket(key.second);
      c.cutting_s(secs);
      p.cutting().push_back(c);
    }
    if (!alarm_code.empty()) {
      p.alarm(true);
      p.alarm_code(alarm_code);
      p.alarm_text(alarm_text);
    }
    station_->OnProgress(p);
  }
  // The machine's state a segment changes: the spindle tool (the socket the station named, else the
  // station file's), the spindle, and `cut_per_feed_s` of cutting per feed move with the spindle turning.
  void Machine(const cell::MotionSegment& seg) {
    if (seg.seq() == 1) cut_.clear();  // a new run counts from zero, as the servo does
    switch (seg.kind()) {
      case cell::SEGMENT_TOOL_CHANGE:
        tool_ = seg.tool().to_string();
        tool_socket_ = seg.tool_socket() > 0 ? seg.tool_socket() : socket_of[tool_];
        break;
      case cell::SEGMENT_SPINDLE:
        spindle_on_ = seg.spindle_mode() == 1 || seg.spindle_mode() == 2;
        break;
      case cell::SEGMENT_LINEAR:
      case cell::SEGMENT_ARC:
        if (spindle_on_ && !tool_.empty()) cut_[{tool_, tool_socket_}] += cut_per_feed_s;
        break;
      default:
        break;
    }
  }
  // Segments of run `run` that the machine ran, by kind.
  std::vector<cell::MotionSegment> Ran(std::int32_t run, cell::SegmentKind kind) const {
    std::vector<cell::MotionSegment> out;
    for (const auto& s : ran)
      if (s.run_id() == run && s.kind() == kind) out.push_back(s);
    return out;
  }

  std::string station_id = "KT01";
  std::size_t matched = 1;
  std::uint64_t total_matched = 1;
  int per_wait = 2;
  int drop_writes = 0;                  // the next n writes are lost (an unmatched reader)
  bool silent = false;                  // reports nothing
  bool deaf_until_rejoin = false;       // drop_writes and silent end at the interpreter's rejoin
  bool unmatched_until_rejoin = false;  // matched = 0 ends at the interpreter's rejoin
  int rejoins = 0;
  bool hold = false;  // the operator's feed hold in effect: nothing completes
  bool probe_contact = true;
  double probe_contact_z = 0;
  bool takes_parts = true;  // acknowledges a part model (false: a servo that cannot read it)
  std::vector<cell::PartModel> parts;
  std::uint64_t boot_id = 77;
  std::string alarm_code, alarm_text;
  std::uint64_t max_outstanding = 0;
  std::vector<cell::MotionSegment> written, ran;
  double cut_per_feed_s = 10;
  std::map<std::string, int> socket_of;  // the magazine by tool number (a tool change without a socket)
  std::set<int> broken_sockets;          // a G38 check of the tool from there finds it broken

 private:
  Station* station_ = nullptr;
  std::uint64_t capacity_;
  std::int32_t run_ = 0, part_run_ = 0;
  std::uint64_t received_ = 0, completed_ = 0;
  std::deque<cell::MotionSegment> queue_;
  std::string tool_;
  int tool_socket_ = 0;
  bool spindle_on_ = false;
  std::map<std::pair<std::string, int>, double> cut_;  // this run's cutting time (cumulative)
  bool dirty_ = true;
  bool reported_hold_ = false;
  std::uint64_t reported_boot_ = 0;
  std::string reported_alarm_;
};

class FakeIo final : public StationIo {
 public:
  void PublishStatus(const cell::StationStatus& s) override { status.push_back(s); }
  void PublishTools(const cell::ToolTable& t) override { tools.push_back(t); }
  void PublishVariables(const cell::StationVariables& v) override { variables.push_back(v); }
  void PublishIo(const cell::StationIoState& s) override { io.push_back(s); }
  void PublishEvent(const cell::StationEvent& e) override { events.push_back(e); }
  void PublishProgram(const cell::StationProgram& p) override { programs_run.push_back(p); }
  void PublishRun(const cell::RunStatus& r) override { runs.push_back(r); }
  void PublishControl(const cell::ServoControl& c) override {
    control.push_back(c);
    if (on_control) on_control(c);
  }
  bool WaitForProgramStore(Clock::Duration timeout) override {
    store_waited.push_back(timeout);
    return !store_absent;
  }
  std::optional<std::string> Program(const std::string& node, const std::string& name) override {
    fetched.push_back(name);
    if (on_fetch) on_fetch(name);
    for (const std::string& n : {node, std::string("HOST")}) {
      auto it = programs.find(n + "/" + name);
      if (it != programs.end()) return it->second;
    }
    return std::nullopt;
  }
  std::optional<std::string> SelectedProgram(const std::string& station) override {
    (void)station;
    return selected;
  }
  std::optional<std::string> ProgramIn(const std::string& node, const std::string& name) override {
    fetched.push_back(node + ":" + name);
    auto it = programs.find(node + "/" + name);
    if (it == programs.end()) return std::nullopt;
    return it->second;
  }
  std::optional<std::string> PartModel(const std::string& node, const std::string& name) override {
    for (const std::string& n : {node, std::string("HOST")}) {
      auto it = part_models.find(n + "/" + name);
      if (it != part_models.end()) return it->second;
      if (programs.count(n + "/" + name)) return std::nullopt;
    }
    return std::nullopt;
  }
  bool DeleteFile(const std::string& node, const std::string& name, const std::string& key) override {
    if (store_down) throw Error(Errc::kUnavailable, "no cell/program_store service");
    deleted.push_back(node + "/" + name + " " + key);
    return programs.erase(node + "/" + name) > 0;
  }
  void SaveFile(const std::string& node, const std::string& name, const std::string& text,
                const SaveAs& as) override {
    if (store_down) throw Error(Errc::kUnavailable, "no cell/program_store service");
    programs[node + "/" + name] = text;
    saved_as[node + "/" + name] = as;
  }
  bool StoreRecord(const cell::InspectionRequest& request) override {
    if (!writer_up) return false;
    if (writer_refuses) throw Error(Errc::kUnavailable, "writer busy");
    records.push_back(request);
    return true;
  }
  // The station's serial line (Okuma READ/WRITE): a READ is answered once `replies` holds a record.
  std::optional<std::string> LineRead(const std::string& holder) override {
    ++line_asks;
    line_holders.push_back(holder);
    if (!line_error.empty()) throw Error(Errc::kUnavailable, line_error);
    if (replies.empty()) return std::nullopt;
    std::string r = replies.front();
    replies.erase(replies.begin());
    return r;
  }
  void LineWrite(const std::string& holder, const std::string& record) override {
    line_holders.push_back(holder);
    if (!line_error.empty()) throw Error(Errc::kUnavailable, line_error);
    written.push_back(record);
  }
  // The last run status of a dispatch.
  std::optional<cell::RunStatus> LastRun(std::int32_t dispatch) const {
    for (auto it = runs.rbegin(); it != runs.rend(); ++it)
      if (it->dispatch_id() == dispatch) return *it;
    return std::nullopt;
  }
  std::map<std::string, double> LastVariables() const {
    std::map<std::string, double> out;
    if (variables.empty()) return out;
    for (const auto& v : variables.back().variables()) out[v.name().to_string()] = v.value();
    return out;
  }

  std::map<std::string, std::string> programs;     // "NODE/NAME" -> text
  std::optional<std::string> selected;             // SelectedProgram: "BS01/MP2:P9" (Balt-System SPG)
  std::map<std::string, std::string> part_models;  // "NODE/NAME" -> text, stored as type part_model
  std::vector<std::string> deleted;                // "NODE/NAME KEY" per DeleteFile
  std::map<std::string, SaveAs> saved_as;          // "NODE/NAME" -> how SaveFile declared it
  std::function<void(const std::string&)> on_fetch;
  bool writer_up = true, writer_refuses = false;
  bool store_down = false;    // SaveFile: the program store is not on the bus
  bool store_absent = false;  // WaitForProgramStore: no store came within the time asked
  std::vector<Clock::Duration> store_waited;
  std::vector<cell::StationStatus> status;
  std::vector<cell::ToolTable> tools;
  std::vector<cell::StationVariables> variables;
  std::vector<cell::StationIoState> io;
  std::vector<cell::StationEvent> events;
  std::vector<cell::StationProgram> programs_run;
  std::vector<cell::RunStatus> runs;
  std::vector<cell::ServoControl> control;
  std::function<void(const cell::ServoControl&)> on_control;  // at each publication
  std::vector<cell::InspectionRequest> records;
  std::vector<std::string> replies, written, line_holders;  // the serial line's records in and out
  std::string line_error;                                   // LineRead/LineWrite fail with it
  int line_asks = 0;
  std::vector<std::string> fetched;
};

}  // namespace cell::station::testing
