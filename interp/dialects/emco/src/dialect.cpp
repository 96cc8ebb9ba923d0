// EMCOTRONIC TM02 as the cell sees it: the Dialect the registry lists (file names and kinds, detection
// evidence, program numbers, runs, the X/Z/R/L tool data file, the manual's listing style;
// ../shared/reference/seed-emco.md).
#include <fmt/format.h>

#include "cell/interp/emco.h"
#include "cell/interp/scan.h"
#include "interp_internal.h"
#include "listing.h"
#include "tool_table.h"

namespace cell::interp {
namespace {

using namespace scan;

class Emco final : public Dialect {
 public:
  std::string_view name() const override { return "emco"; }
  std::string_view title() const override { return "EMCOTRONIC TM02"; }
  std::vector<std::string_view> aliases() const override { return {"EMCOTRONIC", "TM02"}; }
  MachineKind machine() const override { return MachineKind::kLathe; }
  std::vector<FileKind> kinds() const override {
    return {FileKind::kPartProgram, FileKind::kLibrary, FileKind::kToolTable};
  }
  std::vector<std::string_view> extensions() const override { return {".emco", ".nc"}; }

  void CheckName(std::string_view name, FileKind kind) const override {
    (void)kind;
    CheckPlainName(name, "EMCO");
  }

  FileKind Classify(std::string_view text) const override {
    bool m17 = false, end = false;
    for (std::string_view raw : Lines(text)) {
      std::string upper = Upper(Trim(raw));
      if (HasMCode(upper, 30) || HasMCode(upper, 2)) end = true;
      if (HasMCode(upper, 17)) m17 = true;
    }
    return m17 && !end ? FileKind::kLibrary : FileKind::kPartProgram;
  }

  void FindEvidence(std::string_view text, std::vector<Evidence>& out) const override {
    std::vector<std::string_view> lines = Lines(text);
    int n4_blocks = 0, other_numbered = 0, first_significant = 0, cycle_line = 0;
    bool starts_percent = false;
    for (std::size_t idx = 0; idx < lines.size(); ++idx) {
      int ln = static_cast<int>(idx) + 1;
      std::string upper = Upper(Trim(lines[idx]));
      if (upper.empty()) continue;
      if (first_significant == 0) {
        first_significant = ln;
        // "A program may begin with % or with the letter O" (a program number O0000-O9999).
        starts_percent = upper[0] == '%' || (upper.size() >= 2 && upper.size() <= 5 && upper[0] == 'O' &&
                                             AllDigits(std::string_view(upper).substr(1)));
      }
      bool numbered = false;
      std::string_view body = SkipSequence(upper, &numbered);
      if (numbered) {
        std::size_t digits = 0;
        std::string_view s = Trim(upper);
        if (!s.empty() && s[0] == '/') s = Trim(s.substr(1));
        while (digits + 1 < s.size() && IsDigit(s[digits + 1])) ++digits;
        if (digits == 4 && (digits + 1 >= s.size() || s[digits + 1] == ' ' || s[digits + 1] == '/')) {
          ++n4_blocks;
        } else {
          ++other_numbered;
        }
      }
      // Cycle parameters "D3=..." / "P0 = ..." and the subroutine call / jump "G25 L..." / "G27 L...".
      for (std::size_t i = 0; i + 2 < body.size(); ++i) {
        if ((body[i] == 'D' || body[i] == 'P') && IsDigit(body[i + 1]) &&
            (i == 0 || body[i - 1] == ' ' || body[i - 1] == '/')) {
          std::size_t k = i + 2;
          while (k < body.size() && body[k] == ' ') ++k;
          if (k < body.size() && body[k] == '=') {
            out.push_back({ln, fmt::format("{} cycle parameter", body[i]), true});
            break;
          }
        }
      }
      for (std::string_view g : {"G25", "G27"}) {
        std::size_t pos = body.find(g);
        if (pos != std::string_view::npos) {
          std::string_view after = Trim(body.substr(pos + 3));
          if (after.size() >= 2 && after[0] == 'L' && IsDigit(after[1])) {
            out.push_back({ln, fmt::format("{} L subroutine/jump", g), true});
          }
        }
      }
      if (cycle_line == 0) {
        for (std::string_view g : {"G84", "G85", "G86", "G87", "G88", "G33"}) {
          if (HasWord(body, g)) cycle_line = ln;
        }
      }
    }
    // "%" (or an O number) first, then 4-digit block numbers throughout, with lathe cycles.
    if (starts_percent && n4_blocks >= 3 && other_numbered == 0) {
      out.push_back({first_significant, "%/O header with 4-digit N blocks", false});
      if (cycle_line != 0) out.push_back({cycle_line, "4-digit N blocks with G84-G88/G33 cycles", true});
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
      std::string name;
      std::string_view u = upper;
      std::size_t paren = u.find('(');
      std::string_view s = Trim(paren == std::string_view::npos ? u : u.substr(0, paren));
      if (s.size() >= 2 && s.size() <= 5 && s[0] == 'O' && AllDigits(s.substr(1))) name = std::string(s);
      if (name.empty() && u.size() > 1 && u[0] == '%' && AllDigits(u.substr(1))) name = upper;  // "%10"
      if (name.empty()) continue;
      if (!names.Add(name, ln, "O")) continue;
    }
    return h;
  }

  std::unique_ptr<Run> StartRun(const RunOptions& options) const override {
    return std::make_unique<emco::EmRun>(options);
  }

  tooltable::ToolTable ParseToolTable(std::string_view text, std::string_view source,
                                      const tooltable::ToolTable& base) const override {
    return emco::ParseToolData(text, source, base);
  }

  std::string ImportListing(std::string_view text) const override { return emco::ImportListing(text); }

  // What carries from program to program on the control (ln 1212-1292) and what it keeps (the registers,
  // the part counter): exactly what EmRun::Variables() reports (docs/dialects/emco.md).
  std::string CheckVariable(std::string_view name, double value) const override {
    return emco::CheckKeptVariable(name, value);
  }

  // The TM02 carries T, M03/M04/M05 and M08/M09 into the next program (ln 1212-1292); a pallet's first
  // program starts knowing the tool was put away (T 0) and spindle and coolant stopped (M05, M09), so its T
  // changes the tool.
  void PalletArrives(std::map<std::string, double>& variables) const override {
    for (const auto& [name, value] : {std::pair<const char*, double>{"ACT.T", 0}, {"M.0", 5}, {"M.3", 9}})
      if (variables.count(name)) variables[name] = value;
  }
};

}  // namespace

const Dialect& EmcoDialect() {
  static const Emco kEmco;
  return kEmco;
}

}  // namespace cell::interp
