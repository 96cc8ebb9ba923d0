// The toolpath of the program a station runs, for the page (docs/dashboard.md, "Toolpath"): the program is
// the text the station published as its run started (topics::kStationProgram), or, for another program or
// one too long to publish, fetched from the program store as the station looks it up (its namespace, then
// HOST); it is run offline through
// the station's dialect with its tools, kept variables and [params], and drawn with cell_interp_plot in its
// machine's view, as `cellctl program plot --station` draws it. The page overlays what the machine has done
// and where the tool is from the axis positions it already receives.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/idl/station.h"
#include "cell/interp/plot.h"

namespace cell::program_store {
class Client;
}

namespace cell::dashboard {

// The page's form of a plot: the SVG, where the path starts and every drawn move in order (index = the SVG
// paths' data-seq) with its kind, line, ends in X Y Z (X as a radius) and, for an arc in X Y Z, its centre,
// plane and sense; `motion_ops` counts the run's motion ops (the first only says where the path starts).
nlohmann::json PathJson(const interp::Plot& plot);

// Answers of Paths::Path: an HTTP status and the body (PathJson plus station, program, node, revision (null
// for a station's published text), source,
// dialect, machine; or {"error": why}).
struct PathAnswer {
  int status = 200;
  nlohmann::json body;
};

class Paths {
 public:
  explicit Paths(bus::Participant& p);
  ~Paths();
  Paths(const Paths&) = delete;
  Paths& operator=(const Paths&) = delete;

  // The path of `program` as `station` runs it; cached per station, program source (the store's namespace and
  // revision, or the station's run and text) and tool table revision (a dry run of a long program takes a
  // while, and every browser asks for it).
  PathAnswer Path(const std::string& station, const std::string& program);

 private:
  // A program's text and where it came from: `label` for people, `key` for the cache.
  struct Source {
    std::string text, node, label, key;
    std::optional<uint32_t> revision;  // the store's; none for the text a station published
  };
  program_store::Client* Store(std::string& why);
  std::optional<Source> FromStation(const std::string& station, const std::string& program, std::string& why);
  Source FromStore(const std::string& station, const std::string& program, const std::string& prefix);
  PathAnswer Build(const std::string& station, const std::string& program);

  bus::Participant& p_;
  std::mutex mu_;       // one dry run and one store request at a time
  std::mutex data_mu_;  // what the readers keep (their callbacks run on the bus thread during a dry run)
  std::unique_ptr<program_store::Client> store_;
  std::map<std::string, cell::ToolTable> tools_;
  std::map<std::string, cell::StationVariables> vars_;
  std::map<std::string, cell::StationProgram> programs_;  // what each station's run started with
  std::map<std::string, nlohmann::json> cache_;
  bus::Reader<cell::ToolTable> tools_reader_;
  bus::Reader<cell::StationVariables> vars_reader_;
  bus::Reader<cell::StationProgram> programs_reader_;
};

}  // namespace cell::dashboard
