// The station row (DESIGN §6 `station ls`, §6a `/api/state` `stations`) and the rules that decide what a
// station's state reads. `cellctl station ls`, the dashboard's page and /api/state, and its MTConnect
// observations all take the state from StationRow, so no view can say NORMAL where another says UNAVAILABLE.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "cell/idl/health.h"
#include "cell/idl/station.h"

namespace cell::records {

// What a station last said of itself on cell/station/status, in words.
struct StationStatus {
  std::string station;
  std::string execution = "READY";   // ExecutionName
  std::string condition = "NORMAL";  // ConditionName
  std::string alarm_code, alarm_text;
  std::string status_text;  // what a WAIT or a program stop waits for, else the program's last message
  std::string program;
  int line = 0;
  int pallet = 0;
  std::uint32_t part_count = 0;
  std::string tool;
  int dispatch_id = 0;
  int queued = 0;
  std::int64_t time_ns = 0;
};
StationStatus FromWire(const cell::StationStatus& s);

// A condition another process raises on the station (cell/alarm: the scheduler's DUPLICATE when two
// processes claim its interpreter or servo). The latest by time counts.
struct StationAlarm {
  bool active = false;
  std::string code, text;
  std::int64_t time_ns = 0;
};
StationAlarm FromWire(const cell::Alarm& a);

// Everything a row is made of.
struct StationFacts {
  std::string id, dialect;
  bool online = false;                    // announced: its interpreter's heartbeat is heard
  const StationStatus* status = nullptr;  // its last status, if any arrived
  const StationAlarm* alarm = nullptr;    // the latest alarm raised on it, if any
  double backlog_s = 0;                   // the scheduler's backlog (0 when none is known)
};

// The state rules. A station reports its state only while announced and after its first status: otherwise
// execution and condition read UNAVAILABLE and the rest is null (as MTConnect reports a source that is
// gone). An active alarm raised on an announced station makes its condition FAULT with that code and text.
struct StationState {
  bool live = false;  // announced and its status known: the fields below come from it
  std::string execution, condition, alarm_code, alarm_text;
};
StationState StateOf(const StationFacts& f);

// {id, dialect, online, execution, condition, alarm_code, alarm_text, backlog_s, pallet, program, line,
// status_text, tool, part_count}: empty strings and zero pallet/line are null; everything but id, dialect,
// online and backlog_s is null while the station is not live.
nlohmann::json StationRow(const StationFacts& f);

}  // namespace cell::records
