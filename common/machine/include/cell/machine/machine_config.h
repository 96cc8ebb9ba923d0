// Station machine configuration: the machine tables of deploy/stations/<ID>.toml, read by the axis servo
// and by the dashboard (which axes a station has).
// Tables owned by others ([station] apart from id/dialect, anything unknown) are ignored; [[tools]] is read
// only for its `tool` and `socket` keys (initial magazine contents; common/config reads the rest).
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "cell/tooltable/tooltable.h"

namespace cell::machine {

// The nine axes every station file and motion segment index by (the wire's order, idl/motion.idl): the
// linear X Y Z, the rotary A B C, and the linear co-axes U V W parallel to X Y Z (a KT-APL U-head's U).
inline constexpr int kNumAxes = 9;
enum Axis : int { kX = 0, kY = 1, kZ = 2, kA = 3, kB = 4, kC = 5, kU = 6, kV = 7, kW = 8 };
inline constexpr std::array<char, kNumAxes> kAxisNames = {'x', 'y', 'z', 'a', 'b', 'c', 'u', 'v', 'w'};
inline constexpr bool IsRotary(int axis) {
  return axis >= kA && axis <= kC;
}

enum class AxisType { kLinear, kRotary, kIndex };

// Drive and plant of one axis, on the motor side: rad, N·m, kg·m².
struct DriveConfig {
  double motor_inertia = 0.002;     // kg·m²
  double load_inertia = 0.001;      // kg·m², load reflected to the motor shaft
  double viscous_friction = 0.002;  // N·m·s/rad at the motor
  double max_torque = 20.0;         // N·m (drive current limit)
  double units_per_rev = 10.0;      // mm (linear) or degrees (rotary) of axis travel per motor revolution
  // PID on motor angle; when not given they follow from bandwidth_hz and damping and the nominal inertia.
  double kp = 0.0;  // N·m/rad
  double ki = 0.0;  // N·m/(rad·s)
  double kd = 0.0;  // N·m·s/rad
  double bandwidth_hz = 40.0;
  double damping = 1.0;
  double kvff = 1.0;   // velocity feed-forward, fraction of the nominal viscous friction
  double kaff = 0.95;  // acceleration feed-forward, fraction of the nominal inertia
};

struct AxisConfig {
  bool present = false;
  AxisType type = AxisType::kLinear;
  double min = 0.0, max = 0.0;                  // soft limits, axis units (mm / deg; lathe X as a radius)
  double max_velocity = 0.0;                    // units/min, programmed feed clamp
  double rapid = 0.0;                           // units/min
  double max_acceleration = 0.0;                // units/s²
  double max_jerk = 0.0;                        // units/s³
  double following_error_limit = 0.0;           // units
  bool diameter = false;                        // lathe X: programs give diameters
  double index_increment = 0.0;                 // kIndex: positions are multiples of this (deg)
  double clamp_time = 0.0, unclamp_time = 0.0;  // kIndex, s
  DriveConfig drive;
};

struct PartModelRef {
  int pallet = 0;
  std::filesystem::path file;  // absolute, or relative to the station file's directory when loaded
};

struct MachineConfig {
  std::string station_id;
  std::string dialect;
  std::string source;        // file the config came from (for messages)
  std::string kind = "hmc";  // "hmc" or "lathe"
  double servo_period_s = 0.001;
  double path_tolerance = 0.02;  // mm, blending tolerance for continuous blocks
  double in_position = 0.025;    // mm, exact-stop window (KT-APL G00: 0.025 mm / 0.001 in)
  int queue_capacity = 64;       // segments (credits)
  std::array<AxisConfig, kNumAxes> axes{};
  // Spindle
  double spindle_max_rpm = 4000.0;
  double spindle_accel_rpm_s = 2000.0;
  double spindle_orient_time = 1.5;
  // A lathe's live-tool (M-tool) spindle, for rotating tools on the turret; 0: the machine has none.
  double live_tool_max_rpm = 0.0;
  double live_tool_accel_rpm_s = 0.0;
  // A lathe with a C axis: seconds to join the work spindle as C (Okuma M110) or release it (M109).
  double c_joint_time = 1.0;
  // Devices
  int magazine_sockets = 60;
  double magazine_index_time = 0.1;  // s per socket step
  double tool_change_time = 6.0;     // s, chip to chip without magazine travel
  double pallet_change_time = 25.0;  // s
  double coolant_time = 0.3;         // s
  tooltable::ToolTable tools;        // initial magazine contents (tool and socket of [[tools]])
  std::vector<int> broken_sockets;   // [magazine] broken: the tools there are broken (a G38 check finds it)
  // Probe
  double probe_ball_diameter = 6.0;  // mm
  double probe_max_feed = 2000.0;    // mm/min
  double probe_overtravel = 5.0;     // mm the stylus may deflect past a contact before alarm 602
  std::vector<PartModelRef> part_models;
};

// Parses a station file. Throws cell::Error(kInvalidArgument) naming file, key and allowed range, or
// cell::Error(kNotFound / kIo) when the file is missing or unreadable.
MachineConfig LoadMachineConfig(const std::filesystem::path& file);
// Same from text; `source` names the text in messages and resolves relative part-model paths.
MachineConfig ParseMachineConfig(std::string_view toml_text, const std::string& source);

// The machine kinds a station file may name ([machine] kind) and the words a person reads for each (the
// dashboard's page takes them from here through /api/state).
struct KindInfo {
  std::string_view name;   // "hmc"
  std::string_view title;  // "horizontal machining centre"
};
const std::vector<KindInfo>& MachineKinds();

// A built-in machine for tests and benchmarks, by machine kind: "hmc" (X Y Z + B index, like KT01) or
// "lathe" (X as a diameter, Z, like OK01). Throws cell::Error(kInvalidArgument) for another kind.
MachineConfig DefaultMachineConfig(std::string_view kind);

}  // namespace cell::machine
