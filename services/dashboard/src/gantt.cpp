#include "cell/dashboard/gantt.h"

#include <algorithm>

#include "cell/records/time.h"

namespace cell::dashboard {

using nlohmann::json;

namespace {

std::string Text(const json& row, const char* key) {
  auto it = row.find(key);
  return it != row.end() && it->is_string() ? it->get<std::string>() : std::string();
}

// The station's row in hand at `now`, and the first one after it.
std::pair<json, json> CurrentAndNext(const json& planned, const std::string& station,
                                     const std::string& now) {
  json current, next;
  for (const json& r : planned) {
    if (Text(r, "station") != station) continue;
    const std::string start = Text(r, "start"), end = Text(r, "end");
    if (current.is_null() && start <= now && now < end) {
      current = r;
    } else if (next.is_null() && start >= now) {
      next = r;
    }
  }
  return {current, next};
}

}  // namespace

json GanttJson(const std::vector<std::string>& stations, const PlanFetch& plan, const json& ran,
               std::int64_t now_ns) {
  const std::string now = records::IsoTime(now_ns);
  json planned = json::array(), waiting = json::array();
  for (const json& r : plan.rows) {
    if (!Text(r, "station").empty() && !Text(r, "start").empty() && !Text(r, "end").empty()) {
      planned.push_back(r);
    } else {
      waiting.push_back({{"job", r.value("job", json())},
                         {"pallet", r.value("pallet", json())},
                         {"route", r.value("route", json())},
                         {"op", r.value("op", json())},
                         {"waiting_for", r.value("waiting_for", json())}});
    }
  }
  std::stable_sort(planned.begin(), planned.end(), [](const json& a, const json& b) {
    const std::string sa = Text(a, "station"), sb = Text(b, "station");
    return sa != sb ? sa < sb : Text(a, "start") < Text(b, "start");
  });
  json current = json::object(), next = json::object();
  for (const std::string& s : stations) {
    auto [c, n] = CurrentAndNext(planned, s, now);
    current[s] = c;
    next[s] = n;
  }
  return {{"now", now},
          {"fetched", records::TimeOrNull(plan.fetched_ns)},
          {"error", plan.error.empty() ? json() : json(plan.error)},
          {"stations", stations},
          {"planned", planned},
          {"waiting", waiting},
          {"ran", ran.is_array() ? ran : json::array()},
          {"current", current},
          {"next", next}};
}

}  // namespace cell::dashboard
