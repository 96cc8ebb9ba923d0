// Okuma OSP-E100L as the cell sees it: the Dialect the registry lists (file names and kinds, detection
// evidence, program names, runs, the tool table in Okuma's own form). The executor is OkRun
// (interp_internal.h); docs/dialects/okuma.md lists what it supports and every judgement call.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "cell/error/error.h"
#include "cell/interp/okuma.h"
#include "cell/interp/scan.h"
#include "interp_internal.h"
#include "tool_data.h"

namespace cell::interp {
namespace {

using namespace scan;

constexpr auto kStatements =
    std::to_array<std::string_view>({"VSET", "PSELECT", "CALL", "RTS", "MODIN", "MODOUT", "GOTO", "IF"});

[[noreturn]] void Invalid(const std::string& what) {
  throw Error(Errc::kInvalidArgument, what);
}

class Okuma final : public Dialect {
 public:
  std::string_view name() const override { return "okuma"; }
  std::string_view title() const override { return "Okuma OSP-E100L"; }
  std::vector<std::string_view> aliases() const override { return {"OSP", "OSP-E100L"}; }
  MachineKind machine() const override { return MachineKind::kLathe; }
  std::vector<FileKind> kinds() const override {
    return {FileKind::kPartProgram, FileKind::kLibrary, FileKind::kSchedule, FileKind::kToolTable};
  }
  std::vector<std::string_view> extensions() const override {
    return {".MIN", ".SUB", ".SSB", ".MSB", ".LIB"};
  }

  std::optional<FileKind> KindFromName(std::string_view name) const override {
    std::string upper = Upper(name);
    auto ends = [&](std::string_view suffix) {
      return upper.size() > suffix.size() &&
             upper.compare(upper.size() - suffix.size(), suffix.size(), suffix) == 0;
    };
    if (ends(".SDF")) return FileKind::kSchedule;
    if (ends(".SUB") || ends(".SSB") || ends(".MSB") || ends(".LIB")) return FileKind::kLibrary;
    if (ends(".MIN")) return FileKind::kPartProgram;
    return std::nullopt;
  }

  void CheckName(std::string_view name, FileKind kind) const override {
    (void)kind;
    CheckNameCharacters(name, "Okuma");
    if (name.find(':') != std::string_view::npos) {
      Invalid(fmt::format(
          "Okuma name '{}' contains ':'; device prefixes such as MD1: are not part of stored names", name));
    }
    std::size_t dot = name.rfind('.');
    std::string_view base = name.substr(0, dot);
    std::string_view ext = dot == std::string_view::npos ? std::string_view() : name.substr(dot + 1);
    if (base.empty() || !IsAlpha(base.front()))
      Invalid(fmt::format("Okuma file name '{}' must begin with a letter", name));
    if (base.size() > 16) {
      Invalid(fmt::format("Okuma file name '{}' is too long: {} characters before the extension, at most 16",
                          name, base.size()));
    }
    for (char c : base) {
      if (!(IsAlnum(c) || c == '-' || c == '_')) {
        Invalid(
            fmt::format("Okuma file name '{}' contains '{}'; allowed: letters, digits, '-', '_' and one '.' "
                        "before the extension",
                        name, c));
      }
    }
    if (dot != std::string_view::npos &&
        (ext.empty() || ext.size() > 3 || !std::all_of(ext.begin(), ext.end(), IsAlnum))) {
      Invalid(fmt::format("Okuma name '{}': the extension must be 1-3 letters or digits (MIN, SUB, SSB, SDF)",
                          name));
    }
  }

  FileKind Classify(std::string_view text) const override {
    bool pselect = false, rts = false, end = false, tool_data = false, other = false;
    for (std::string_view raw : Lines(text)) {
      std::string upper = Upper(Trim(raw));
      if (upper.empty()) continue;
      if (upper.rfind("VTOF", 0) == 0 || upper.rfind("VNSR", 0) == 0) {
        tool_data = true;
      } else if (upper != "%" && upper[0] != '(' && upper[0] != '$' && ProgramName(upper).empty()) {
        other = true;
      }
      if (HasMCode(upper, 30) || HasMCode(upper, 2)) end = true;
      std::string_view body = SkipSequence(upper);
      if (body.substr(0, 3) == "RTS" && (body.size() == 3 || body[3] == ' ')) rts = true;
      if (body.substr(0, 7) == "PSELECT") pselect = true;
    }
    if (pselect) return FileKind::kSchedule;
    if (tool_data && !other) return FileKind::kToolTable;
    if (rts && !end) return FileKind::kLibrary;
    return FileKind::kPartProgram;
  }

