#include "cell/scheduler/allocator.h"

namespace cell::scheduler {

int ToolIndex::Intern(std::string_view tool) {
  auto it = ids_.find(std::string(tool));
  if (it != ids_.end()) return it->second;
  const int id = static_cast<int>(names_.size());
  names_.emplace_back(tool);
  ids_.emplace(names_.back(), id);
  return id;
}

void StationState::SetTools(const tooltable::ToolTable& table, ToolIndex& index) {
  held.clear();
  for (const auto& e : table.entries()) {
    if (!tooltable::Usable(e)) continue;  // worn or broken: the station cannot cut with it
    const auto id = static_cast<std::size_t>(index.Intern(tooltable::BaseTool(e.tool)));
    if (held.size() <= id / 64) held.resize(id / 64 + 1, 0);
    held[id / 64] |= std::uint64_t{1} << (id % 64);
  }
}

void Allocate(const std::vector<int>& listed, const std::vector<int>& tools,
              const std::vector<StationState>& stations, AllocationRec& out, std::int64_t job) {
  out.winner = -1;
  out.tied = 0;
  out.candidates.resize(listed.size());
  out.missing.clear();
  std::int64_t best = 0;
  for (std::size_t i = 0; i < listed.size(); ++i) {
    const int s = listed[i];
    const StationState& st = stations[static_cast<std::size_t>(s)];
    CandidateRec& c = out.candidates[i];
    c.station = s;
    c.backlog_s = st.backlog_s;
    c.online = st.online;
    c.fault = st.fault;
    c.schedule_job = st.schedule_job == job ? 0 : st.schedule_job;
    c.missing_begin = static_cast<std::uint32_t>(out.missing.size());
    for (int t : tools) {
      if (!st.Holds(t)) out.missing.push_back(t);
    }
    c.missing_count = static_cast<std::uint32_t>(out.missing.size()) - c.missing_begin;
    if (!c.eligible()) continue;
    if (out.winner < 0 || st.backlog_s < best) {
      out.winner = s;
      best = st.backlog_s;
      out.tied = 1;
    } else if (st.backlog_s == best) {
      ++out.tied;
    }
  }
}

}  // namespace cell::scheduler
