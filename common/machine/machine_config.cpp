#include "cell/machine/machine_config.h"

#include <fmt/format.h>

#include <toml++/toml.h>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>

#include "cell/error/error.h"
#include "cell/toml/parse.h"

namespace cell::machine {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Reads keys of one table, turning every problem into "FILE: KEY: reason (allowed RANGE)".
class TableReader {
 public:
  TableReader(const std::string& source, std::string prefix, const toml::table* table)
      : source_(source), prefix_(std::move(prefix)), table_(table) {}

  bool exists() const { return table_ != nullptr; }
  void Mark(std::string_view key) const { seen_.insert(std::string(key)); }
  // Every key of the table must have been read: a misspelt key is an error, not a silent default.
  void Done() const {
    if (!table_) return;
    for (auto&& [k, v] : *table_) {
      if (seen_.count(std::string(k.str()))) continue;
      std::string allowed;
      for (const auto& a : seen_) allowed += (allowed.empty() ? "" : ", ") + a;
      Fail(k.str(), fmt::format("unknown key (allowed: {})", allowed));
    }
  }
  bool has(std::string_view key) const { return table_ && table_->contains(key); }

  [[noreturn]] void Fail(std::string_view key, const std::string& reason) const {
    throw Error(Errc::kInvalidArgument, fmt::format("{}: {}{}: {}", source_, prefix_, key, reason));
  }

  // A number in [lo, hi] (open at lo when lo_open). Missing: `fallback`, or an error when none.
  double Number(std::string_view key, double lo, double hi, std::optional<double> fallback,
                std::string_view unit = "", bool lo_open = false) const {
    Mark(key);
    std::string range =
        fmt::format("{}{}, {}]{}{}", lo_open ? "(" : "[", Fmt(lo), Fmt(hi), unit.empty() ? "" : " ", unit);
    const toml::node* n = table_ ? table_->get(key) : nullptr;
    if (!n) {
      if (fallback) return *fallback;
      Fail(key, fmt::format("missing; allowed range {}", range));
    }
    std::optional<double> v;
    if (auto f = n->value_exact<double>())
      v = *f;
    else if (auto i = n->value_exact<int64_t>())
      v = static_cast<double>(*i);
    if (!v) Fail(key, fmt::format("must be a number in {}", range));
    if (!std::isfinite(*v) || *v < lo || *v > hi || (lo_open && *v == lo))
      Fail(key, fmt::format("{} is outside the allowed range {}", Fmt(*v), range));
    return *v;
  }

  int Integer(std::string_view key, int lo, int hi, std::optional<int> fallback) const {
    Mark(key);
    const toml::node* n = table_ ? table_->get(key) : nullptr;
    std::string range = fmt::format("[{}, {}]", lo, hi);
    if (!n) {
      if (fallback) return *fallback;
      Fail(key, fmt::format("missing; allowed range {}", range));
    }
    auto i = n->value_exact<int64_t>();
    if (!i) Fail(key, fmt::format("must be an integer in {}", range));
    if (*i < lo || *i > hi) Fail(key, fmt::format("{} is outside the allowed range {}", *i, range));
    return static_cast<int>(*i);
  }

  bool Bool(std::string_view key, bool fallback) const {
    Mark(key);
    const toml::node* n = table_ ? table_->get(key) : nullptr;
    if (!n) return fallback;
    auto b = n->value_exact<bool>();
    if (!b) Fail(key, "must be true or false");
    return *b;
  }

  std::string Choice(std::string_view key, std::initializer_list<std::string_view> allowed,
                     std::optional<std::string> fallback) const {
    Mark(key);
    std::string list;
    for (auto a : allowed) list += fmt::format("{}\"{}\"", list.empty() ? "" : ", ", a);
    const toml::node* n = table_ ? table_->get(key) : nullptr;
    if (!n) {
      if (fallback) return *fallback;
      Fail(key, fmt::format("missing; allowed values {}", list));
    }
    auto s = n->value_exact<std::string>();
    if (s)
      for (auto a : allowed)
        if (*s == a) return *s;
    Fail(key, fmt::format("{} is not one of {}", s ? "\"" + *s + "\"" : std::string("value"), list));
  }

