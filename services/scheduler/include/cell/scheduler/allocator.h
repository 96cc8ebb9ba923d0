// The allocation rule of OPERATE (DESIGN §5, KT-APL seed lines 4130-4134 and 4300-4304), as a pure function
// over interned station states, so that the scheduler and the benchmark share it.
//
//   eligible = listed for the operation, online, not in FAULT, and holding every UTL tool of the operation
//   winner   = the eligible station with the shortest backlog; ties go to the station listed first.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "cell/tooltable/tooltable.h"

namespace cell::scheduler {

// Interns tool numbers (UTL numbers, the base numbers of tool table entries) to small integers.
class ToolIndex {
 public:
  int Intern(std::string_view tool);
  const std::string& Name(int id) const { return names_[static_cast<std::size_t>(id)]; }
  std::size_t size() const { return names_.size(); }

 private:
  std::unordered_map<std::string, int> ids_;
  std::vector<std::string> names_;
};

struct StationState {
  bool online = false;
  bool fault = false;
  std::int64_t backlog_s = 0;
  std::vector<std::uint64_t> held;  // bit per interned tool id: a usable (not broken) data set is loaded
  // A schedule job that has the station to itself from its first step to its end (0: none): on the control a
  // schedule program runs its PSELECTs one after another with nothing between, and its VSET/IF counters are
  // the station's common variables (docs/scheduler.md §9).
  std::int64_t schedule_job = 0;

  bool Holds(int tool) const {
    const auto word = static_cast<std::size_t>(tool) / 64;
    return word < held.size() && ((held[word] >> (static_cast<unsigned>(tool) % 64)) & 1u) != 0;
  }
  void SetTools(const tooltable::ToolTable& table, ToolIndex& index);
};

struct CandidateRec {
  int station = 0;  // index into the station array
  std::int64_t backlog_s = 0;
  bool online = false;
  bool fault = false;
  std::uint32_t missing_begin =
      0;  // this candidate's tools not held: AllocationRec::missing[begin, begin+count)
  std::uint32_t missing_count = 0;
  std::int64_t schedule_job = 0;  // another job's schedule has the station (StationState::schedule_job)
  bool eligible() const { return online && !fault && missing_count == 0 && schedule_job == 0; }
};

struct AllocationRec {
  int winner = -1;                       // station index, -1: nobody is eligible
  int tied = 0;                          // how many eligible stations shared the winner's backlog
  std::vector<CandidateRec> candidates;  // in listed order
  std::vector<int> missing;              // tool ids not held, all candidates one after another

  template <typename F>
  void ForMissing(const CandidateRec& c, F&& f) const {
    for (std::uint32_t i = 0; i < c.missing_count; ++i) f(missing[c.missing_begin + i]);
  }
};

// Decides one operation of job `job`. `listed`: station indexes in the operation's order; `tools`: interned
// UTL ids.
void Allocate(const std::vector<int>& listed, const std::vector<int>& tools,
              const std::vector<StationState>& stations, AllocationRec& out, std::int64_t job = 0);

}  // namespace cell::scheduler
