#include "cell/station/memory.h"

#include <algorithm>
#include <cmath>

#include "cell/error/error.h"
#include "cell/interp/interp.h"

namespace cell::station {

namespace {

// DESIGN §5: the Okuma schedule programs' common variables V1-V200 live on the station and persist, whatever
// the station's dialect (the scheduler's VSET and IF use them).
bool IsScheduleVariable(const std::string& name) {
  if (name.size() < 2 || name.size() > 4 || name[0] != 'V' || name[1] == '0') return false;
  int n = 0;
  for (size_t i = 1; i < name.size(); ++i) {
    if (name[i] < '0' || name[i] > '9') return false;
    n = n * 10 + (name[i] - '0');
  }
  return n >= 1 && n <= 200;
}

template <typename T, typename Key>
std::vector<T> ApplyKeyed(const std::vector<T>& now, const std::vector<T>& before,
                          const std::vector<T>& after, Key key) {
  auto find = [&](const std::vector<T>& v, const T& x) {
    return std::find_if(v.begin(), v.end(), [&](const T& y) { return key(y) == key(x); });
  };
  std::vector<T> out;
  for (const T& e : now) {
    const bool removed = find(before, e) != before.end() && find(after, e) == after.end();
    if (!removed) out.push_back(e);
  }
  for (const T& a : after) {
    auto b = find(before, a);
    if (b != before.end() && *b == a) continue;  // the program left it as it found it
    auto o = std::find_if(out.begin(), out.end(), [&](const T& y) { return key(y) == key(a); });
    if (o != out.end())
      *o = a;
    else
      out.push_back(a);
  }
  return out;
}

}  // namespace

tooltable::ToolTable ApplyToolChanges(const tooltable::ToolTable& now, const tooltable::ToolTable& before,
                                      const tooltable::ToolTable& after) {
  auto entries = ApplyKeyed(now.entries(), before.entries(), after.entries(),
                            [](const tooltable::ToolEntry& e) { return std::make_pair(e.tool, e.socket); });
  auto process = ApplyKeyed(now.process_comps(), before.process_comps(), after.process_comps(),
                            [](const tooltable::ProcessComp& c) { return std::make_pair(c.tool, c.pallet); });
  return tooltable::ToolTable(std::move(entries), std::move(process));
}

Memory::Memory(StationDb& db, std::string dialect, const std::vector<tooltable::ToolEntry>& initial_tools,
               MemoryListener listener)
    : db_(db), dialect_(std::move(dialect)), listener_(std::move(listener)) {
  now_.image = db_.LoadMemory();
  if (!db_.ToolsSeeded()) {
    now_.image.tools = tooltable::ToolTable(initial_tools);
    db_.SaveMemory(now_.image);
  }
}

MemorySnapshot Memory::Get() const {
  std::lock_guard lk(mu_);
  return now_;
}

void Memory::Announce() const {
  std::lock_guard lk(mu_);
  listener_(now_, true, true);
}

bool Memory::DialectKeeps(const std::string& name) const {
  const interp::Dialect* d = interp::FindDialect(dialect_);
  return d && d->CheckVariable(name, 0).empty();
}

std::string Memory::CheckVariable(const std::string& name, double value) const {
  if (IsScheduleVariable(name)) {
    if (!std::isfinite(value)) return name + " must be a finite number";
    return "";
  }
  const interp::Dialect* d = interp::FindDialect(dialect_);
  std::string why = d ? d->CheckVariable(name, value) : "'" + name + "': unknown dialect '" + dialect_ + "'";
  if (!why.empty() && !DialectKeeps(name)) why += "; every station keeps the schedule variables V1..V200";
  return why;
}

std::uint32_t Memory::ChangeTools(const std::function<void(tooltable::ToolTable&)>& change) {
  std::lock_guard lk(mu_);
  MemoryImage next = now_.image;
  change(next.tools);
  db_.SaveMemory(next);
  now_.image = std::move(next);
  ++now_.tools_revision;
  listener_(now_, true, false);
  return now_.tools_revision;
}

std::uint32_t Memory::SetVariables(const std::map<std::string, double>& values) {
  for (const auto& [name, value] : values) {
    if (auto why = CheckVariable(name, value); !why.empty()) throw Error(Errc::kInvalidArgument, why);
  }
  std::lock_guard lk(mu_);
  MemoryImage next = now_.image;
  for (const auto& [name, value] : values) next.variables[name] = value;
  db_.SaveMemory(next);
  now_.image = std::move(next);
  ++now_.variables_revision;
  listener_(now_, false, true);
  return now_.variables_revision;
}

void Memory::Commit(const MemoryImage& before, const tooltable::ToolTable& tools,
                    const std::map<std::string, double>& variables, const RunProgress& progress) {
  std::lock_guard lk(mu_);
  MemoryImage next = now_.image;
  next.tools = ApplyToolChanges(now_.image.tools, before.tools, tools);
  for (const auto& [name, value] : before.variables) {
    if (DialectKeeps(name) && !variables.count(name)) next.variables.erase(name);  // deleted (DLP)
  }
  for (const auto& [name, value] : variables) {
    auto b = before.variables.find(name);
    if (b == before.variables.end() || b->second != value) next.variables[name] = value;
  }
  const bool tools_changed = next.tools.entries() != now_.image.tools.entries() ||
                             next.tools.process_comps() != now_.image.tools.process_comps();
  const bool vars_changed = next.variables != now_.image.variables;
  db_.SaveMemory(next, &progress);
  now_.image = std::move(next);
  if (tools_changed) ++now_.tools_revision;
  if (vars_changed) ++now_.variables_revision;
  if (tools_changed || vars_changed) listener_(now_, tools_changed, vars_changed);
}

}  // namespace cell::station
