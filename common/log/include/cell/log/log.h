// Process-wide logging: one line per event on stderr, naming the service and the station.
//
//   cell::log::Init("cell-interpreter", "KT01");
//   spdlog::info("program {} started", name);
//
// prints, on a terminal or in a pipe,
//   2026-11-22T02:22:04.123Z cell-interpreter[KT01] info: program O1234 started
// and, when stderr is the systemd journal (JOURNAL_STREAM matches stderr), the same line without the
// timestamp and with a "<N>" syslog priority prefix so that journalctl shows the right priority:
//   <6>cell-interpreter[KT01] info: program O1234 started
// Newlines inside a message are written as "\n" so that every event stays one line.
// The level comes from CELL_LOG_LEVEL (trace, debug, info, warn, error, critical, off; default info).
#pragma once

#include <spdlog/spdlog.h>

#include <cstdio>
#include <optional>
#include <string>
#include <string_view>

namespace cell::log {

struct Options {
  // Where lines go. Tests pass a temporary file; services keep stderr.
  std::FILE* out = stderr;
  // Journal format (priority prefix, no timestamp). Default: detected from JOURNAL_STREAM.
  std::optional<bool> journal;
  // Level. Default: CELL_LOG_LEVEL, else info.
  std::optional<spdlog::level::level_enum> level;
};

// Installs the default spdlog logger for this process. Call once at the top of main (calling again
// replaces the logger). An invalid CELL_LOG_LEVEL does not fail: it is reported in a warning line and
// info is used.
void Init(std::string_view service, std::string_view station = {}, const Options& options = {});

// "trace", "debug", "info", "warn" (or "warning"), "error" (or "err"), "critical", "off"; case-insensitive.
// Throws cell::Error(kInvalidArgument) naming the allowed values.
spdlog::level::level_enum ParseLevel(std::string_view name);

// The prefix every line carries: "service[station]" or "service" when station is empty.
std::string Tag(std::string_view service, std::string_view station);

}  // namespace cell::log
