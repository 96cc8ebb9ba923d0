// Predicted and learned cycle times (issue 40; docs/scheduler.md "Estimates"). The scheduler asks a
// Predictor (the service's: the program run through its dialect and the station's servo model on the virtual
// clock, services/predict) for a program's machine seconds on a station, keeps the answer with the program's
// revision, and corrects it after each run with the rule of LearnEstimate.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cell/scheduler/program_source.h"

namespace cell::scheduler {

struct Predicted {
  std::optional<double> seconds;  // machine seconds, first segment to end
  std::string why;                // when there is no number
};

class Predictor {
 public:
  virtual ~Predictor() = default;
  // `program` (a map entry) as `station` reads and runs it, offline.
  virtual Predicted Predict(std::string_view program, std::string_view station) = 0;
  // What else the prediction rests on for this station (its file's fingerprint): a change predicts again.
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