  std::string String(std::string_view key, std::optional<std::string> fallback) const {
    Mark(key);
    const toml::node* n = table_ ? table_->get(key) : nullptr;
    if (!n) {
      if (fallback) return *fallback;
      Fail(key, "missing; must be a string");
    }
    auto s = n->value_exact<std::string>();
    if (!s) Fail(key, "must be a string");
    return *s;
  }

  const toml::table* Sub(std::string_view key) const {
    Mark(key);
    const toml::node* n = table_ ? table_->get(key) : nullptr;
    if (!n) return nullptr;
    if (!n->is_table()) Fail(key, "must be a table");
    return n->as_table();
  }

 private:
  static std::string Fmt(double v) {
    if (v == kInf) return "inf";
    if (v == -kInf) return "-inf";
    return fmt::format("{:g}", v);
  }
  const std::string& source_;
  std::string prefix_;
  const toml::table* table_;
  mutable std::set<std::string> seen_;
};

void ReadDrive(const std::string& src, const std::string& prefix, const toml::table* t, DriveConfig& d,
               bool rotary) {
  TableReader r(src, prefix, t);
  if (!r.exists()) r.Fail("", "missing table (motor and load inertia, friction, torque, units_per_rev)");
  d.motor_inertia = r.Number("motor_inertia", 0, 10, std::nullopt, "kg·m²", true);
  d.load_inertia = r.Number("load_inertia", 0, 100, std::nullopt, "kg·m²");
  d.viscous_friction = r.Number("viscous_friction", 0, 100, std::nullopt, "N·m·s/rad");
  d.max_torque = r.Number("max_torque", 0, 10000, std::nullopt, "N·m", true);
  d.units_per_rev =
      r.Number("units_per_rev", 0, rotary ? 360.0 : 100.0, std::nullopt, rotary ? "deg/rev" : "mm/rev", true);
  d.bandwidth_hz = r.Number("bandwidth_hz", 0, 200, 40.0, "Hz", true);
  d.damping = r.Number("damping", 0.3, 3, 1.0);
  d.kp = r.Number("kp", 0, 1e9, 0.0, "N·m/rad");
  d.ki = r.Number("ki", 0, 1e12, 0.0, "N·m/(rad·s)");
  d.kd = r.Number("kd", 0, 1e7, 0.0, "N·m·s/rad");
  d.kvff = r.Number("kvff", 0, 1.5, 1.0);
  d.kaff = r.Number("kaff", 0, 1.5, 0.95);
  r.Done();
}

void ReadAxis(const std::string& src, int index, const toml::table* t, const MachineConfig& m,
              AxisConfig& a) {
  const char name = kAxisNames[index];
  const bool rotary_name = IsRotary(index);
  TableReader r(src, fmt::format("axes.{}.", name), t);
  a.present = true;
  std::string type =
      r.Choice("type", {"linear", "rotary", "index"}, std::string(rotary_name ? "rotary" : "linear"));
  a.type = type == "linear" ? AxisType::kLinear : type == "rotary" ? AxisType::kRotary : AxisType::kIndex;
  if (rotary_name && a.type == AxisType::kLinear) r.Fail("type", "axes a, b, c are rotary or index");
  if (!rotary_name && a.type != AxisType::kLinear) r.Fail("type", "axes x, y, z, u, v, w are linear");
  const bool rot = a.type != AxisType::kLinear;
  const std::string_view u = rot ? "deg" : "mm";
  a.min = r.Number("min", -1e5, 1e5, std::nullopt, u);
  a.max = r.Number("max", -1e5, 1e5, std::nullopt, u);
  if (a.max <= a.min) r.Fail("max", fmt::format("{:g} must be greater than min {:g}", a.max, a.min));
  a.max_velocity = r.Number("max_velocity", 0, 1e6, std::nullopt, rot ? "deg/min" : "mm/min", true);
  a.rapid = r.Number("rapid", 0, 1e6, std::nullopt, rot ? "deg/min" : "mm/min", true);
  a.max_acceleration = r.Number("max_acceleration", 0, 1e6, std::nullopt, rot ? "deg/s²" : "mm/s²", true);
  a.max_jerk = r.Number("max_jerk", 0, 1e9, std::nullopt, rot ? "deg/s³" : "mm/s³", true);
  a.following_error_limit = r.Number("following_error_limit", 0, 100, std::nullopt, u, true);
  a.diameter = r.Bool("diameter", false);
  if (a.diameter && index != kX) r.Fail("diameter", "only the X axis of a lathe is programmed in diameter");
  if (a.diameter && m.kind != "lathe") r.Fail("diameter", "only allowed when machine.kind = \"lathe\"");
  if (a.type == AxisType::kIndex) {
    a.index_increment = r.Number("index_increment", 0, 360, std::nullopt, "deg", true);
    a.clamp_time = r.Number("clamp_time", 0, 60, 0.5, "s");
    a.unclamp_time = r.Number("unclamp_time", 0, 60, 0.5, "s");
  }
  ReadDrive(src, fmt::format("axes.{}.drive.", name), r.Sub("drive"), a.drive, rot);
  r.Done();
  // The drive must be able to produce the configured acceleration; otherwise every rapid is a DIFF over.
  const double to_rad = 2 * M_PI / a.drive.units_per_rev;
  const double need = (a.drive.motor_inertia + a.drive.load_inertia) * a.max_acceleration * to_rad +
                      a.drive.viscous_friction * a.rapid / 60.0 * to_rad;
  if (need > a.drive.max_torque)
    r.Fail("drive.max_torque",
           fmt::format("{:g} N·m cannot give max_acceleration at rapid (needs {:.3g} N·m)",
                       a.drive.max_torque, need));
}

}  // namespace

