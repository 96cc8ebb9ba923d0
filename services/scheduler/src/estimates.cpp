// Predicted and learned cycle times (docs/scheduler.md "Estimates"): the records per program and station,
// the backlog an allocation adds with them, and the learning after each visit.
#include "cell/scheduler/estimates.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "cell/error/error.h"
#include "cell/scheduler/scheduler.h"
#include "scheduler_impl.h"

namespace cell::scheduler {

double LearnEstimate(double estimate, double predicted, double actual, int runs) {
  const double w = std::max(kLearnMinWeight, 1.0 / (std::max(runs, 0) + 1));
  const double a = predicted > 0 ? std::clamp(actual, kRatioMin * predicted, kRatioMax * predicted) : actual;
  return estimate + w * (a - estimate);
}

const EstimateRec* Scheduler::Impl::EstimateFor(const std::string& program, const std::string& revision,
                                                int station) {
  if (!predictor || revision.empty()) return nullptr;
  const std::string& id = stations[static_cast<std::size_t>(station)].id;
  std::string key = revision + "/" + predictor->Basis(id);
  if (auto it = estimates.find({program, id}); it != estimates.end() && it->second.revision == key)
    return &it->second;
  // Asked, never made here: a prediction fetches the program and runs it, seconds under the caller's lock
  // would stall every allocation and report (the chaos test's stalled scheduler, issue 40).
  if (ask) ask(PredictionRequest{program, id, std::move(key)});
  return nullptr;
}

void Scheduler::Impl::AskEstimates(const Op& op) {
  for (std::size_t i = 0; i < op.programs.size(); ++i) {
    if (op.Revision(i).empty()) continue;
    for (int s : op.stations) EstimateFor(op.programs[i], op.Revision(i), s);
  }
}

std::vector<std::int64_t> Scheduler::Impl::BacklogFor(const Op& op, int station,
                                                      std::optional<double>& predicted) {
  std::vector<std::int64_t> secs = op.ucy;
  double sum = 0;
  bool all = true, any = false;
  for (std::size_t i = 0; i < op.programs.size() && i < secs.size(); ++i) {
    const std::string& rev = op.Revision(i);
    if (rev.empty()) continue;  // a part model, or an operation stored before estimates
    const EstimateRec* e = EstimateFor(op.programs[i], rev, station);
    if (e && e->predicted) {
      sum += *e->predicted;
      any = true;
    } else {
      all = false;
    }
    if (!op.Stated(i) && e && e->estimate) secs[i] = std::llround(*e->estimate);
  }
  predicted = any && all ? std::optional<double>(sum) : std::nullopt;
  return secs;
}

void Scheduler::Impl::Learn(const DispatchRec& d, double actual) {
  auto j = jobs.find(d.job);
  if (j == jobs.end() || !j->second.ops || d.op >= static_cast<int>(j->second.ops->size())) return;
  const Op& op = (*j->second.ops)[static_cast<std::size_t>(d.op)];
  if (op.programs != d.programs || actual <= 0) return;  // a schedule run: programs of its own
  const std::string& id = stations[static_cast<std::size_t>(d.station)].id;
  // The visit's seconds are shared among its programs in proportion to their estimates: only a visit whose
  // every program has one teaches anything.
  std::vector<EstimateRec*> recs;
  double total = 0;
  for (std::size_t i = 0; i < op.programs.size(); ++i) {
    const std::string& rev = op.Revision(i);
    if (rev.empty()) continue;
    auto it = estimates.find({op.programs[i], id});
    if (it == estimates.end() || !it->second.estimate || it->second.revision.rfind(rev + "/", 0) != 0) return;
    recs.push_back(&it->second);
    total += *it->second.estimate;
  }
  if (recs.empty() || total <= 0) return;
  for (std::size_t i = 0, k = 0; i < op.programs.size(); ++i) {
    if (op.Revision(i).empty()) continue;
    EstimateRec& r = *recs[k++];
    const double share = actual * *r.estimate / total;
    r.estimate = LearnEstimate(*r.estimate, r.predicted.value_or(0), share, r.runs);
    ++r.runs;
    dirty_estimates.insert({op.programs[i], id});
  }
}

void Scheduler::SetPredictor(Predictor* predictor, std::function<void(const PredictionRequest&)> ask) {
  impl_->predictor = predictor;
  impl_->ask = std::move(ask);
}

Effects Scheduler::PredictionAnswered(const PredictionRequest& request, const Predicted& answer) {
  Impl& m = *impl_;
  m.Call([&] {
    if (answer.transient) {
      m.fx.notes.push_back(fmt::format("prediction of {} on {} not made ({}): asked again at its next need",
                                       request.program, request.station, answer.why));
      return;
    }
    if (m.FindStation(request.station) < 0) return;
    EstimateRec& r = m.estimates[{request.program, request.station}];
    if (r.revision == request.revision) return;  // answered before (a request asked twice)
    // A new revision (of the program or the station's model) starts over: what was learned was another
    // program.
    r = EstimateRec{request.revision, answer.seconds, answer.seconds ? std::string() : answer.why,
                    answer.seconds, 0};
    m.dirty_estimates.insert({request.program, request.station});
  });
  return m.TakeEffects();
}

ProgramEstimates Scheduler::Estimates(std::string_view program) {
  Impl& m = *impl_;
  return m.Call([&] {
    ProgramEstimates out;
    std::optional<ProgramMeta> meta = m.programs.Lookup(program);
    if (!meta) throw Error(Errc::kNotFound, "program '" + std::string(program) + "' not found");
    out.meta = std::move(*meta);
    for (std::size_t s = 0; s < m.stations.size(); ++s) {
      EstimateView v;
      v.station = m.stations[s].id;
      if (out.meta.part_model) {
        v.why = "a part model: nothing runs";
      } else if (const EstimateRec* e =
                     m.EstimateFor(std::string(program), out.meta.revision, static_cast<int>(s))) {
        v.predicted_s = e->predicted;
        v.why = e->why;
        v.estimate_s = e->estimate;
        v.runs = e->runs;
      } else {
        v.why = m.predictor ? "not predicted yet: asked for" : "no predictor";
      }
      out.stations.push_back(std::move(v));
    }
    std::sort(out.stations.begin(), out.stations.end(),
              [](const EstimateView& a, const EstimateView& b) { return a.station < b.station; });
    return out;
  });
}

}  // namespace cell::scheduler
