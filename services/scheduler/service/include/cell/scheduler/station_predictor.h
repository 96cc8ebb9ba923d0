// The scheduler service's Predictor (cell/scheduler/estimates.h): a program from the program store, run
// through services/predict on the station's file (its dialect, [params], tools and machine model), offline.
// Predict runs on the service's PredictionQueue worker, Basis on the scheduler's thread: they share nothing.
#pragma once

#include <chrono>
#include <map>
#include <string>
#include <string_view>

#include "cell/bus/bus.h"
#include "cell/program_store/client.h"
#include "cell/scheduler/estimates.h"

namespace cell::scheduler {

class StationPredictor : public Predictor {
 public:
  // A program store client of its own (the service's is used under its lock), whose requests give up after
  // `fetch_timeout`: a store that does not answer makes a transient failure, asked again later.
  explicit StationPredictor(bus::Participant& p,
                            std::chrono::milliseconds fetch_timeout = std::chrono::milliseconds(5000))
      : store_(p, fetch_timeout) {}
  Predicted Predict(std::string_view program, std::string_view station, std::chrono::milliseconds limit,
                    std::stop_token stop) override;
  // The station file's text fingerprint, read once: the service reads its stations' files at start.
  std::string Basis(std::string_view station) override;

 private:
  program_store::Client store_;
  std::map<std::string, std::string, std::less<>> basis_;
};

}  // namespace cell::scheduler