MachineConfig ParseMachineConfig(std::string_view text, const std::string& source) {
  toml::table root = tomlfile::Parse(text, source);
  MachineConfig m;
  m.source = source;
  TableReader station(source, "station.", root["station"].as_table());
  if (station.exists()) {
    m.station_id = station.String("id", std::string());
    m.dialect = station.String("dialect", std::string());
  }
  TableReader mach(source, "machine.", root["machine"].as_table());
  if (!mach.exists()) mach.Fail("", "missing table [machine]");
  m.kind = mach.Choice("kind", {MachineKinds()[0].name, MachineKinds()[1].name, MachineKinds()[2].name},
                       std::nullopt);
  m.servo_period_s = mach.Number("servo_period_ms", 0.1, 10, 1.0, "ms") / 1000.0;
  m.path_tolerance = mach.Number("path_tolerance", 0.001, 1, 0.02, "mm");
  m.in_position = mach.Number("in_position", 0.001, 1, 0.025, "mm");
  m.queue_capacity = mach.Integer("queue_capacity", 2, 4096, 64);
  mach.Done();

  const toml::table* axes = root["axes"].as_table();
  if (!axes) mach.Fail("", "missing table [axes] (one sub-table per axis: [axes.x], ...)");
  for (auto&& [key, node] : *axes) {
    std::string k(key.str());
    int idx = -1;
    for (int i = 0; i < kNumAxes; ++i)
      if (k.size() == 1 && k[0] == kAxisNames[i]) idx = i;
    if (idx < 0)
      throw Error(Errc::kInvalidArgument,
                  fmt::format("{}: axes.{}: unknown axis; allowed x, y, z, a, b, c, u, v, w", source, k));
    if (!node.is_table())
      throw Error(Errc::kInvalidArgument, fmt::format("{}: axes.{}: must be a table", source, k));
    ReadAxis(source, idx, node.as_table(), m, m.axes[idx]);
  }
  if (!m.axes[kX].present || !m.axes[kZ].present) mach.Fail("", "axes.x and axes.z are required");
  if (m.kind == "lathe" && !m.axes[kX].diameter)
    throw Error(Errc::kInvalidArgument,
                fmt::format("{}: axes.x.diameter: a lathe's X is programmed in diameter; set true", source));

  TableReader sp(source, "spindle.", root["spindle"].as_table());
  m.spindle_max_rpm = sp.Number("max_rpm", 0, 100000, std::nullopt, "rpm", true);
  m.spindle_accel_rpm_s = sp.Number("acceleration", 0, 1e6, std::nullopt, "rpm/s", true);
  m.spindle_orient_time = sp.Number("orient_time", 0, 60, 1.5, "s");
  m.live_tool_max_rpm = sp.Number("live_tool_max_rpm", 0, 100000, 0.0, "rpm");
  m.live_tool_accel_rpm_s = sp.Number("live_tool_acceleration", 0, 1e6, 0.0, "rpm/s");
  if ((m.live_tool_max_rpm > 0) != (m.live_tool_accel_rpm_s > 0))
    sp.Fail("live_tool_acceleration",
            "a live-tool spindle needs live_tool_max_rpm and live_tool_acceleration");
  // The manual gives no figure for the C-axis joint (ln 1983-1984): the station file does, or 1 s.
  m.c_joint_time = sp.Number("c_joint_time", 0, 60, 1.0, "s");
  sp.Done();

  TableReader mag(source, "magazine.", root["magazine"].as_table());
  m.magazine_sockets = mag.Integer("sockets", 1, 1000, std::nullopt);
  m.magazine_index_time = mag.Number("index_time", 0, 60, 0.1, "s per socket");
  mag.Mark("broken");
  mag.Done();
  if (const toml::node* broken = root["magazine"]["broken"].node()) {
    const toml::array* arr = broken->as_array();
    if (!arr) mag.Fail("broken", "must be an array of socket numbers");
    for (const auto& n : *arr) {
      auto sock = n.value_exact<int64_t>();
      if (!sock || *sock < 1 || *sock > m.magazine_sockets)
        mag.Fail("broken", fmt::format("socket numbers are in [1, {}]", m.magazine_sockets));
      m.broken_sockets.push_back(static_cast<int>(*sock));
    }
  }

  TableReader times(source, "times.", root["times"].as_table());
  m.tool_change_time = times.Number("tool_change", 0, 600, std::nullopt, "s");
  m.pallet_change_time = times.Number("pallet_change", 0, 3600, std::nullopt, "s");
  m.coolant_time = times.Number("coolant", 0, 60, 0.3, "s");
  times.Done();

  TableReader probe(source, "probe.", root["probe"].as_table());
  m.probe_ball_diameter = probe.Number("ball_diameter", 0, 50, 6.0, "mm");
  m.probe_max_feed = probe.Number("max_feed", 0, 1e5, 2000.0, "mm/min", true);
  m.probe_overtravel = probe.Number("overtravel", 0, 50, 5.0, "mm", true);
  probe.Mark("parts");
  probe.Done();
  if (const toml::node* parts = root["probe"]["parts"].node()) {
    const toml::array* arr = parts->as_array();
    if (!arr) probe.Fail("parts", "must be an array of tables {pallet, file}");
    std::filesystem::path base = std::filesystem::path(source).parent_path();
    for (size_t i = 0; i < arr->size(); ++i) {
      TableReader pr(source, fmt::format("probe.parts[{}].", i), (*arr)[i].as_table());
      if (!pr.exists()) probe.Fail("parts", "must be an array of tables {pallet, file}");
      PartModelRef ref;
      ref.pallet = pr.Integer("pallet", 0, 255, std::nullopt);
      std::filesystem::path f = pr.String("file", std::nullopt);
      ref.file = f.is_absolute() ? f : base / f;
      pr.Done();
      m.part_models.push_back(ref);
    }
  }

  // Initial magazine contents from the station's [[tools]] (owned by common/config; only tool and socket).
  if (const toml::array* tools = root["tools"].as_array()) {
    for (size_t i = 0; i < tools->size(); ++i) {
      const toml::table* t = (*tools)[i].as_table();
      if (!t) continue;
      tooltable::ToolEntry slot;
      if (auto s = (*t)["tool"].value_exact<std::string>())
        slot.tool = *s;
      else if (auto n = (*t)["tool"].value_exact<int64_t>())
        slot.tool = std::to_string(*n);
      else
        continue;
      auto sock = (*t)["socket"].value_exact<int64_t>();
      if (!sock) continue;
      if (*sock < 1 || *sock > m.magazine_sockets)
        throw Error(Errc::kInvalidArgument,
                    fmt::format("{}: tools[{}].socket: {} is outside the magazine's sockets [1, {}]", source,
                                i, *sock, m.magazine_sockets));
      slot.socket = static_cast<int>(*sock);
      m.tools.Upsert(slot);
    }
  }
  return m;
}

