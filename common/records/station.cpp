#include "cell/records/station.h"

#include "cell/records/names.h"
#include "cell/records/values.h"

namespace cell::records {

using nlohmann::json;

StationStatus FromWire(const cell::StationStatus& s) {
  StationStatus in;
  in.station = s.station().to_string();
  in.execution = std::string(ExecutionName(s.execution()));
  in.condition = std::string(ConditionName(s.condition()));
  in.alarm_code = s.alarm_code().to_string();
  in.alarm_text = s.alarm_text().to_string();
  in.status_text = s.status_text().to_string();
  in.program = s.program().to_string();
  in.line = s.line();
  in.pallet = s.pallet();
  in.part_count = s.part_count();
  in.tool = s.tool().to_string();
  in.dispatch_id = s.dispatch_id();
  in.queued = s.queued();
  in.time_ns = s.updated_ns();
  return in;
}

StationAlarm FromWire(const cell::Alarm& a) {
  return {a.active(), a.code().to_string(), a.text().to_string(), a.time_ns()};
}

StationState StateOf(const StationFacts& f) {
  StationState st;
  st.live = f.online && f.status != nullptr;
  if (!st.live) {
    st.execution = st.condition = std::string(kUnavailable);
    return st;
  }
  st.execution = f.status->execution;
  st.condition = f.status->condition;
  st.alarm_code = f.status->alarm_code;
  st.alarm_text = f.status->alarm_text;
  if (f.alarm != nullptr && f.alarm->active) {
    st.condition = "FAULT";
    st.alarm_code = f.alarm->code;
    st.alarm_text = f.alarm->text;
  }
  return st;
}

json StationRow(const StationFacts& f) {
  const StationState st = StateOf(f);
  json row = {{"id", f.id},
              {"dialect", f.dialect},
              {"online", f.online},
              {"execution", st.execution},
              {"condition", st.condition},
              {"alarm_code", TextOrNull(st.alarm_code)},
              {"alarm_text", TextOrNull(st.alarm_text)},
              {"backlog_s", f.backlog_s},
              {"pallet", nullptr},
              {"program", nullptr},
              {"line", nullptr},
              {"status_text", nullptr},
              {"tool", nullptr},
              {"part_count", nullptr}};
  if (!st.live) return row;
  const StationStatus& s = *f.status;
  if (s.pallet > 0) row["pallet"] = s.pallet;
  if (s.line > 0) row["line"] = s.line;
  row["program"] = TextOrNull(s.program);
  row["status_text"] = TextOrNull(s.status_text);
  row["tool"] = TextOrNull(s.tool);
  row["part_count"] = s.part_count;
  return row;
}

}  // namespace cell::records
