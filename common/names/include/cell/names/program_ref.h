// A program as a pallet map or a route operation names it (docs/scheduler.md, "Program names"): "NAME",
// looked up by the running station in its own namespace, then HOST; or "NODE:NAME", NAME in namespace NODE
// alone (HOST, a station id or a station's memory "BS01/MP2": a Balt-System program kept in the control's
// memory).
#pragma once

#include <string>
#include <string_view>

namespace cell::names {

struct ProgramRef {
  std::string node;  // "" when the entry names no namespace
  std::string name;
};

// Splits at the first ':' when what precedes it is a namespace (CheckNode's rule) and a name follows; any
// other entry is a plain name (a HOST file may hold ':' in its name).
ProgramRef SplitProgramRef(std::string_view entry);
// The station whose namespace `node` is: "BS01" for "BS01" and "BS01/MP2"; "" for HOST.
std::string NodeStation(std::string_view node);
// The rule a map's entry obeys: the name's (CheckProgram) and, when it names one, the namespace's.
void CheckProgramRef(std::string_view entry, std::string_view what = "program name");

}  // namespace cell::names
