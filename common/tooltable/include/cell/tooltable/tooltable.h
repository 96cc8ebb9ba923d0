// A station's tool table (the CNC's tool management table): the one tool model of the cell. The interpreter,
// the station service, the axis servo, the scheduler and the station config all use it; the IDL ToolEntry is
// its wire form (cell/tooltable/wire.h) and ToJson/FromJson its stored and printed form.
//
// Each dialect reads and writes tool tables in its own form (KT-APL TLD statements, a lathe's X/Z/R/L table,
// a mill's offset file) through the dialect registry (interp/registry); this library only holds the
// data.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace cell::tooltable {

// One data set of a tool: what every dialect needs. Lengths in millimetres; fields a dialect does not use
// stay at their defaults (and are left out of `station tools --json`).
struct ToolEntry {
  std::string tool;          // "33412" (primary), "33412.5" (KT-APL suffix set 5), a lathe's "3"
  int socket = 0;            // magazine socket or turret station; 0 = none (manual tool, not loaded)
  double length = 0;         // length compensation (KT-APL P, a mill's length along length_axis), signed
  double diameter = 0;       // cutter diameter compensation (KT-APL D, Balt-System K), signed
  double life_left_min = 0;  // remaining tool life, minutes (KT-APL L, hhmm); 0 = no limit given (or used up:
                             // then `worn`)
  bool worn = false;         // KT-APL E; set when cutting time uses up the life
  bool broken = false;       // KT-APL B; set by a G38 check that finds the tool broken
  bool check = false;        // KT-APL C: check the tool on its first use
  bool manual = false;       // KT-APL M: manual tool
  double max_hp = 0;         // KT-APL H: maximum allowable horsepower (0 = not given)
  char length_axis = 'Z';    // mills: the axis the length compensation acts along (X, Y or Z)
  double x_offset = 0;       // lathes: tool offset along X (on the diameter where the dialect programs one)
  double z_offset = 0;       // lathes: tool offset along Z
  double nose_radius = 0;    // lathes: tool-nose radius
  int tip = 0;               // lathes: tip position code 0-9 (0: the nose centre)

  bool operator==(const ToolEntry&) const = default;
};

// Usable for cutting: neither worn nor broken.
inline bool Usable(const ToolEntry& e) {
  return !e.worn && !e.broken;
}

// What the machine measured on one data set while a program ran: cutting time (feed moves with the spindle
// turning, machine seconds) and a G38 check that found the tool broken. The station collects it from its
// servo; a run applies it to its table (ToolTable::Charge) before it selects a tool.
struct ToolWear {
  std::string tool;  // as the tool change named it
  int socket = 0;
  double cutting_s = 0;
  bool broken = false;
  bool operator==(const ToolWear&) const = default;
};

// A process compensation (KT-APL TLD with W): added to a tool's data set while pallet `pallet` is on the
// table.
struct ProcessComp {
  std::string tool;
  int pallet = 0;
  double length = 0;
  double diameter = 0;
  bool operator==(const ProcessComp&) const = default;
};

// Normalises a tool number as written in UTL or TLD: strips a leading T and leading zeros of the number part
// ("T0012" -> "12", "33412.5" stays). Throws cell::Error on anything that is not 1-7 digits with an optional
// .1-.7 suffix.
std::string NormalizeToolNumber(std::string_view text);

// The part of a tool number before the suffix: "33412.5" -> "33412".
std::string_view BaseTool(std::string_view tool);

class ToolTable {
 public:
  ToolTable() = default;
  explicit ToolTable(std::vector<ToolEntry> entries, std::vector<ProcessComp> process = {});

  const std::vector<ToolEntry>& entries() const { return entries_; }
  const std::vector<ProcessComp>& process_comps() const { return process_; }
  // The first data set of this tool number (exact, suffix included); with `socket` > 0 the one in that
  // socket, else the first.
  const ToolEntry* Find(std::string_view tool, int socket = 0) const;
  ToolEntry* Find(std::string_view tool, int socket = 0);

  // Adds or replaces a data set (a TLD statement loads a whole data set, as on the control). A data set of a
  // tool number already in another magazine socket is an alternate (sister) tool: both are kept (KT-APL
  // Fig. 6.1 lists tools 4421 and 11113 twice). Otherwise the data set of that number is replaced.
  void Upsert(const ToolEntry& entry);

  // The data set a selection of tool number `tool` loads (KT-APL T + M06): the first usable one (neither
  // worn nor broken) in table order, so alternates are used one after the other. nullptr when the number has
  // data sets but none is usable (`*exists` = true), or has none (`*exists` = false: the tool is as
  // programmed, the machine finds it by number).
  const ToolEntry* Select(std::string_view tool, bool* exists = nullptr) const;

  // Applies what the machine measured: the data set (tool, socket; else the first of that number) loses
  // the cutting time from its life (minutes; a life of 0 means none was given and is not counted) and is
  // worn when it reaches 0; `broken` sets its broken flag. False when no such data set is in the table.
  bool Charge(const ToolWear& wear);
  // Adds or replaces a process compensation by (tool, pallet). A process compensation needs a primary or
  // suffix data set of its tool first (KT-APL manual ln 4073): returns false, table unchanged, without one.
  bool UpsertProcess(const ProcessComp& comp);
  // Empties the table (KT-APL ZTB,T).
  void Clear();

  // The length and diameter compensation of a data set with the process compensation for `pallet` added
  // (0 = no pallet); false when there is no such data set.
  struct Compensation {
    double length = 0;
    double diameter = 0;
  };
  bool Effective(std::string_view tool, int pallet, Compensation* out, int socket = 0) const;

  // True when a usable (neither worn nor broken) data set of this tool number is in the table: the UTL check
  // (a station holds tool N when some entry of N is usable). A bare UTL number such as "33412" is held by
  // its primary set, an alternate, or any suffix set of it.
  bool Holds(std::string_view tool) const;

  bool operator==(const ToolTable&) const = default;

 private:
  std::vector<ToolEntry> entries_;  // kept in insertion order
  std::vector<ProcessComp> process_;
};

// The stored and printed form: {"entries":[{tool, socket, length, diameter, life_left_min, worn, broken,
// ...}], "process":[{tool, pallet, length, diameter}]}. EntryJson is one entry as `station tools --json`
// prints it (DESIGN §6 keys always; other dialects' fields where they are set).
nlohmann::json ToJson(const ToolTable& t);
ToolTable FromJson(const nlohmann::json& j);  // throws cell::Error(kInvalidArgument) on a malformed table
nlohmann::json EntryJson(const ToolEntry& e);
ToolEntry EntryFromJson(const nlohmann::json& j);

}  // namespace cell::tooltable
