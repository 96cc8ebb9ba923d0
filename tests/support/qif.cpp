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
  if (const char* d = std::getenv("CELL_QIF_SCHEMAS"); d && *d) return d;
  // ../shared/reference/qif3 beside the clone (CI), or beside the worktrees' folder (a developer's tree).
  fs::path p = SourceDir();
  for (int up = 0; up < 4; ++up, p = p.parent_path()) {
    fs::path c = p.parent_path() / "shared/reference/qif3";
    if (fs::exists(c / "QIFApplications/QIFDocument.xsd")) return c.string();
  }
  return "";
}

std::string ValidateQif(const std::string& xml) {
  static std::atomic<int> n{0};
  const std::string file = "/tmp/cell-qif-" + std::to_string(getpid()) + "-" + std::to_string(n++) + ".qif";
  std::ofstream(file) << xml;
  auto r = RunCommand({"xmllint", "--noout", "--nonet", "--schema",
                       QifSchemaDir() + "/QIFApplications/QIFDocument.xsd", file});
  fs::remove(file);
  return r.code == 0 ? "" : r.err + r.out + "(exit " + std::to_string(r.code) + ")";
}

}  // namespace cell::testing
