// The listing entries (DESIGN §6): a program (`program ls`, and the head of `program show`) and an inspection
// record or file (`inspect ls`, and the page's latest inspection results). The store and the inspection
// writer fill them; every listing prints the row from here.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace cell::records {

struct ProgramEntry {
  std::string name, node, type, dialect;  // type and dialect as the store names them ("part", "ktapl")
  std::uint32_t revision = 0;
  std::uint64_t size = 0;
  bool is_protected = false;
  bool selected = false, hidden = false;  // Balt-System SPG and ATT HIDDEN
};
// {name, node, type, dialect, revision, size, protected, selected, hidden}
nlohmann::json ProgramRow(const ProgramEntry& e);

struct InspectionEntry {
  std::string name;                  // "run-KT01-12.json", "KT01/PROBE1"
  std::string station;               // KT01
  std::string kind;                  // "run" or "inspection"
  std::optional<std::int64_t> size;  // bytes, where the file is at hand
};
// Station and kind from a stored name: run records are `run-<station>-<dispatch>.json`, inspection files
// `<station>/<file>`.
InspectionEntry InspectionEntryOf(const std::string& name);
// {name, station, kind, size}; size null when unknown.
nlohmann::json InspectionRow(const InspectionEntry& e);

}  // namespace cell::records
