// Balt-System NC-110/210 as the cell sees it: file names and kinds, detection evidence, %:NAME program
// headers, runs, and the tool table in the form of the offsets file FI1COR
// (../shared/reference/seed-balt.md).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

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

  // ln 5497: "E parameters normally remain stored after a power down": a station keeps every E parameter
  // (E0..E9999, the most a configuration has: E_PARAMETERS), each within its format of Table 5.8
  // (ln 5414-5419); a whole format takes whole numbers only (the run reports them converted).
  std::string CheckVariable(std::string_view name, double value) const override {
    bool digits = name.size() >= 2 && name.size() <= 5 && name[0] == 'E' &&
                  (name[1] != '0' || name.size() == 2) && std::all_of(name.begin() + 1, name.end(), IsDigit);
    if (!digits)
      return fmt::format("'{}' is not a variable a Balt-System station keeps (the E parameters E0..E9999)",
                         name);
    int n = std::stoi(std::string(name.substr(1)));
    struct Format {
      int last;
      double lo, hi;
      bool whole;
      const char* text;
    };
    static constexpr Format kFormats[] = {
        {9, 0, 255, true, "a byte, 0 .. 255"},
        {19, -32768, 32767, true, "an integer, -32768 .. 32767"},
        {24, -2147483647.0, 2147483647.0, true, "a long integer, -2147483647 .. 2147483647"},
        {29, -9999999.0, 9999999.0, false, "a real of 7 digits"},
        {9999, -9999999999999.0, 9999999999999.0, false, "a long real of 13 whole digits"},
    };
    for (const Format& f : kFormats) {
      if (n > f.last) continue;
      if (!std::isfinite(value) || value < f.lo || value > f.hi || (f.whole && value != std::floor(value)))
        return fmt::format("{} = {} does not fit {} (Table 5.8)", name, value, f.text);
      return "";
    }
    return "";
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
