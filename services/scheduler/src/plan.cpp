// The plan (docs/scheduler.md §15): the scheduler's own rule run forward on the backlog seconds it uses.
#include <algorithm>
#include <queue>

#include "cell/scheduler/scheduler.h"
#include "scheduler_impl.h"

namespace cell::scheduler {

namespace {

// A route job's next operation, ready to be allocated when its previous visit ends.
struct Ready {
  std::int64_t at_ms;
  std::int64_t job;
  int op;
  bool operator>(const Ready& o) const { return at_ms != o.at_ms ? at_ms > o.at_ms : job > o.job; }
};

std::int64_t Sum(const std::vector<std::int64_t>& v, std::size_t from = 0) {
  std::int64_t s = 0;
  for (std::size_t i = from; i < v.size(); ++i) s += v[i];
  return s;
}

}  // namespace

std::vector<PlanRow> Scheduler::Plan() {
  Impl& m = *impl_;
  return m.Call([&] {
    const std::int64_t now = m.NowMs();
    std::vector<std::int64_t> free(m.stations.size(), now);  // when each station is projected free
    std::vector<PlanRow> rows;
    std::priority_queue<Ready, std::vector<Ready>, std::greater<>> ready;
    auto visit = [&](const JobRec& j, int op, int s, std::int64_t start, std::int64_t seconds) {
      const std::int64_t end = start + seconds * 1000;
      rows.push_back(
          {j.id, j.pallet, j.route, op, m.stations[static_cast<std::size_t>(s)].id, start, end, ""});
      free[static_cast<std::size_t>(s)] = std::max(free[static_cast<std::size_t>(s)], end);
      if (j.kind == "route" && j.ops && op + 1 < static_cast<int>(j.ops->size()))
        ready.push({end, j.id, op + 1});
    };
    // What each station holds now, in its order: the visit in hand (what remains of it from now, or from
    // when it started), then its queue.
    for (std::size_t s = 0; s < m.stations.size(); ++s) {
      const StationRec& st = m.stations[s];
      if (st.inflight != 0) {
        const DispatchRec& d = m.dispatches.at(st.inflight);
        const JobRec& j = m.jobs.at(d.job);
        const bool running = j.state == JobState::kRunning;
        const std::int64_t start = running && j.started > 0 ? j.started : now;
        rows.push_back({j.id, j.pallet, j.route, d.op, st.id, start, now + d.Remaining() * 1000, ""});
        free[s] = now + d.Remaining() * 1000;
        if (j.kind == "route" && j.ops && d.op + 1 < static_cast<int>(j.ops->size()))
          ready.push({free[s], j.id, d.op + 1});
      }
      for (std::int64_t id : st.queue) {
        const DispatchRec& d = m.dispatches.at(id);
        visit(m.jobs.at(d.job), d.op, static_cast<int>(s), free[s], Sum(d.ucy));
      }
    }
    // Later operations, in the order their pallets become ready: the allocation rule (eligible, shortest
    // backlog, listed first) with each station's backlog the time it still has then.
    std::vector<StationState> states = m.states;
    AllocationRec alloc;
    std::vector<int> scratch;
    while (!ready.empty()) {
      const Ready r = ready.top();
      ready.pop();
      const JobRec& j = m.jobs.at(r.job);
      const Op& op = (*j.ops)[static_cast<std::size_t>(r.op)];
      for (std::size_t s = 0; s < states.size(); ++s)
        states[s].backlog_s = std::max<std::int64_t>(0, (free[s] - r.at_ms + 999) / 1000);
      alloc = AllocationRec{};
      if (op.blocked.empty())
        Allocate(m.ListedFor(op.stations, j.pallet, scratch), op.tool_ids, states, alloc, j.id);
      if (alloc.winner < 0) {
        rows.push_back({j.id, j.pallet, j.route, r.op, "", std::nullopt, std::nullopt,
                        op.blocked.empty() ? m.Describe(alloc) : op.blocked});
        continue;
      }
      std::optional<double> predicted;
      const std::vector<std::int64_t> secs = m.BacklogFor(op, alloc.winner, predicted);
      visit(j, r.op, alloc.winner, std::max(r.at_ms, free[static_cast<std::size_t>(alloc.winner)]),
            Sum(secs));
    }
    for (std::int64_t id : m.waiting) {
      const JobRec& j = m.jobs.at(id);
      rows.push_back({j.id, j.pallet, j.route, j.op, "", std::nullopt, std::nullopt, j.reason});
    }
    std::stable_sort(rows.begin(), rows.end(), [](const PlanRow& a, const PlanRow& b) {
      return a.job != b.job ? a.job < b.job : a.op < b.op;
    });
    return rows;
  });
}

}  // namespace cell::scheduler
