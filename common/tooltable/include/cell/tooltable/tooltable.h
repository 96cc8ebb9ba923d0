// A station's tool table (the CNC's tool management table) and the KT-APL TLD statement that loads it.
//
// TLD (KT-APL manual, "TLD TOOL LIFE DATA STATEMENT", seed lines 3975-4097):
//   (TLD,SnnTnnnnnnn[.s]CMWnnnPnnnnnDnnnnnnnnnLnnnnHnn.n)   ASCII form
//   %TLD,...%                                                 EIA form
// S socket, T tool (up to 7 digits, optional suffix .1-.7), C check flag, M manual flag, W pallet (process
// compensation), P length comp, D diameter comp, L tool life hhmm, H maximum horsepower, B broken, E worn.
// Flags are bare letters. Values are read in the current unit (G70 inch / G71 metric); the table stores mm.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cell::tooltable {

// One primary or suffix data set of a tool.
struct ToolEntry {
  std::string tool;       // "33412" (primary) or "33412.5" (suffix set 5)
  int socket = 0;         // magazine socket; 0 = none (manual tool or not in the magazine)
  double length = 0;      // P: tool length compensation, mm
  double diameter = 0;    // D: cutter diameter compensation, mm
  int life_left_min = 0;  // L: remaining life in minutes (0 = no limit given)
  bool worn = false;      // E
  bool broken = false;    // B
  bool check = false;     // C: check the tool on its first use
  bool manual = false;    // M: manual tool
  double max_hp = 0;      // H: maximum allowable horsepower (0 = not given)

  bool operator==(const ToolEntry&) const = default;
};

// A process compensation: added to a tool's data while pallet `pallet` is on the table.
struct ProcessComp {
  std::string tool;
  int pallet = 0;
  double length = 0;
  double diameter = 0;
  bool operator==(const ProcessComp&) const = default;
};

// One parsed TLD statement: either a data set (entry) or a process compensation (W given).
struct TldStatement {
  int line = 0;  // 1-based line of the statement in the source
  int column = 0;
  std::optional<ToolEntry> entry;
  std::optional<ProcessComp> process;
};

struct ParseOptions {
  bool metric = true;    // unit mode at the start (G71); G70/G71 in the text switch it
  int max_pallet = 255;  // 127 for coded-pallet FMS stations (seed line 4081-4083)
};

// Parses every TLD statement of a tool-table file (a KT-APL program of TLD blocks). Lines holding G70/G71
// switch the unit; other blocks (%, N numbers, NAM, comments) are skipped. Throws cell::Error
// (kInvalidArgument) with "SOURCE:LINE:COL: error: text" at the first malformed TLD.
std::vector<TldStatement> ParseTld(std::string_view text, std::string_view source = "tld",
                                   const ParseOptions& options = {});

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
  const ToolEntry* Find(std::string_view tool) const;

  // Adds or replaces data sets by tool number (a TLD statement loads a whole data set, as on the control) and
  // adds or replaces process compensations by (tool, pallet). A process compensation needs a primary or
  // suffix data set of its tool first (seed line 4073, "Before a process compensation is entered either a
  // primary or a suffix compensation must be entered"): otherwise cell::Error kFailedPrecondition naming the
  // line, and the table is left unchanged. Returns the number of statements applied.
  std::size_t Merge(const std::vector<TldStatement>& statements, std::string_view source = "tld");
  void Upsert(const ToolEntry& entry);

  // True when a usable (not broken) data set of this tool number is in the table. A bare UTL number such as
  // "33412" is held by its primary set or any suffix set of it.
  bool Holds(std::string_view tool) const;

 private:
  std::vector<ToolEntry> entries_;  // kept in insertion order
  std::vector<ProcessComp> process_;
};

}  // namespace cell::tooltable
