// KT-APL as the cell sees it: the Dialect the registry lists (names, kinds, detection, heading, runs, the
// tool table in TLD form).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "cell/error/error.h"
#include "cell/interp/scan.h"
#include "interp_internal.h"

namespace cell::interp {
namespace {

// Mnemonics that only KT-APL uses (MIR, CLS, WAI, SET and MSG are shared with Balt-System or too generic).
constexpr auto kKtaplOnly = std::to_array<std::string_view>(
    {"NAM", "UTL", "UCY", "PAR", "DFS", "DFC", "IFT", "GTO", "LBL", "OPF", "FXC", "FWR",
     "TLD", "ZTB", "UAT", "DLF", "CER", "UFX", "RCP", "DLP", "USF", "ULF", "OIF", "CPY",
     "CLF", "ACP", "EVT", "SER", "PRT", "U88", "DAT", "OCR", "SSA", "END"});

[[noreturn]] void Invalid(const std::string& what) {
  throw Error(Errc::kInvalidArgument, what);
}

class Ktapl final : public Dialect {
 public:
  std::string_view name() const override { return "ktapl"; }
  std::string_view title() const override { return "Kearney & Trecker KT-APL"; }
  std::vector<std::string_view> aliases() const override { return {"KT-APL", "KT_APL", "KT"}; }
  MachineKind machine() const override { return MachineKind::kMachiningCentre; }
  std::vector<FileKind> kinds() const override {
    return {FileKind::kPartProgram, FileKind::kLibrary, FileKind::kToolTable, FileKind::kFixtureOffsets};
  }
  std::vector<std::string_view> extensions() const override { return {".ktapl", ".apl", ".nc", ".txt"}; }

  std::optional<FileKind> KindFromName(std::string_view name) const override {
    std::string upper = scan::Upper(name);
    if (upper.size() > 4 && upper.compare(upper.size() - 4, 4, ";FXT") == 0) return FileKind::kFixtureOffsets;
    return std::nullopt;
  }

  // Local file names (manual ch. 7): up to 32 characters (28 before ;FXT), letters, digits, spaces, '.',
  // '-', '_', and one ';' before an extension of 1-3 letters or digits.
  void CheckName(std::string_view name, FileKind kind) const override {
    using scan::IsAlnum;
    scan::CheckNameCharacters(name, "KT-APL");
    std::size_t semi = name.find(';');
    std::string_view base = name.substr(0, semi);
    std::string_view ext = semi == std::string_view::npos ? std::string_view() : name.substr(semi + 1);
    if (base.empty()) Invalid(fmt::format("KT-APL name '{}' has an empty file name before ';'", name));
    if (semi != std::string_view::npos) {
      if (ext.empty() || ext.size() > 3 || !std::all_of(ext.begin(), ext.end(), IsAlnum)) {
        Invalid(fmt::format(
            "KT-APL name '{}': the extension after ';' must be 1-3 letters or digits (e.g. ;FXT)", name));
      }
    }
    bool fxt = scan::Upper(ext) == "FXT";
    if (kind == FileKind::kFixtureOffsets && !fxt) {
      Invalid(fmt::format("fixture offset table name '{}' must end in ;FXT (e.g. PALLET38;FXT)", name));
    }
    std::size_t limit = fxt ? 28 : 32;
    if (base.size() > limit) {
      Invalid(fmt::format("KT-APL name '{}' is too long: {} characters before {}, at most {}", name,
                          base.size(), fxt ? "';FXT'" : "the extension", limit));
    }
    for (char c : base) {
      if (c == ',')
        Invalid(fmt::format("KT-APL name '{}' contains a comma (not allowed in local file names)", name));
      if (!(IsAlnum(c) || c == ' ' || c == '.' || c == '-' || c == '_')) {
        Invalid(
            fmt::format("KT-APL name '{}' contains '{}'; allowed: letters, digits, spaces, '.', '-', '_' and "
                        "one ';' before "
                        "the extension",
                        name, c));
      }
    }
  }

  FileKind Classify(std::string_view text) const override {
    bool only_tld = true, defines = false, inside = false;
    int tld_blocks = 0, outside = 0;
    for (std::string_view raw : scan::Lines(text)) {
      std::string upper = scan::Upper(scan::Trim(raw));
      if (upper.empty() || upper == "%" || upper[0] == '!') continue;
      std::string_view body = scan::SkipSequence(upper);
      std::vector<std::string> m;
      if (upper.find('(') != std::string::npos || upper[0] == '%') m = scan::Mnemonics(upper);
      auto has = [&](std::string_view mn) { return std::find(m.begin(), m.end(), mn) != m.end(); };
      bool opens = has("DFS") || has("DFC");
      if (opens) defines = true;
      bool heading = has("NAM") || has("UTL") || has("UCY");
      if (!inside && !opens && !heading && !body.empty() && !(body[0] == '(' && m.empty())) ++outside;
      if (opens) inside = true;
      if (has("END")) inside = false;
      if (has("TLD")) {
        ++tld_blocks;
      } else if (!body.empty() && !(body[0] == '(' && m.empty())) {
        only_tld = false;  // anything but TLD statements and comments
      }
    }
    if (tld_blocks > 0 && only_tld) return FileKind::kToolTable;
    if (defines && outside == 0) return FileKind::kLibrary;
    return FileKind::kPartProgram;
  }

