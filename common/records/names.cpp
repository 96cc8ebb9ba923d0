#include "cell/records/names.h"

#include <array>
#include <utility>

namespace cell::records {

namespace {

constexpr std::array<std::pair<cell::Execution, std::string_view>, 10> kExecution{{
    {cell::EXECUTION_UNAVAILABLE, "UNAVAILABLE"},
    {cell::EXECUTION_READY, "READY"},
    {cell::EXECUTION_ACTIVE, "ACTIVE"},
    {cell::EXECUTION_INTERRUPTED, "INTERRUPTED"},
    {cell::EXECUTION_FEED_HOLD, "FEED_HOLD"},
    {cell::EXECUTION_STOPPED, "STOPPED"},
    {cell::EXECUTION_OPTIONAL_STOP, "OPTIONAL_STOP"},
    {cell::EXECUTION_PROGRAM_STOPPED, "PROGRAM_STOPPED"},
    {cell::EXECUTION_PROGRAM_COMPLETED, "PROGRAM_COMPLETED"},
    {cell::EXECUTION_WAIT, "WAIT"},
}};

constexpr std::array<std::pair<cell::JobState, std::string_view>, 7> kJobState{{
    {cell::JOB_QUEUED, "QUEUED"},
    {cell::JOB_WAITING, "WAITING"},
    {cell::JOB_DISPATCHED, "DISPATCHED"},
    {cell::JOB_RUNNING, "RUNNING"},
    {cell::JOB_COMPLETED, "COMPLETED"},
    {cell::JOB_FAILED, "FAILED"},
    {cell::JOB_CANCELLED, "CANCELLED"},
}};

constexpr std::array<std::pair<cell::RunState, std::string_view>, 5> kRunState{{
    {cell::RUN_QUEUED, "QUEUED"},
    {cell::RUN_ACTIVE, "ACTIVE"},
    {cell::RUN_COMPLETED, "COMPLETED"},
    {cell::RUN_FAILED, "FAILED"},
    {cell::RUN_CANCELLED, "CANCELLED"},
}};

template <typename Table, typename E>
std::string_view Find(const Table& table, E value, std::string_view otherwise) {
  for (const auto& [v, name] : table)
    if (v == value) return name;
  return otherwise;
}

}  // namespace

std::string_view ExecutionName(cell::Execution e) {
  return Find(kExecution, e, kUnavailable);  // an out-of-range wire value is no state at all
}

std::string_view ConditionName(cell::Condition c) {
  return c == cell::CONDITION_FAULT ? "FAULT" : c == cell::CONDITION_WARNING ? "WARNING" : "NORMAL";
}

std::string_view JobStateName(cell::JobState s) {
  return Find(kJobState, s, "QUEUED");
}

std::optional<cell::JobState> JobStateFromName(std::string_view name) {
  for (const auto& [v, n] : kJobState)
    if (n == name) return v;
  return std::nullopt;
}

bool IsTerminalJobState(std::string_view name) {
  return name == "COMPLETED" || name == "FAILED" || name == "CANCELLED";
}

std::string_view RunStateName(cell::RunState s) {
  return Find(kRunState, s, "QUEUED");
}

}  // namespace cell::records
