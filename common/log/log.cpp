#include "cell/log/log.h"

#include <spdlog/sinks/base_sink.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <mutex>

#include "cell/error/error.h"

namespace cell::log {
namespace {

// syslog priorities (sd-daemon.h SD_* prefixes) for each spdlog level.
int SyslogPriority(spdlog::level::level_enum level) {
  switch (level) {
    case spdlog::level::trace:
    case spdlog::level::debug:
      return 7;
    case spdlog::level::info:
      return 6;
    case spdlog::level::warn:
      return 4;
    case spdlog::level::err:
      return 3;
    case spdlog::level::critical:
      return 2;
    default:
      return 6;
  }
}

std::string_view LevelWord(spdlog::level::level_enum level) {
  switch (level) {
    case spdlog::level::trace:
      return "trace";
    case spdlog::level::debug:
      return "debug";
    case spdlog::level::info:
      return "info";
    case spdlog::level::warn:
      return "warning";
    case spdlog::level::err:
      return "error";
    case spdlog::level::critical:
      return "critical";
    default:
      return "off";
  }
}

// True when stderr is connected to the journal: systemd sets JOURNAL_STREAM to "<dev>:<inode>" of the
// stream it hands the service; a child that inherited the variable but not the stream must not match.
bool StderrIsJournal(std::FILE* out) {
  const char* js = std::getenv("JOURNAL_STREAM");
  if (js == nullptr || out == nullptr) return false;
  struct stat st {};
  if (fstat(fileno(out), &st) != 0) return false;
  unsigned long long dev = 0, ino = 0;
  if (std::sscanf(js, "%llu:%llu", &dev, &ino) != 2) return false;
  return static_cast<unsigned long long>(st.st_dev) == dev &&
         static_cast<unsigned long long>(st.st_ino) == ino;
}

class LineSink final : public spdlog::sinks::base_sink<std::mutex> {
 public:
  LineSink(std::FILE* out, std::string tag, bool journal)
      : out_(out), tag_(std::move(tag)), journal_(journal) {}

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    std::string line;
    line.reserve(tag_.size() + msg.payload.size() + 48);
    if (journal_) {
      line += fmt::format("<{}>", SyslogPriority(msg.level));
    } else {
      auto t = std::chrono::time_point_cast<std::chrono::milliseconds>(msg.time);
      auto ms = t.time_since_epoch().count() % 1000;
      std::time_t secs = std::chrono::system_clock::to_time_t(t);
      std::tm tm{};
      gmtime_r(&secs, &tm);
      line += fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}.{:03}Z ", tm.tm_year + 1900, tm.tm_mon + 1,
                          tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, ms);
    }
    line += tag_;
    line += ' ';
    line += LevelWord(msg.level);
    line += ": ";
    for (char c : std::string_view(msg.payload.data(), msg.payload.size())) {
      if (c == '\n') {
        line += "\\n";
      } else if (c == '\r') {
        line += "\\r";
      } else {
        line += c;
      }
    }
    line += '\n';
    std::fwrite(line.data(), 1, line.size(), out_);
    std::fflush(out_);
  }
  void flush_() override { std::fflush(out_); }

 private:
  std::FILE* out_;
  std::string tag_;
  bool journal_;
};

}  // namespace

std::string Tag(std::string_view service, std::string_view station) {
  if (station.empty()) return std::string(service);
  return fmt::format("{}[{}]", service, station);
}

spdlog::level::level_enum ParseLevel(std::string_view name) {
  std::string n(name);
  std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return std::tolower(c); });
  if (n == "trace") return spdlog::level::trace;
  if (n == "debug") return spdlog::level::debug;
  if (n == "info") return spdlog::level::info;
  if (n == "warn" || n == "warning") return spdlog::level::warn;
  if (n == "error" || n == "err") return spdlog::level::err;
  if (n == "critical") return spdlog::level::critical;
  if (n == "off") return spdlog::level::off;
  throw Error(
      Errc::kInvalidArgument,
      fmt::format("log level '{}' is not one of trace, debug, info, warn, error, critical, off", name));
}

void Init(std::string_view service, std::string_view station, const Options& options) {
  bool journal = options.journal.has_value() ? *options.journal : StderrIsJournal(options.out);
  auto sink = std::make_shared<LineSink>(options.out, Tag(service, station), journal);
  auto logger = std::make_shared<spdlog::logger>(std::string(service), std::move(sink));
  std::string bad_level;
  spdlog::level::level_enum level = spdlog::level::info;
  if (options.level.has_value()) {
    level = *options.level;
  } else if (const char* env = std::getenv("CELL_LOG_LEVEL"); env != nullptr && *env != '\0') {
    try {
      level = ParseLevel(env);
    } catch (const Error& e) {
      bad_level = e.what();
    }
  }
  logger->set_level(level);
  logger->flush_on(spdlog::level::trace);
  spdlog::set_default_logger(logger);
  if (!bad_level.empty()) spdlog::warn("CELL_LOG_LEVEL: {}; using info", bad_level);
}

}  // namespace cell::log