  void FindEvidence(std::string_view text, std::vector<Evidence>& out) const override {
    std::vector<std::string_view> lines = Lines(text);
    for (std::size_t idx = 0; idx < lines.size(); ++idx) {
      int ln = static_cast<int>(idx) + 1;
      std::string upper = Upper(Trim(lines[idx]));
      if (upper.empty()) continue;
      if (upper[0] == '$' && upper.find('.') != std::string::npos)
        out.push_back({ln, "$FILE.EXT tape header", false});
      std::string_view body = SkipSequence(upper);
      // A sequence *name* with letters ("NAT01 G81").
      std::string_view s = Trim(upper);
      if (s.size() >= 3 && s[0] == 'N' && IsUpperAlpha(s[1])) {
        std::size_t i = 1;
        while (i < s.size() && (IsUpperAlpha(s[i]) || IsDigit(s[i]))) ++i;
        if (i <= 5 && i < s.size() && (s[i] == ' ' || s[i] == '\t')) {
          out.push_back({ln, "sequence name with letters", true});
          body = Trim(s.substr(i));
        }
      }
      std::size_t word_end = 0;
      while (word_end < body.size() && IsUpperAlpha(body[word_end])) ++word_end;
      std::string_view word = body.substr(0, word_end);
      if (std::find(kStatements.begin(), kStatements.end(), word) != kStatements.end() &&
          (word_end == body.size() || body[word_end] == ' ' || (word == "IF" && body[word_end] == '['))) {
        out.push_back({ln, fmt::format("{} statement", word), true});
      }
      if (!ProgramName(upper).empty()) out.push_back({ln, "O program name", false});
    }
  }

  Heading ReadHeading(std::string_view text, const HeadingOptions& options) const override {
    (void)options;
    Heading h;
    ProgramNameCollector names(h);
    std::vector<std::string_view> lines = Lines(text);
    for (std::size_t idx = 0; idx < lines.size(); ++idx) {
      int ln = static_cast<int>(idx) + 1;
      std::string name = ProgramName(Upper(Trim(lines[idx])));
      if (name.empty()) continue;
      if (!names.Add(name, ln, "O")) continue;
      if (name.rfind("OO", 0) == 0) {
        h.notices.push_back(
            {HeadingNotice::Kind::kValue, "O", ln, 1, "program names OO... are reserved for the system"});
      }
    }
    return h;
  }

  std::unique_ptr<Run> StartRun(const RunOptions& options) const override {
    return std::make_unique<okuma::OkRun>(options);
  }

  tooltable::ToolTable ParseToolTable(std::string_view text, std::string_view source,
                                      const tooltable::ToolTable& base) const override {
    return okuma::ParseToolDataText(text, source, base);
  }

  // A station keeps the common variables V1-V200 (ln 7553-7576: they survive reset and power-off);
  // the manual gives them no range of their own: the tape's 8 digits bound them (judgement call 39).
  std::string CheckVariable(std::string_view name, double value) const override {
    bool digits = name.size() >= 2 && name.size() <= 4 && name[0] == 'V' && name[1] != '0' &&
                  std::all_of(name.begin() + 1, name.end(), IsDigit);
    int n = digits ? std::stoi(std::string(name.substr(1))) : 0;
    if (n < 1 || n > 200) {
      return fmt::format("'{}' is not a variable an Okuma station keeps (the common variables V1..V200)",
                         name);
    }
    if (!std::isfinite(value) || std::fabs(value) > 99999999.0)
      return fmt::format("{} = {} is outside the range -99999999 .. 99999999", name, value);
    return "";
  }

  // Program name block: "O" + 1-4 digits, or "O" + a letter + up to 3 letters/digits; nothing else but a
  // comment. Returns the name with its O, or "".
  static std::string ProgramName(std::string_view upper) {
    std::size_t paren = upper.find('(');
    std::string_view s = Trim(paren == std::string_view::npos ? upper : upper.substr(0, paren));
    if (s.size() < 2 || s.size() > 5 || s[0] != 'O') return {};
    std::string_view rest = s.substr(1);
    if (AllDigits(rest)) return std::string(s);
    if (!IsUpperAlpha(rest[0])) return {};
    if (!std::all_of(rest.begin(), rest.end(), [](char c) { return IsUpperAlpha(c) || IsDigit(c); }))
      return {};
    return std::string(s);
  }
};

}  // namespace

const Dialect& OkumaDialect() {
  static const Okuma kOkuma;
  return kOkuma;
}

}  // namespace cell::interp
