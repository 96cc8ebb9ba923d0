// Stations for the dashboard's tests: a KT machining centre (X Y Z + B) and a lathe (X diameter, Z).
#pragma once

#include <string>
#include <vector>

#include "cell/dashboard/cell_view.h"
#include "cell/testing/process.h"

namespace cell::dashboard::testing {

inline std::vector<StationDef> TwoStations() {
  StationDef kt{
      "KT01",
      "ktapl",
      "Kearney & Trecker machining centre",
      "hmc",
      {{"X", 0, false, false}, {"Y", 1, false, false}, {"Z", 2, false, false}, {"B", 4, true, false}}};
  StationDef ok{"OK01", "okuma", "Okuma lathe", "lathe", {{"X", 0, false, true}, {"Z", 2, false, false}}};
  return {kt, ok};
}

inline StatusIn Status(const std::string& station, const std::string& exec, const std::string& program = "",
                       int line = 0, int pallet = 0) {
  StatusIn s;
  s.station = station;
  s.execution = exec;
  s.program = program;
  s.line = line;
  s.pallet = pallet;
  return s;
}

// A tool table from (tool, socket, length, diameter, life, worn, broken) rows.
struct ToolRow {
  std::string tool;
  int socket;
  double length, diameter, life_left_min;
  bool worn, broken;
};
inline tooltable::ToolTable Tools(const std::vector<ToolRow>& rows) {
  std::vector<tooltable::ToolEntry> out;
  for (auto& r : rows) {
    tooltable::ToolEntry e;
    e.tool = r.tool;
    e.socket = r.socket;
    e.length = r.length;
    e.diameter = r.diameter;
    e.life_left_min = r.life_left_min;
    e.worn = r.worn;
    e.broken = r.broken;
    out.push_back(e);
  }
  return tooltable::ToolTable(out);
}

// The MTConnect 2.4 schemas (`_1.0.xsd` variants) the repository carries in tests/schemas/mtconnect, or
// CELL_MTCONNECT_SCHEMAS; "" when they are missing.
std::string SchemaDir();
// Validates a document with xmllint --noout --nonet --schema; returns xmllint's complaint, "" when valid.
std::string Validate(const std::string& xml, const std::string& schema);

}  // namespace cell::dashboard::testing
