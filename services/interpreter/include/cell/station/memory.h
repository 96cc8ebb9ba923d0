// The CNC's memory: the station's tool table and the variables it keeps between programs (KT-APL machine
// parameters L1000-L2999 by the dialect's rule, and the cell's schedule variables V1-V200, DESIGN §5),
// persisted in StationDb and published on every change.
//
// A run starts from a snapshot (Get) and reports what it left (its tool table and its persistent variables,
// by the dialect's own names). Commit applies the difference between the two to the memory as it stands then:
// what the program set, changed or deleted is kept; what the operator changed meanwhile and the program did
// not touch stays. Tools, variables and the run's progress go to SQLite in one transaction.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "cell/station/station_db.h"
#include "cell/tooltable/tooltable.h"

namespace cell::station {

struct MemorySnapshot {
  MemoryImage image;
  std::uint32_t tools_revision = 0;
  std::uint32_t variables_revision = 0;
};

// Called with the new state after every change, under the memory's lock (so publications never overtake
// each other); `tools` / `variables` say what changed.
using MemoryListener = std::function<void(const MemorySnapshot& now, bool tools, bool variables)>;

class Memory {
 public:
  // Loads the memory; a station that was never seeded gets the config's initial tools (and keeps them).
  Memory(StationDb& db, std::string dialect, const std::vector<tooltable::ToolEntry>& initial_tools,
         MemoryListener listener);

  MemorySnapshot Get() const;
  // Publishes the current state (at start-up).
  void Announce() const;

  // "" when the station keeps variable `name` with `value`: the dialect's own persistent variables
  // (interp::Dialect::CheckVariable) and the cell's schedule variables V1-V200; else a one-line reason.
  std::string CheckVariable(const std::string& name, double value) const;

  // The operator: `change` applied to a copy of the tool table (a tool load in the dialect's own form; a
  // cell::Error it throws changes nothing); variables set (checked first: nothing is set when one is
  // refused). Each is committed, published, and returns the new revision.
  std::uint32_t ChangeTools(const std::function<void(tooltable::ToolTable&)>& change);
  std::uint32_t SetVariables(const std::map<std::string, double>& values);

  // What a program changed between `before` (what it started from) and its `tools` and `variables` (the
  // dialect's persistent variables as the run reports them), applied and committed with `progress`.
  void Commit(const MemoryImage& before, const tooltable::ToolTable& tools,
              const std::map<std::string, double>& variables, const RunProgress& progress);

 private:
  bool DialectKeeps(const std::string& name) const;

  StationDb& db_;
  std::string dialect_;
  MemoryListener listener_;
  mutable std::mutex mu_;
  MemorySnapshot now_;
};

// The tool-table part of Commit, exposed for tests: `now` with the data sets and process compensations that
// differ between `before` and `after` replaced, added or removed.
tooltable::ToolTable ApplyToolChanges(const tooltable::ToolTable& now, const tooltable::ToolTable& before,
                                      const tooltable::ToolTable& after);

}  // namespace cell::station