  void FindEvidence(std::string_view text, std::vector<Evidence>& out) const override {
    std::vector<std::string_view> lines = scan::Lines(text);
    for (std::size_t idx = 0; idx < lines.size(); ++idx) {
      int ln = static_cast<int>(idx) + 1;
      std::string upper = scan::Upper(scan::Trim(lines[idx]));
      if (upper.empty()) continue;
      for (const std::string& m : scan::Mnemonics(upper)) {
        if (std::find(kKtaplOnly.begin(), kKtaplOnly.end(), m) != kKtaplOnly.end()) {
          out.push_back({ln, fmt::format("({},...) statement", m), true});
        }
      }
      if (upper[0] == '!') out.push_back({ln, "'!' comment", false});
      std::string_view body = scan::SkipSequence(upper);
      // Parameter addresses "XL1500".
      for (std::size_t i = 0; i + 2 < body.size(); ++i) {
        if (std::string_view("XYZABCFS").find(body[i]) != std::string_view::npos && body[i + 1] == 'L' &&
            scan::IsDigit(body[i + 2]) && (i == 0 || !scan::IsUpperAlpha(body[i - 1]))) {
          out.push_back({ln, "L parameter address", false});
          break;
        }
      }
    }
  }

  Heading ReadHeading(std::string_view text, const HeadingOptions& options) const override {
    return ReadKtaplHeading(text, options);
  }

  std::unique_ptr<Run> StartRun(const RunOptions& options) const override {
    return std::make_unique<ktapl::KtRun>(options);
  }

  // A KT-APL program of TLD statements (manual ln 3975-4097): G70/G71 set the unit of the values after them;
  // other blocks (%, N numbers, NAM, comments) are skipped; the text is not run.
  tooltable::ToolTable ParseToolTable(std::string_view text, std::string_view source,
                                      const tooltable::ToolTable& base) const override {
    tooltable::ToolTable table = base;  // all or nothing
    bool metric = true;
    int found = 0, line_no = 0;
    auto fail = [&](int col, const std::string& what) -> void {
      throw Error(Errc::kInvalidArgument, fmt::format("{}:{}:{}: error: {}", source, line_no, col, what));
    };
    for (std::string_view line : scan::Lines(text)) {
      ++line_no;
      std::string err;
      size_t err_at = 0;
      auto statements = ktapl::FindStatements(line, &err, &err_at);
      // G70/G71 outside statements.
      bool in_paren = false;
      for (size_t i = 0; i < line.size(); ++i) {
        char c = line[i];
        if (c == '!') break;
        if (c == '(') in_paren = true;
        if (c == ')') in_paren = false;
        if (!in_paren && ktapl::Up(c) == 'G' && i + 2 < line.size() && line[i + 1] == '7' &&
            (line[i + 2] == '0' || line[i + 2] == '1') &&
            (i + 3 >= line.size() || !scan::IsDigit(line[i + 3]))) {
          metric = line[i + 2] == '1';
        }
      }
      for (const auto& st : statements) {
        if (st.mnemonic != "TLD") continue;
        ++found;
        ktapl::TldContext ctx;
        ctx.metric = metric;
        ctx.col0 = st.col + 5;
        ktapl::TldStatement t;
        try {
          t = ktapl::ParseTld(st.body, ctx);
        } catch (const ktapl::TldError& e) {
          fail(e.col, e.text);
        }
        if (t.entry) table.Upsert(*t.entry);
        if (t.process && !table.UpsertProcess(*t.process)) {
          fail(st.col,
               "PROCESS COMPENSATION NEEDS A PRIMARY OR SUFFIX ENTRY FIRST (tool " + t.process->tool + ")");
        }
      }
      if (!err.empty() && ktapl::Upper(line).find("TLD") != std::string::npos) {
        fail(static_cast<int>(err_at) + 1, err);
      }
    }
    if (found == 0) {
      throw Error(Errc::kInvalidArgument,
                  fmt::format("{}: no TLD statement found (a KT-APL tool table is a program "
                              "of (TLD,...) statements)",
                              source));
    }
    return table;
  }

  // Manual ln 8513-8525: machine related parameters L1000-L2999 "are not deleted when a program ends" and may
  // be modified "by the program, PMI, a subroutine, or the parameter display"; ln 8420: assignments range
  // -99999999. thru 999999999. Names as Run::Variables() reports them: "L" and the number, no leading zero.
  // The fixture table (FXC/UFX, manual ch. 6) stays too: "H1.X" ... "H32.C" in mm and degrees, "H<n>.I" the
  // B position G49 selects the line at; linear offsets within the FXC range (+-42949.672 mm).
  std::string CheckVariable(std::string_view name, double value) const override {
    if (auto f = ktapl::ParseFixtureKey(name)) {
      if (!std::isfinite(value) || (f->axis >= 0 && !IsRotaryAxis(f->axis) && std::fabs(value) > 42949.672))
        return fmt::format("{} = {} is outside the fixture offset range -42949.672 .. 42949.672 mm", name,
                           value);
      return "";
    }
    bool kept = name.size() == 5 && name[0] == 'L' && name[1] != '0' &&
                std::all_of(name.begin() + 1, name.end(), [](char c) { return scan::IsDigit(c); });
    int n = kept ? std::stoi(std::string(name.substr(1))) : 0;
    if (!kept || n < 1000 || n > 2999) {
      return fmt::format(
          "'{}' is not a variable a KT-APL station keeps (the machine parameters L1000..L2999, the fixture "
          "table H1.X..H32.C, H<n>.I)",
          name);
    }
    if (!std::isfinite(value) || value < -99999999.0 || value > 999999999.0)
      return fmt::format("{} = {} is outside the parameter range -99999999. .. 999999999.", name, value);
    return "";
  }

  // A station file's [[tools]] entry against the TLD ranges (tld.cpp holds them, for both paths).
  std::string CheckToolEntry(const tooltable::ToolEntry& entry) const override {
    return ktapl::CheckToolEntry(entry);
  }
};

}  // namespace

const Dialect& KtaplDialect() {
  static const Ktapl kKtapl;
  return kKtapl;
}

}  // namespace cell::interp
