// Balt-System NC-110/210 as the cell sees it: file names and kinds, detection evidence, %:NAME program
// headers, runs, and the tool table in the form of the offsets file FI1COR
// (../shared/reference/seed-balt.md).
#include <fmt/format.h>

#include <algorithm>
#include <array>

#include "cell/error/error.h"
#include "cell/interp/balt.h"
#include "cell/interp/scan.h"
#include "interp_internal.h"

namespace cell::interp {
namespace {

using namespace scan;

// Three-letter commands only Balt-System uses (MIR, CLS, WAI, SET and MSG are shared with KT-APL or too
// generic).
constexpr auto kBaltOnly = std::to_array<std::string_view>(
    {"DIS", "URT", "UAO", "UOT", "RPT", "UAV", "ERP", "BEQ", "RQU", "DPI", "RQO", "EPP", "TOF",
     "BGT", "DLO", "UIO", "SCF", "DSA", "DPT", "BLT", "ASC", "BNC", "INP", "DSC", "UCG", "CTL",
     "BNE", "DLY", "SND", "RQP", "EXE", "DTL", "GTL", "EPT", "BGE", "BLE", "BGR", "BLS", "TCA"});

class Balt final : public Dialect {
 public:
  std::string_view name() const override { return "balt"; }
  std::string_view title() const override { return "Balt-System NC-110/210"; }
  std::vector<std::string_view> aliases() const override {
    return {"BALT-SYSTEM", "BALT_SYSTEM", "NC110", "NC210"};
  }
  MachineKind machine() const override { return MachineKind::kMachiningCentre; }
  std::vector<FileKind> kinds() const override {
    return {FileKind::kPartProgram, FileKind::kLibrary, FileKind::kToolTable};
  }
  std::vector<std::string_view> extensions() const override { return {".balt", ".nc"}; }

  void CheckName(std::string_view name, FileKind kind) const override {
    (void)kind;
    CheckPlainName(name, "Balt-System");
  }

  // An offsets file (records "n Z.. K..") is a tool table; anything else a part program (subroutines are
  // programs too: CLS calls a program by name).
  FileKind Classify(std::string_view text) const override {
    try {
      (void)balt::ParseOffsets(text, {}, true);
      return FileKind::kToolTable;
    } catch (const balt::FileError&) {
      return FileKind::kPartProgram;
    }
  }

  void FindEvidence(std::string_view text, std::vector<Evidence>& out) const override {
    std::vector<std::string_view> lines = Lines(text);
    for (std::size_t idx = 0; idx < lines.size(); ++idx) {
      int ln = static_cast<int>(idx) + 1;
      std::string upper = Upper(Trim(lines[idx]));
      if (upper.empty()) continue;
      for (const std::string& m : Mnemonics(upper)) {
        if (std::find(kBaltOnly.begin(), kBaltOnly.end(), m) != kBaltOnly.end()) {
          out.push_back({ln, fmt::format("({},...) statement", m), true});
        }
      }
      if (upper.rfind("%:", 0) == 0) out.push_back({ln, "%:NAME program header", true});
      if (upper[0] == ';') out.push_back({ln, "';' comment line", false});
      std::string_view body = SkipSequence(upper);
      // E parameter assignment "E40=..."
      if (body.size() >= 3 && body[0] == 'E' && IsDigit(body[1])) {
        std::size_t i = 1;
        while (i < body.size() && IsDigit(body[i])) ++i;
        while (i < body.size() && body[i] == ' ') ++i;
        if (i < body.size() && body[i] == '=') out.push_back({ln, "E parameter assignment", true});
      }
    }
  }

  Heading ReadHeading(std::string_view text, const HeadingOptions& options) const override {
    (void)options;
    Heading h;
    ProgramNameCollector names(h);
    std::vector<std::string_view> lines = Lines(text);
    for (std::size_t idx = 0; idx < lines.size(); ++idx) {
      int ln = static_cast<int>(idx) + 1;
      std::string upper = Upper(Trim(lines[idx]));
      if (upper.rfind("%:", 0) != 0) continue;
      std::string name(Trim(std::string_view(upper).substr(2)));
      if (name.empty()) continue;
      if (!names.Add(name, ln, "%:")) continue;
    }
    return h;
  }

  std::unique_ptr<Run> StartRun(const RunOptions& options) const override {
    return std::make_unique<balt::BaltRun>(options);
  }

  // The offsets file FI1COR (§6.4.1, §6.5.2): records "n Z.. K.." applied on top of `base`.
  tooltable::ToolTable ParseToolTable(std::string_view text, std::string_view source,
                                      const tooltable::ToolTable& base) const override {
    try {
      return balt::ParseOffsets(text, base, true);
    } catch (const balt::FileError& e) {
      throw Error(Errc::kInvalidArgument,
                  fmt::format("{}:{}:{}: error: [FILMS4 {:02}] {}: {}", source, e.line, e.col, e.code,
                              balt::FilmsText(e.code), e.text));
    }
  }
};

}  // namespace

const Dialect& BaltDialect() {
  static const Balt kBalt;
  return kBalt;
}

}  // namespace cell::interp
