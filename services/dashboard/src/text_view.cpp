#include "cell/dashboard/text_view.h"

#include <fmt/format.h>

#include <algorithm>
#include <ctime>

namespace cell::dashboard {

using nlohmann::json;

namespace {

std::string Str(const json& v, const std::string& none = "-") {
  if (v.is_null()) return none;
  if (v.is_string()) return v.get<std::string>().empty() ? none : v.get<std::string>();
  return v.dump();
}

std::string Dur(double s) {
  long n = static_cast<long>(s + 0.5);
  if (n < 60) return fmt::format("{} s", n);
  if (n < 3600) return fmt::format("{} min {:02} s", n / 60, n % 60);
  return fmt::format("{} h {:02} min", n / 3600, (n % 3600) / 60);
}

std::string Fit(const std::string& s, size_t n) {
  if (s.size() <= n) return s;
  return n > 3 ? s.substr(0, n - 3) + "..." : s.substr(0, n);
}

struct Paint {
  bool on;
  std::string operator()(const std::string& s, const char* code) const {
    return on ? std::string("\x1b[") + code + "m" + s + "\x1b[0m" : s;
  }
};

const char* ExecColour(const std::string& e) {
  if (e == "ACTIVE") return "1;32";
  if (e == "READY") return "1;34";
  if (e == "FEED_HOLD" || e == "INTERRUPTED" || e == "OPTIONAL_STOP" || e == "PROGRAM_STOPPED") return "1;33";
  if (e == "STOPPED") return "1;31";
  if (e == "WAIT") return "1;35";
  if (e == "PROGRAM_COMPLETED") return "1;36";
  return "2";
}

const char* CondColour(const std::string& c) {
  if (c == "NORMAL") return "32";
  if (c == "WARNING") return "1;33";
  if (c == "FAULT") return "1;41;37";
  return "2";
}

const char* JobColour(const std::string& s) {
  if (s == "RUNNING" || s == "COMPLETED") return "32";
  if (s == "WAITING") return "1;33";
  if (s == "FAILED") return "1;31";
  if (s == "DISPATCHED" || s == "QUEUED") return "34";
  return "2";
}

// Padding that ignores the escape codes.
std::string Pad(const std::string& painted, size_t visible, size_t width) {
  return painted + std::string(width > visible ? width - visible : 0, ' ');
}

}  // namespace

std::string RenderText(const json& snap, const TextStyle& style) {
  const Paint paint{style.color};
  const size_t W = static_cast<size_t>(std::max(60, style.width));
  std::string out;
  std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  char clock[32];
  std::strftime(clock, sizeof clock, "%Y-%m-%d %H:%M:%S", &tm);
  std::string head = paint("CELL", "1") + fmt::format("  {}  ", clock);
  for (auto [id, label] :
       {std::pair{"cell-scheduler", "scheduler"}, std::pair{"cell-program-store", "program store"},
        std::pair{"cell-inspection-writer", "inspection writer"}}) {
    bool up = snap["services"].value(id, false);
    head += " " + paint(up ? "●" : "○", up ? "32" : "1;31") + " " + label + (up ? "" : " OFFLINE");
  }
  out += head + "\n\n";

  // Stations
  double max_backlog = 60;
  for (auto& s : snap["stations"]) max_backlog = std::max(max_backlog, s.value("backlog_s", 0.0));
  out += paint(fmt::format("{:<6} {:<17} {:<11} {:<14} {:>5} {:>6} {:<8} {:>5}  {}", "STAT", "EXECUTION",
                           "COND", "PROGRAM", "LINE", "PALLET", "TOOL", "PARTS", "BACKLOG"),
               "2") +
         "\n";
  std::vector<std::string> notes;
  for (auto& s : snap["stations"]) {
    const std::string ex = s["execution"], cond = s["condition"], id = s["id"];
    double backlog = s.value("backlog_s", 0.0);
    const size_t bar_w = 8;
    size_t fill = static_cast<size_t>(bar_w * std::min(1.0, backlog / max_backlog) + 0.5);
    std::string bar;
    for (size_t i = 0; i < bar_w; ++i) bar += i < fill ? "█" : "·";
    out += fmt::format("{:<6} ", Fit(id, 6)) +
           Pad(paint(Fit(ex, 17), ExecColour(ex)), std::min<size_t>(ex.size(), 17), 17) + " " +
           Pad(paint(cond, CondColour(cond)), cond.size(), 11) +
           fmt::format(" {:<14} {:>5} {:>6} {:<8} {:>5}  ", Fit(Str(s["program"]), 14), Str(s["line"]),
                       Str(s["pallet"]), Fit(Str(s["tool"]), 8), Str(s["part_count"])) +
           paint(bar, "34") + " " + Dur(backlog) + "\n";
    if (!s["alarm_code"].is_null() || !s["alarm_text"].is_null())
      notes.push_back(paint(fmt::format("  {} {} {}: {}", id, cond == "FAULT" ? "ALARM" : "warning",
                                        Str(s["alarm_code"], ""), Fit(Str(s["alarm_text"], ""), W - 30)),
                            cond == "FAULT" ? "1;31" : "33"));
    if (ex == "FEED_HOLD")
      notes.push_back(paint("  " + id + " feed hold: the run stands still until cycle start", "33"));
    // What a WAIT or a program stop waits for ("M00 program stop ...: press cycle start"), else the program's
    // message (MSG).
    if (!s.value("status_text", json()).is_null())
      notes.push_back(
          paint("  " + id + " " + Fit(Str(s["status_text"], ""), W - 10), ex == "ACTIVE" ? "2" : "33"));
    if (!s.value("online", false))
      notes.push_back(paint("  " + id + " offline: its CNC is not announced", "2"));
    std::vector<std::string> queued;
    for (auto& q : s["queue"])
      if (q["state"] != "RUNNING")
        queued.push_back(fmt::format("pallet {} (job {})", Str(q["pallet"]), Str(q["job"])));
    if (!queued.empty()) {
      std::string list;
      for (auto& q : queued) list += (list.empty() ? "" : ", ") + q;
      notes.push_back("  " + id + " queued: " + Fit(list, W - 20));
    }
  }
  for (auto& n : notes) out += n + "\n";

  // Pallets that wait: per job, every listed station's reason.
  std::map<int, std::pair<json, std::vector<std::string>>> waiting;
  for (auto& s : snap["stations"])
    for (auto& w : s["waiting"]) {
      auto& e = waiting[w["job"].get<int>()];
      e.first = w;
      e.second.push_back(s["id"].get<std::string>() + " " + w["why"].get<std::string>());
    }
  for (auto& j : snap["jobs"])
    if (j["state"] == "WAITING" && !waiting.count(j["id"].get<int>()))
      waiting[j["id"].get<int>()] = {j, {Str(j["reason"], "no reason given")}};
  if (!waiting.empty()) {
    out += "\n" + paint("WAITING PALLETS", "1;33") + "\n";
    for (auto& [job, w] : waiting) {
      std::string why;
      for (auto& x : w.second) why += (why.empty() ? "" : "; ") + x;
      out += Fit(fmt::format("  pallet {} (job {}{}): {}", Str(w.first["pallet"]), job,
                             w.first.contains("route") && !w.first["route"].is_null()
                                 ? ", route " + Str(w.first["route"])
                                 : "",
                             why),
                 W) +
             "\n";
    }
  }

  // What programs recorded for the supervisor (KT-APL EVT), newest first.
  if (!snap.value("program_events", json::array()).empty()) {
    out += "\n" + paint("EVENTS", "1") + "\n";
    int n = 0;
    for (auto& e : snap["program_events"]) {
      if (n++ >= 5) break;
      std::string when = Str(e["time"], "");
      if (when.size() >= 19) when = when.substr(11, 8);  // hh:mm:ss of the ISO time
      out += Fit(fmt::format("  {} {} pallet {} {} line {}: {}", when, Str(e["station"]), Str(e["pallet"]),
                             Str(e["program"]), Str(e["line"]), Str(e["text"], "")),
                 W) +
             "\n";
    }
  }

  // Serial lines (DNC, docs/dnc.md): state, what they carry and how far, the last error of a line in error.
  if (!snap.value("dnc", json::array()).empty()) {
    out += "\n" + paint("SERIAL LINES", "1") + "\n";
    for (auto& d : snap["dnc"]) {
      const std::string st = Str(d["state"]);
      const char* colour = st == "error" || st == "offline" ? "1;31" : st == "idle" ? "2" : "1;32";
      const auto bytes = d.value("bytes", std::uint64_t{0}), total = d.value("total", std::uint64_t{0});
      std::string tail =
          fmt::format(" {:<20} {}", Fit(Str(d["program"]), 20),
                      total > 0 ? fmt::format("{}/{} bytes", bytes, total) : fmt::format("{} bytes", bytes));
      if (st == "error") tail += "  " + Str(d["last_error"], "");
      const size_t head = 2 + 6 + 1 + 14 + 1 + 10;  // the columns before `tail`
      out += fmt::format("  {:<6} {:<14} ", Fit(Str(d["station"]), 6), Fit(Str(d["device"]), 14)) +
             Pad(paint(st, colour), st.size(), 10) + Fit(tail, W - head) + "\n";
    }
  }

  // Jobs
  out += "\n" +
         paint(fmt::format("{:>5} {:<10} {:<12} {:>6} {:<7} {:>5} {:>9}  {}", "JOB", "STATE", "ROUTE",
                           "PALLET", "STATION", "OP", "CYCLE", "REASON"),
               "2") +
         "\n";
  int shown = 0;
  for (auto& j : snap["jobs"]) {
    if (shown++ >= style.jobs) break;
    const std::string st = j["state"];
    std::string route = !j["route"].is_null()      ? Str(j["route"])
                        : !j["schedule"].is_null() ? Str(j["schedule"])
                                                   : Str(j["kind"]);
    std::string cycle = j["cycle_s"].is_null() ? "-" : fmt::format("{:.1f} s", j["cycle_s"].get<double>());
    std::string line =
        fmt::format("{:>5} ", j["id"].get<int>()) + Pad(paint(st, JobColour(st)), st.size(), 10) +
        fmt::format(" {:<12} {:>6} {:<7} {:>5} {:>9}  ", Fit(route, 12), Str(j["pallet"]), Str(j["station"]),
                    fmt::format("{}/{}", Str(j["op_index"]), Str(j["op_count"])), cycle);
    out += line + Fit(Str(j["reason"], ""), W > 70 ? W - 70 : 10) + "\n";
  }
  if (snap["jobs"].empty()) out += paint("  no jobs yet", "2") + "\n";
  return out;
}

}  // namespace cell::dashboard
