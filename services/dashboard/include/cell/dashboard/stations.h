// What the dashboard knows of each station from configuration: identity, dialect, machine kind and the
// axes the machine really has (deploy/stations/<ID>.toml, read with cell::machine as the axis servo does),
// so that a lathe shows X/Z and a machining centre X/Y/Z and B without a list of station kinds here.
#pragma once

#include <string>
#include <vector>

namespace cell::config {
struct StationConfig;
}
namespace cell::machine {
struct MachineConfig;
}

namespace cell::dashboard {

struct AxisDef {
  std::string name;       // "X", "Y", "Z", "A", "B", "C", "U", "V", "W" (the configured ones)
  int index = 0;          // into AxisState arrays (x y z a b c u v w)
  bool rotary = false;    // degrees; linear axes are mm
  bool diameter = false;  // lathe X: positions are diameters
};

struct StationDef {
  std::string id;
  std::string dialect;
  std::string description;
  std::string kind;  // "hmc", "lathe", ... as the machine table says
  std::vector<AxisDef> axes;
  bool live_tool = false;  // a lathe's live-tool (M-tool) spindle: a second spindle
};

// From the two config readers' results (tests build these without files).
StationDef MakeStationDef(const cell::config::StationConfig& station,
                          const cell::machine::MachineConfig& machine);
// Every configured station (cell::config::ListStations), in order. Throws cell::Error like LoadStation.
std::vector<StationDef> LoadStationDefs();

}  // namespace cell::dashboard
