// Predicted and learned cycle times (issue 40; docs/scheduler.md "Estimates"). The scheduler never predicts
// itself: where it needs a (program, station) pair it has no record for, it asks (Scheduler::SetPredictor's
// `ask`, which only queues: PredictionQueue), goes on with UCY or nothing meanwhile, and keeps the answer
// Scheduler::PredictionAnswered is given with the program's revision; it corrects the estimate after each run
// with the rule of LearnEstimate. A Predictor (the service's: the program run through its dialect and the
// station's servo model on the virtual clock, services/predict) answers on the queue's worker thread.
#pragma once

#include <chrono>
#include <optional>
#include <stop_token>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "cell/scheduler/program_source.h"

namespace cell::scheduler {

// One prediction the scheduler wants: `program` (a map entry) on station `station`, for `revision`
// (ProgramMeta::revision + "/" + Predictor::Basis of the station: what the answer is kept under).
struct PredictionRequest {
  std::string program, station, revision;
  bool operator<(const PredictionRequest& o) const {
    return std::tie(program, station, revision) < std::tie(o.program, o.station, o.revision);
  }
  bool operator==(const PredictionRequest&) const = default;
};

struct Predicted {
  std::optional<double> seconds;  // machine seconds, first segment to end
  std::string why;                // when there is no number
  // No answer this time (the program store did not answer, the time limit passed): not kept, asked again
  // later. A definite answer (a number, or the dialect refusing the program) is kept with the revision.
  bool transient = false;
};

class Predictor {
 public:
  virtual ~Predictor() = default;
  // `program` (a map entry) as `station` reads and runs it, offline: on PredictionQueue's worker, never
  // under the scheduler's lock. Gives up (transient) after `limit` of wall clock or when `stop` is requested.
  virtual Predicted Predict(std::string_view program, std::string_view station,
                            std::chrono::milliseconds limit, std::stop_token stop) = 0;
  // What else the prediction rests on for this station (its file's fingerprint): a change predicts again.
  // Called on the scheduler's thread (with its lock), so it must be cheap and not share state with Predict.
  virtual std::string Basis(std::string_view station) = 0;
};

// One program on one station.
struct EstimateView {
  std::string station;
  std::optional<double> predicted_s;  // the model's number; nullopt: `why`
  std::string why;
  std::optional<double> estimate_s;  // the learned estimate the backlog uses (the prediction before any run)
  int runs = 0;                      // runs behind the estimate
};

struct ProgramEstimates {
  ProgramMeta meta;
  std::vector<EstimateView> stations;  // every configured station, by id
};

// The learning rule: after a run that took `actual` machine seconds (this program's share of its visit), the
// estimate moves toward it with weight 1/(runs + 1), no less than kLearnMinWeight (the mean of the first
// five runs, then an exponential moving average over about the last five), and the run counts only as far as
// [kRatioMin, kRatioMax] x the prediction: one run held up by an operator or a feed hold moves the estimate
// by a bounded step. `runs` is the number of runs before this one.
inline constexpr double kLearnMinWeight = 0.2;
inline constexpr double kRatioMin = 0.5, kRatioMax = 2.0;
double LearnEstimate(double estimate, double predicted, double actual, int runs);

}  // namespace cell::scheduler
