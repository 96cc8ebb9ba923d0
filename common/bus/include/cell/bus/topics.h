// The cell's topic and service names: the contract between processes (docs/architecture.md).
// Names use letters, digits, '_' and '/' only (Cyclone rejects others).
#pragma once

#include <string>

#include "cell/bus/backend.h"

namespace cell::bus::topics {

// State topics (kState): last value per key, late joiners get it.
inline constexpr const char* kHealth = "cell/health";                   // ServiceHealth, 1 Hz heartbeat
inline constexpr const char* kStationStatus = "cell/station/status";    // StationStatus
inline constexpr const char* kToolTable = "cell/station/tools";         // ToolTable
inline constexpr const char* kVariables = "cell/station/variables";     // StationVariables
inline constexpr const char* kStationIo = "cell/station/io";            // StationIoState
inline constexpr const char* kStationEvent = "cell/station/event";      // StationEvent (KT-APL EVT)
inline constexpr const char* kStationProgram = "cell/station/program";  // StationProgram, as runs start
inline constexpr const char* kSchedulerState = "cell/scheduler/state";  // SchedulerState (backlog)
inline constexpr const char* kJobState = "cell/job/state";              // JobInfo, key job_id % kJobSlots
inline constexpr const char* kProgramList = "cell/program/list";        // ProgramEntry, key node and name
inline constexpr const char* kDncStatus = "cell/dnc/status";            // DncStatus, key station (cell-dnc)
// Event topics (kEvent): recent history for late joiners.
inline constexpr const char* kRunStatus = "cell/run/status";          // RunStatus
inline constexpr const char* kJobStatus = "cell/job/status";          // JobStatus
inline constexpr const char* kProgramChange = "cell/program/change";  // ProgramChange
inline constexpr const char* kAlarm = "cell/alarm";                   // Alarm
// What the inspection writer made durable (InspectionStored), for viewers.
inline constexpr const char* kInspectionStored = "cell/inspection/stored";
// Telemetry (kTelemetry).
inline constexpr const char* kAxisState = "cell/motion/axes";  // AxisState, 50 Hz wall
// Streams (kStream), per station.
inline std::string Segments(const std::string& station) {
  return "cell/station/" + station + "/segments";
}
inline std::string Probe(const std::string& station) {
  return "cell/station/" + station + "/probe";
}
// State (kState), per station: the run's part model from the program store (PartModel).
inline std::string Part(const std::string& station) {
  return "cell/station/" + station + "/part";
}
// State (kState), per station, between a station's interpreter and its axis servo only: segment credits
// (SegmentProgress), feed hold and overrides (ServoControl), and the tool table the servo's tool changer
// reads (ToolTable, also on kToolTable for the cell). Shared keyed topics made every interpreter match every
// servo: 3 x 32 x 32 reliable matches at 32 stations, for data each reader dropped but its own station's.
inline std::string Progress(const std::string& station) {
  return "cell/station/" + station + "/progress";
}
inline std::string ServoControl(const std::string& station) {
  return "cell/station/" + station + "/control";
}
inline std::string ServoTools(const std::string& station) {
  return "cell/station/" + station + "/servo_tools";
}
// Request/reply services (two kCommand topics each: <name>/request, <name>/reply).
inline constexpr const char* kProgramStore = "cell/program_store";  // ProgramRequest / ProgramReply
inline constexpr const char* kScheduler = "cell/scheduler";         // SchedulerRequest / SchedulerReply
inline constexpr const char* kInspection = "cell/inspection";       // InspectionRequest / InspectionReply
// Dispatches (RunRequest / RunReply): one service for every station. The scheduler is its only client; each
// interpreter answers the requests that name its station (bus::Server's `accept`), and the scheduler drops a
// reply a station writes about another (bus::Client). Per-station topics gave the scheduler two endpoints per
// station it had dispatched to, and Fast DDS 2.9 heartbeats every endpoint of a participant's discovery
// history to every matched participant whenever one more joins it: at 64 stations across four hosts that made
// each `cellctl` call cost the cell about ten times more than the same call before the first dispatch
// (docs/operations.md §9.5, "One dispatch topic").
inline constexpr const char* kStationRun = "cell/station/run";
inline std::string StationCommand(const std::string& station) {
  return "cell/station/" + station + "/command";
}
// The station's serial line (DncRequest / DncReply), served by its cell-dnc.
inline std::string StationDnc(const std::string& station) {
  return "cell/station/" + station + "/dnc";
}

// JobInfo instances: the newest kJobSlots jobs (slot = job_id % kJobSlots), no instance disposed.
inline constexpr int kJobSlots = 1024;

// A station (its interpreter) counts as online while its heartbeat is younger than this.
inline constexpr int kHeartbeatMs = 1000;
inline constexpr int kOfflineAfterMs = 3500;

}  // namespace cell::bus::topics
