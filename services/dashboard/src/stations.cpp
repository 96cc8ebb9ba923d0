#include "cell/dashboard/stations.h"

#include <cctype>

#include "cell/config/config.h"
#include "cell/machine/machine_config.h"

namespace cell::dashboard {

StationDef MakeStationDef(const cell::config::StationConfig& station,
                          const cell::machine::MachineConfig& machine) {
  StationDef d;
  d.id = station.id;
  d.dialect = station.dialect;
  d.description = station.description;
  d.kind = machine.kind;
  for (int i = 0; i < cell::machine::kNumAxes; ++i) {
    const auto& a = machine.axes[static_cast<size_t>(i)];
    if (!a.present) continue;
    AxisDef x;
    x.name =
        std::string(1, static_cast<char>(std::toupper(cell::machine::kAxisNames[static_cast<size_t>(i)])));
    x.index = i;
    x.rotary = a.type != cell::machine::AxisType::kLinear;
    x.diameter = a.diameter;
    d.axes.push_back(x);
  }
  d.live_tool = machine.live_tool_max_rpm > 0;
  return d;
}

std::vector<StationDef> LoadStationDefs() {
  std::vector<StationDef> out;
  for (auto& id : cell::config::ListStations()) {
    auto st = cell::config::LoadStation(id);
    out.push_back(MakeStationDef(st, cell::machine::LoadMachineConfig(st.file)));
  }
  return out;
}

}  // namespace cell::dashboard