MachineConfig LoadMachineConfig(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec))
    throw Error(Errc::kNotFound, fmt::format("{}: station file not found", file.string()));
  std::ifstream in(file);
  if (!in) throw Error(Errc::kIo, fmt::format("{}: cannot open", file.string()));
  std::stringstream ss;
  ss << in.rdbuf();
  return ParseMachineConfig(ss.str(), file.string());
}

const std::vector<KindInfo>& MachineKinds() {
  static const std::vector<KindInfo> kinds = {
      {"hmc", "horizontal machining centre"}, {"vmc", "vertical machining centre"}, {"lathe", "lathe"}};
  return kinds;
}

MachineConfig DefaultMachineConfig(std::string_view kind) {
  if (kind == "lathe") {
    return ParseMachineConfig(R"(
[station]
id = "OK01"
[machine]
kind = "lathe"
[axes.x]
min = -5.0
max = 200.0
diameter = true
max_velocity = 8000.0
rapid = 12000.0
max_acceleration = 3000.0
max_jerk = 60000.0
following_error_limit = 0.3
drive = { motor_inertia = 0.0012, load_inertia = 0.0003, viscous_friction = 0.001, max_torque = 12.0, units_per_rev = 5.0 }
[axes.z]
min = -600.0
max = 5.0
max_velocity = 10000.0
rapid = 15000.0
max_acceleration = 3000.0
max_jerk = 60000.0
following_error_limit = 0.3
drive = { motor_inertia = 0.0015, load_inertia = 0.0008, viscous_friction = 0.0015, max_torque = 15.0, units_per_rev = 10.0 }
[spindle]
max_rpm = 3500
acceleration = 1500
live_tool_max_rpm = 4000
live_tool_acceleration = 2000
[magazine]
sockets = 12
index_time = 0.3
[times]
tool_change = 1.2
pallet_change = 40.0
)",
                              "<builtin lathe>");
  }
  if (kind != "hmc")
    throw Error(Errc::kInvalidArgument,
                fmt::format("no built-in machine of kind \"{}\" (built-in: hmc, lathe)", kind));
  return ParseMachineConfig(R"(
[station]
id = "KT01"
[machine]
kind = "hmc"
[axes.x]
min = -5.0
max = 800.0
max_velocity = 10000.0
rapid = 20000.0
max_acceleration = 2500.0
max_jerk = 100000.0
following_error_limit = 0.5
drive = { motor_inertia = 0.002, load_inertia = 0.0013, viscous_friction = 0.002, max_torque = 20.0, units_per_rev = 10.0 }
[axes.y]
min = -5.0
max = 700.0
max_velocity = 10000.0
rapid = 20000.0
max_acceleration = 2500.0
max_jerk = 100000.0
following_error_limit = 0.5
drive = { motor_inertia = 0.002, load_inertia = 0.0016, viscous_friction = 0.002, max_torque = 20.0, units_per_rev = 10.0 }
[axes.z]
min = -5.0
max = 750.0
max_velocity = 10000.0
rapid = 20000.0
max_acceleration = 2500.0
max_jerk = 100000.0
following_error_limit = 0.5
drive = { motor_inertia = 0.002, load_inertia = 0.0010, viscous_friction = 0.002, max_torque = 20.0, units_per_rev = 10.0 }
[axes.b]
type = "index"
min = 0.0
max = 359.999
index_increment = 1.0
clamp_time = 0.4
unclamp_time = 0.4
max_velocity = 1800.0
rapid = 1800.0
max_acceleration = 120.0
max_jerk = 4800.0
following_error_limit = 0.2
drive = { motor_inertia = 0.002, load_inertia = 0.004, viscous_friction = 0.003, max_torque = 20.0, units_per_rev = 2.0 }
[spindle]
max_rpm = 4000
acceleration = 2000
orient_time = 1.5
[magazine]
sockets = 60
index_time = 0.12
[times]
tool_change = 6.0
pallet_change = 25.0
coolant = 0.3
[probe]
ball_diameter = 6.0
max_feed = 2000.0
)",
                            "<builtin hmc>");
}

}  // namespace cell::machine
