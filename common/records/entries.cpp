#include "cell/records/entries.h"

namespace cell::records {

using nlohmann::json;

json ProgramRow(const ProgramEntry& e) {
  return {{"name", e.name},
          {"node", e.node},
          {"type", e.type},
          {"dialect", e.dialect},
          {"revision", e.revision},
          {"size", e.size},
          {"protected", e.is_protected},
          {"selected", e.selected},
          {"hidden", e.hidden}};
}

InspectionEntry InspectionEntryOf(const std::string& name) {
  InspectionEntry e;
  e.name = name;
  const bool run = name.rfind("run-", 0) == 0;
  e.kind = run ? "run" : "inspection";
  // run-STATION-DISPATCH.json: a station id may itself hold '-', the dispatch id never does.
  e.station = run ? name.substr(4, name.rfind('-') - 4) : name.substr(0, name.find('/'));
  return e;
}

json InspectionRow(const InspectionEntry& e) {
  return {{"name", e.name},
          {"station", e.station},
          {"kind", e.kind},
          {"size", e.size ? json(*e.size) : json(nullptr)}};
}

}  // namespace cell::records
