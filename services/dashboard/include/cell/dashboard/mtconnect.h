// The MTConnect 2.4 agent's information model and documents (MTConnectDevices, MTConnectStreams,
// MTConnectAssets, MTConnectError), valid against the 2.4 `_1.0.xsd` schemas. One Device per station
// (id, uuid and name = the station id); its axes come from the station's configuration.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "cell/dashboard/sequence_buffer.h"
#include "cell/dashboard/stations.h"

namespace cell::dashboard::mtc {

struct DataItem {
  int station = 0;        // index into the stations
  std::string key;        // "exec", "pos:X", ... (what the cell view updates)
  std::string id;         // XML id, unique in the document
  std::string component;  // the id of the component it belongs to
  std::string category;   // SAMPLE, EVENT, CONDITION
  std::string type;       // POSITION, EXECUTION, ...
  std::string sub_type;
  std::string units;
  std::string name;
  std::string element;       // its element in a Streams document: Position, Execution, ...
  double minimum_delta = 0;  // SAMPLE filters (also announced in the probe)
  double period = 0;
};

struct Component {
  int station = 0;
  std::string element;  // Device, Axes, Linear, Rotary, Controller, Path
  std::string id;
  std::string name;
  std::string parent;  // parent component id; "" for the Device
};

// The devices, their components and data items, built once from the station configs.
class DeviceModel {
 public:
  explicit DeviceModel(std::vector<StationDef> stations);
  const std::vector<StationDef>& stations() const { return stations_; }
  const std::vector<DataItem>& items() const { return items_; }
  const std::vector<Component>& components() const { return components_; }
  // The data item of a station by key, -1 when the station has none (e.g. "pos:Y" on a lathe).
  int Find(int station, std::string_view key) const;
  int StationIndex(std::string_view id) const;  // -1 when unknown

 private:
  void Add(int station, const std::string& component, DataItem d);
  std::vector<StationDef> stations_;
  std::vector<DataItem> items_;
  std::vector<Component> components_;
};

// What every header carries.
struct AgentInfo {
  std::string sender = "cell-dashboard";
  std::uint64_t instance_id = 0;   // this agent process (its start, s since the epoch)
  std::int64_t model_time_ns = 0;  // deviceModelChangeTime
  std::size_t buffer_size = 0;
  std::size_t asset_buffer_size = 0;
};

struct ToolAsset {
  std::string station;
  std::string tool;  // "1001", "33412.5"
  int socket = 0;
  double length = 0, diameter = 0, life_left_min = 0;
  bool worn = false, broken = false;
  std::int64_t time_ns = 0;
};
std::string AssetId(const ToolAsset& t);  // "KT01.T1001"

// A timestamp: records::IsoTimeMicros, of now for ns <= 0 (2026-11-24T03:00:00.123456Z).
std::string IsoTime(std::int64_t ns);
std::string XmlEscape(std::string_view s);

// /probe (device < 0: every device).
std::string Devices(const AgentInfo& a, const DeviceModel& m, int device, std::size_t asset_count);
// /current and /sample: observations grouped by device and component; header from the buffer.
std::string Streams(const AgentInfo& a, const DeviceModel& m, const std::vector<const Observation*>& obs,
                    std::uint64_t first, std::uint64_t last, std::uint64_t next, int device);
// /assets, /asset/<id>
std::string Assets(const AgentInfo& a, const std::vector<ToolAsset>& tools);
// Error documents: code one of MTConnect's error codes (OUT_OF_RANGE, INVALID_REQUEST, NO_DEVICE,
// ASSET_NOT_FOUND, UNSUPPORTED, INTERNAL_ERROR, ...).
std::string Error(const AgentInfo& a, std::string_view code, std::string_view text);

}  // namespace cell::dashboard::mtc
