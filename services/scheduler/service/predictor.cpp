#include "cell/scheduler/station_predictor.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <vector>

#include "cell/interp/station_rules.h"
#include "cell/names/program_ref.h"
#include "cell/predict/predict.h"

namespace cell::scheduler {

namespace {

std::string FileFingerprint(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  std::uint64_t h = 14695981039346656037ull;  // FNV-1a, as a program's revision
  for (unsigned char c : text.str()) h = (h ^ c) * 1099511628211ull;
  return fmt::format("{:016x}", h);
}

}  // namespace

std::string StationPredictor::Basis(std::string_view station) {
  auto it = basis_.find(station);
  if (it != basis_.end()) return it->second;
  std::string b;
  try {
    b = FileFingerprint(interp::LoadStation(station).file.string());
  } catch (const std::exception&) {
    b = "none";  // no file: Predict says why
  }
  return basis_.emplace(std::string(station), b).first->second;
}

// As the station reads its map entry (docs/station.md): "NODE:NAME" from NODE, a plain NAME from the
// station's namespace, then HOST; subprograms likewise. A store that does not answer (here or for a
// subprogram during the run) makes the answer transient: not kept, asked again after the queue's back-off.
Predicted StationPredictor::Predict(std::string_view program, std::string_view station,
                                    std::chrono::milliseconds limit, std::stop_token stop) {
  Predicted out;
  predict::Input in;
  in.station = interp::LoadStation(station);
  const names::ProgramRef ref = names::SplitProgramRef(program);
  const std::vector<std::string> namespaces =
      ref.node.empty() ? std::vector<std::string>{in.station.id, "HOST"} : std::vector<std::string>{ref.node};
  std::optional<program_store::Client::File> file;
  try {
    for (const auto& ns : namespaces)
      if ((file = store_.Fetch(ns, ref.name))) break;
  } catch (const std::exception& e) {
    return Predicted{std::nullopt, fmt::format("the program store did not answer: {}", e.what()), true};
  }
  if (!file) {
    out.why = fmt::format("no program '{}' where {} reads it", program, station);
    return out;
  }
  in.program = ref.name;
  in.program_dialect = file->dialect();
  in.text = std::move(file->content);
  bool store_failed = false;
  in.library = [this, namespaces, &store_failed](const std::string& lib) -> std::optional<std::string> {
    try {
      for (const auto& ns : namespaces)
        if (auto text = store_.Get(ns, lib)) return text;
    } catch (...) {
      store_failed = true;
      throw;
    }
    return std::nullopt;
  };
  in.max_wall_s = std::chrono::duration<double>(limit).count();
  in.stop = std::move(stop);
  const auto t0 = std::chrono::steady_clock::now();
  const predict::Prediction p = predict::Predict(in);
  spdlog::info("predicted {} on {}: {} ({:.3f} s to predict)", program, station,
               p.seconds ? fmt::format("{:.3f} machine seconds", *p.seconds) : p.why,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  out.seconds = p.seconds;
  out.why = p.why;
  out.transient = p.transient || store_failed;
  return out;
}

}  // namespace cell::scheduler
