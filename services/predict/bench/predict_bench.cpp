// predict_bench: every positive conformance program of each dialect (tests/conformance/<dialect>/NAME.<ext>
// with NAME.expected and no NAME.diag) predicted on the repository's station of that dialect (KT01, OK01,
// EM01, BS01): how many get a number, the reasons of those that do not, and the cost: machine seconds
// predicted per wall second, the mean wall time of one prediction and the slowest. Predicted against actual
// through the real processes: predict_cell_test prints those figures. Usage: predict_bench [SOURCE_DIR]
// (default: the source tree it was built from).
#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "cell/config/config.h"
#include "cell/interp/station_rules.h"
#include "cell/predict/predict.h"

namespace fs = std::filesystem;

namespace {

std::string Read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The first words of a reason, with line numbers and names taken out, to group them.
std::string Kind(const std::string& why) {
  const auto err = why.find("error: ");
  std::string k = err == std::string::npos ? why : why.substr(err + 7);
  for (const char* prefix : {"line ", "segment "}) {
    const auto at = k.find(prefix);
    if (at != std::string::npos && k.find(": ", at) != std::string::npos)
      k = k.substr(0, at) + k.substr(k.find(": ", at) + 2);
  }
  return k.substr(0, 60);
}

void Dialect(const fs::path& root, const std::string& dialect, const std::string& ext,
             const std::string& station) {
  const cell::config::StationConfig st = cell::config::LoadStationFile(
      root / "deploy" / "stations" / (station + ".toml"), &cell::interp::StationRules());
  int total = 0, numbers = 0;
  double machine = 0;
  std::map<std::string, int> why;
  double slowest = 0;  // the longest one prediction took (the scheduler's worker runs one at a time)
  std::string slowest_name;
  const auto t0 = std::chrono::steady_clock::now();
  for (const auto& e : fs::directory_iterator(root / "tests" / "conformance" / dialect)) {
    const fs::path p = e.path();
    if (p.extension() != "." + ext) continue;
    if (fs::exists(fs::path(p).replace_extension(".diag")) ||
        !fs::exists(fs::path(p).replace_extension(".expected")))
      continue;
    cell::predict::Input in;
    in.program = p.stem().string();
    in.text = Read(p);
    in.program_dialect = dialect;
    in.station = st;
    in.max_machine_s = 3600;
    const auto p0 = std::chrono::steady_clock::now();
    const cell::predict::Prediction r = cell::predict::Predict(in);
    const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - p0).count();
    if (took > slowest) {
      slowest = took;
      slowest_name = in.program;
    }
    ++total;
    if (r.seconds) {
      ++numbers;
      machine += *r.seconds;
    } else {
      ++why[Kind(r.why)];
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  fmt::print(
      "{:6} on {}: {}/{} programs predicted, {:.1f} machine s in {:.2f} wall s ({:.0f}x real time); {:.1f} "
      "ms "
      "a program, the slowest {} {:.1f} ms\n",
      dialect, station, numbers, total, machine, wall, wall > 0 ? machine / wall : 0.0,
      total ? 1000 * wall / total : 0.0, slowest_name, 1000 * slowest);
  for (const auto& [k, n] : why) fmt::print("    {:3} x {}\n", n, k);
}

}  // namespace

int main(int argc, char** argv) {
  const fs::path root = argc > 1 ? fs::path(argv[1]) : fs::path(CELL_SOURCE_DIR);
  Dialect(root, "ktapl", "ktapl", "KT01");
  Dialect(root, "okuma", "okuma", "OK01");
  Dialect(root, "emco", "emco", "EM01");
  Dialect(root, "balt", "balt", "BS01");
  return 0;
}
