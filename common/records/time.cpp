#include "cell/records/time.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>

namespace cell::records {

namespace {

// Floor division, so a time before the epoch (a test's) still names its own second.
std::tm Utc(std::int64_t ns, std::int64_t& sub_ns) {
  std::int64_t s = ns / 1000000000;
  sub_ns = ns % 1000000000;
  if (sub_ns < 0) {
    sub_ns += 1000000000;
    --s;
  }
  const std::time_t t = static_cast<std::time_t>(s);
  std::tm tm{};
  gmtime_r(&t, &tm);
  return tm;
}

}  // namespace

std::int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string IsoTime(std::int64_t ns) {
  if (ns <= 0) return "";
  std::int64_t sub = 0;
  const std::tm tm = Utc(ns, sub);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string IsoTimeMicros(std::int64_t ns) {
  std::int64_t sub = 0;
  const std::tm tm = Utc(ns, sub);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  // Six digits by hand: snprintf's range analysis in the sanitizer build cannot see sub is under 1 s.
  std::string out = buf;
  out += '.';
  long long us = std::clamp<long long>(sub / 1000, 0, 999999);
  char digits[6];
  for (int i = 5; i >= 0; --i, us /= 10) digits[i] = static_cast<char>('0' + us % 10);
  out.append(digits, 6);
  out += 'Z';
  return out;
}

nlohmann::json TimeOrNull(std::int64_t ns) {
  return ns > 0 ? nlohmann::json(IsoTime(ns)) : nlohmann::json(nullptr);
}

}  // namespace cell::records
