#include "cell/testing/qif.h"

#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "cell/testing/process.h"

namespace cell::testing {

namespace fs = std::filesystem;

std::string QifSchemaDir() {
  const char* d = std::getenv("CELL_QIF_SCHEMAS");
  // The repository carries the schema (tests/schemas/README.md), so a clone validates with nothing beside it.
  const fs::path dir = d && *d ? fs::path(d) : fs::path(SourceDir()) / "tests/schemas/qif3";
  return fs::exists(dir / "QIFApplications/QIFDocument.xsd") ? dir.string() : "";
}

std::string ValidateQif(const std::string& xml) {
  const std::string dir = QifSchemaDir();
  if (dir.empty())
    return "QIF 3.0 schema not found (tests/schemas/qif3 in CELL_SOURCE_DIR, or CELL_QIF_SCHEMAS)";
  static std::atomic<int> n{0};
  const std::string file = "/tmp/cell-qif-" + std::to_string(getpid()) + "-" + std::to_string(n++) + ".qif";
  std::ofstream(file) << xml;
  auto r = RunCommand(
      {"xmllint", "--noout", "--nonet", "--schema", dir + "/QIFApplications/QIFDocument.xsd", file});
  fs::remove(file);
  return r.code == 0 ? "" : r.err + r.out + "(exit " + std::to_string(r.code) + ")";
}

}  // namespace cell::testing
