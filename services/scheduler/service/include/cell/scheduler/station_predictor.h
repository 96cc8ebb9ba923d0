// The scheduler service's Predictor (cell/scheduler/estimates.h): a program from the program store, run
// through services/predict on the station's file (its dialect, [params], tools and machine model), offline.
#pragma once

#include <map>
#include <string>
#include <string_view>

#include "cell/program_store/client.h"
#include "cell/scheduler/estimates.h"

namespace cell::scheduler {

class StationPredictor : public Predictor {
 public:
  explicit StationPredictor(program_store::Client& store) : store_(store) {}
  Predicted Predict(std::string_view program, std::string_view station) override;
  // The station file's text fingerprint, read once: the service reads its stations' files at start.
  std::string Basis(std::string_view station) override;

 private:
  program_store::Client& store_;
  std::map<std::string, std::string, std::less<>> basis_;
};

}  // namespace cell::scheduler
