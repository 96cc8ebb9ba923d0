// ISO-8601 UTC times, the one format of every record (DESIGN §6: "times ISO-8601 UTC or null").
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

namespace cell::records {

std::int64_t NowNs();  // wall clock, ns since the epoch

// "2026-11-22T02:40:00Z" for ns since the epoch, in whole seconds: a record's time (job started and
// finished, a decision, an inspection record, a program event). "" for ns <= 0 (not yet).
std::string IsoTime(std::int64_t ns);
// The same with microseconds ("2026-11-24T03:00:00.123456Z"), as MTConnect timestamps carry them.
std::string IsoTimeMicros(std::int64_t ns);
// IsoTime, or null for ns <= 0: how a record's JSON carries a time that may not have happened.
nlohmann::json TimeOrNull(std::int64_t ns);

}  // namespace cell::records
