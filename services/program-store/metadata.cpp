#include "cell/program_store/metadata.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <map>

#include "cell/error/error.h"
#include "cell/interp/ktapl_meta.h"

namespace cell::program_store {
namespace {

[[noreturn]] void Invalid(const std::string& what) {
  throw cell::Error(Errc::kInvalidArgument, what);
}

std::string Upper(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

bool IsDigit(char c) {
  return c >= '0' && c <= '9';
}
bool IsUpperAlpha(char c) {
  return c >= 'A' && c <= 'Z';
}
bool IsAlpha(char c) {
  return std::isalpha(static_cast<unsigned char>(c)) != 0;
}
bool IsAlnum(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0;
}
bool AllDigits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), IsDigit);
}

// Splits into lines (without "\n" and a trailing "\r").
std::vector<std::string_view> Lines(std::string_view content) {
  std::vector<std::string_view> lines;
  std::size_t start = 0;
  while (start < content.size()) {
    std::size_t end = content.find('\n', start);
    if (end == std::string_view::npos) end = content.size();
    std::string_view line = content.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    start = end + 1;
  }
  return lines;
}

// Skips an optional block delete "/" and a sequence number "N<digits>" (and spaces) at the start of an
// upper-cased, trimmed block. Sets `numbered` when there was an N number.
std::string_view SkipSequence(std::string_view s, bool* numbered = nullptr) {
  if (numbered != nullptr) *numbered = false;
  if (!s.empty() && s.front() == '/') s = Trim(s.substr(1));
  if (s.size() >= 2 && s.front() == 'N' && IsDigit(s[1])) {
    std::size_t i = 1;
    while (i < s.size() && (IsDigit(s[i]) || s[i] == '.')) ++i;
    if (numbered != nullptr) *numbered = true;
    s = Trim(s.substr(i));
  }
  return s;
}

// Three-letter Type II / Balt mnemonics in an upper-cased block: "(MNE," or "(MNE)" anywhere, and the KT-APL
// EIA form "%MNE," at the start.
std::vector<std::string> Mnemonics(std::string_view upper) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < upper.size(); ++i) {
    if (upper[i] != '(' && !(upper[i] == '%' && i == 0)) continue;
    std::size_t j = i + 1;
    while (j < upper.size() && upper[j] == ' ') ++j;
    if (j + 3 > upper.size()) continue;
    std::string_view m = upper.substr(j, 3);
    if (!std::all_of(m.begin(), m.end(), [](char c) { return IsUpperAlpha(c) || IsDigit(c); })) continue;
    if (!IsUpperAlpha(m[0])) continue;
    std::size_t k = j + 3;
    while (k < upper.size() && upper[k] == ' ') ++k;
    if (k < upper.size() && (upper[k] == ',' || (upper[k] == ')' && upper[i] == '('))) out.emplace_back(m);
  }
  return out;
}

bool In(std::string_view word, std::initializer_list<std::string_view> set) {
  return std::find(set.begin(), set.end(), word) != set.end();
}

template <std::size_t N>
bool In(std::string_view word, const std::array<std::string_view, N>& set) {
  return std::find(set.begin(), set.end(), word) != set.end();
}

// Mnemonics that only KT-APL uses (MIR, CLS, WAI, SET and MSG are shared with Balt-System or too generic).
constexpr auto kKtaplOnly = std::to_array<std::string_view>(
    {"NAM", "UTL", "UCY", "PAR", "DFS", "DFC", "IFT", "GTO", "LBL", "OPF", "FXC", "FWR",
     "TLD", "ZTB", "UAT", "DLF", "CER", "UFX", "RCP", "DLP", "USF", "ULF", "OIF", "CPY",
     "CLF", "ACP", "EVT", "SER", "PRT", "U88", "DAT", "OCR", "SSA", "END"});
constexpr auto kBaltOnly = std::to_array<std::string_view>(
    {"DIS", "URT", "UAO", "UOT", "RPT", "UAV", "ERP", "BEQ", "RQU", "DPI", "RQO", "EPP", "TOF",
     "BGT", "DLO", "UIO", "SCF", "DSA", "DPT", "BLT", "ASC", "BNC", "INP", "DSC", "UCG", "CTL",
     "BNE", "DLY", "SND", "RQP", "EXE", "DTL", "GTL", "EPT", "BGE", "BLE", "BGR", "BLS", "TCA"});
constexpr auto kOkumaStatements =
    std::to_array<std::string_view>({"VSET", "PSELECT", "CALL", "RTS", "MODIN", "MODOUT", "GOTO", "IF"});

int Score(const std::vector<Evidence>& evidence, Dialect d) {
  int score = 0;
  for (const Evidence& e : evidence) {
    if (e.dialect == d) score += e.strong ? 10 : 2;
  }
  return score;
}

// Okuma program name block: "O" + 1-4 digits, or "O" + a letter + up to 3 letters/digits; nothing else but
// a comment. Returns the name with its O, or "".
std::string OkumaProgramName(std::string_view upper) {
  std::size_t paren = upper.find('(');
  std::string_view s = Trim(paren == std::string_view::npos ? upper : upper.substr(0, paren));
  if (s.size() < 2 || s.size() > 5 || s[0] != 'O') return {};
  std::string_view rest = s.substr(1);
  if (AllDigits(rest)) return std::string(s);
  if (!IsUpperAlpha(rest[0])) return {};
  if (!std::all_of(rest.begin(), rest.end(), [](char c) { return IsUpperAlpha(c) || IsDigit(c); })) return {};
  return std::string(s);
}

bool HasWord(std::string_view upper, std::string_view word) {
  // word like "M30": must not be followed by a digit or '.'; must be preceded by a non-letter/digit.
  std::size_t pos = 0;
  while ((pos = upper.find(word, pos)) != std::string_view::npos) {
    bool start_ok = pos == 0 || !(IsUpperAlpha(upper[pos - 1]) || IsDigit(upper[pos - 1]));
    std::size_t end = pos + word.size();
    bool end_ok = end >= upper.size() || !(IsDigit(upper[end]) || upper[end] == '.');
    if (start_ok && end_ok) return true;
    pos = end;
  }
  return false;
}

// "M2" also matches "M02" and "M002".
bool HasMCode(std::string_view upper, int code) {
  for (std::size_t pos = 0; (pos = upper.find('M', pos)) != std::string_view::npos; ++pos) {
    if (pos > 0 && (IsUpperAlpha(upper[pos - 1]) || IsDigit(upper[pos - 1]))) continue;
    std::size_t i = pos + 1;
    int value = 0, digits = 0;
    while (i < upper.size() && IsDigit(upper[i]) && digits < 4)
      value = value * 10 + (upper[i++] - '0'), ++digits;
    if (digits > 0 && value == code && (i >= upper.size() || !IsDigit(upper[i]))) return true;
  }
  return false;
}

struct ContentFacts {
  bool has_m30_or_m02 = false;
  bool has_m17 = false;
  bool has_rts = false;
  bool has_pselect = false;
  bool defines_cycles = false;  // KT-APL DFS/DFC
  bool only_tld = true;         // KT-APL: every statement block is TLD
  int tld_blocks = 0;
  int blocks_outside_definitions = 0;  // KT-APL blocks not inside a DFS/DFC ... (END), heading excluded
};

ContentFacts Facts(const std::vector<std::string_view>& lines) {
  ContentFacts f;
  std::string upper;
  bool inside_definition = false;
  for (std::string_view raw : lines) {
    std::string_view trimmed = Trim(raw);
    upper.assign(trimmed);
    for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    if (upper.empty() || upper == "%" || upper[0] == '!') continue;
    if (HasMCode(upper, 30) || HasMCode(upper, 2)) f.has_m30_or_m02 = true;
    if (HasMCode(upper, 17)) f.has_m17 = true;
    std::string_view body = SkipSequence(upper);
    if (body.substr(0, 3) == "RTS" && (body.size() == 3 || body[3] == ' ')) f.has_rts = true;
    if (body.substr(0, 7) == "PSELECT") f.has_pselect = true;
    std::vector<std::string> m;
    if (upper.find('(') != std::string::npos || upper[0] == '%') m = Mnemonics(upper);
    auto has = [&](std::string_view mn) { return std::find(m.begin(), m.end(), mn) != m.end(); };
    bool opens = has("DFS") || has("DFC");
    if (opens) f.defines_cycles = true;
    bool heading = has("NAM") || has("UTL") || has("UCY");
    if (!inside_definition && !opens && !heading && !body.empty() && !(body[0] == '(' && m.empty())) {
      ++f.blocks_outside_definitions;
    }
    if (opens) inside_definition = true;
    if (has("END")) inside_definition = false;
    bool tld = std::find(m.begin(), m.end(), "TLD") != m.end();
    if (tld) {
      ++f.tld_blocks;
    } else if (!body.empty() && !(body[0] == '(' && m.empty())) {
      f.only_tld = false;  // anything but TLD statements and comments
    }
  }
  return f;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// Names of types and dialects

std::string_view FileTypeName(FileType type) {
  switch (type) {
    case FileType::kPartProgram:
      return "part_program";
    case FileType::kLibrary:
      return "library";
    case FileType::kSchedule:
      return "schedule";
    case FileType::kToolTable:
      return "tool_table";
    case FileType::kFixtureOffsets:
      return "fixture_offsets";
    case FileType::kInspection:
      return "inspection";
    case FileType::kData:
      return "data";
  }
  return "data";
}

std::string_view DialectName(Dialect dialect) {
  switch (dialect) {
    case Dialect::kNone:
      return "";
    case Dialect::kKtapl:
      return "ktapl";
    case Dialect::kOkuma:
      return "okuma";
    case Dialect::kEmco:
      return "emco";
    case Dialect::kBalt:
      return "balt";
  }
  return "";
}

FileType ParseFileType(std::string_view text) {
  std::string t = Upper(Trim(text));
  std::replace(t.begin(), t.end(), '-', '_');
  if (In(t, {"PART_PROGRAM", "PROGRAM", "PART", "MAIN", "MIN"})) return FileType::kPartProgram;
  if (In(t, {"LIBRARY", "LIB", "SUBROUTINE", "SUBPROGRAM", "CYCLE", "SUB"})) return FileType::kLibrary;
  if (In(t, {"SCHEDULE", "SCHEDULE_PROGRAM", "SDF"})) return FileType::kSchedule;
  if (In(t, {"TOOL_TABLE", "TOOLS", "TOOLTABLE"})) return FileType::kToolTable;
  if (In(t, {"FIXTURE_OFFSETS", "FIXTURE_OFFSET_TABLE", "FIXTURE", "FXT"})) return FileType::kFixtureOffsets;
  if (In(t, {"INSPECTION", "INSPECTION_FILE"})) return FileType::kInspection;
  if (In(t, {"DATA", "DATA_FILE", "TEXT"})) return FileType::kData;
  Invalid(
      fmt::format("unknown file type '{}' (use part_program, library, schedule, tool_table, "
                  "fixture_offsets, inspection or data)",
                  text));
}

Dialect ParseDialect(std::string_view text) {
  std::string t = Upper(Trim(text));
  if (In(t, {"KTAPL", "KT-APL", "KT_APL", "KT"})) return Dialect::kKtapl;
  if (In(t, {"OKUMA", "OSP", "OSP-E100L"})) return Dialect::kOkuma;
  if (In(t, {"EMCO", "EMCOTRONIC", "TM02"})) return Dialect::kEmco;
  if (In(t, {"BALT", "BALT-SYSTEM", "BALT_SYSTEM", "NC110", "NC210"})) return Dialect::kBalt;
  if (In(t, {"", "NONE"})) return Dialect::kNone;
  Invalid(fmt::format("unknown dialect '{}' (use ktapl, okuma, emco or balt)", text));
}

// ---------------------------------------------------------------------------------------------------------
// Text check

void CheckText(std::string_view content) {
  std::size_t i = 0;
  while (i < content.size()) {
    auto c = static_cast<unsigned char>(content[i]);
    if (c < 0x80) {
      bool allowed = c >= 0x20 ? c != 0x7f
                               : (c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v' || c == 0x1a);
      if (!allowed) {
        Invalid(fmt::format("content is not text: control byte 0x{:02x} at offset {}", c, i));
      }
      ++i;
      continue;
    }
    // UTF-8 multi-byte sequence.
    int len = (c & 0xe0) == 0xc0 ? 2 : (c & 0xf0) == 0xe0 ? 3 : (c & 0xf8) == 0xf0 ? 4 : 0;
    bool ok =
        len != 0 && i + static_cast<std::size_t>(len) <= content.size() && c != 0xc0 && c != 0xc1 && c < 0xf5;
    for (int k = 1; ok && k < len; ++k) {
      ok = (static_cast<unsigned char>(content[i + static_cast<std::size_t>(k)]) & 0xc0) == 0x80;
    }
    if (!ok) Invalid(fmt::format("content is not text: invalid UTF-8 byte 0x{:02x} at offset {}", c, i));
    i += static_cast<std::size_t>(len);
  }
}

// ---------------------------------------------------------------------------------------------------------
// Names

std::optional<FileType> TypeFromName(std::string_view name) {
  std::string upper = Upper(name);
  auto ends = [&](std::string_view suffix) {
    return upper.size() > suffix.size() &&
           upper.compare(upper.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  if (ends(";FXT")) return FileType::kFixtureOffsets;
  if (ends(".SDF")) return FileType::kSchedule;
  if (ends(".SUB") || ends(".SSB") || ends(".MSB") || ends(".LIB")) return FileType::kLibrary;
  if (ends(".MIN")) return FileType::kPartProgram;
  return std::nullopt;
}

namespace {

constexpr std::size_t kMaxGenericName = 128;  // the DDS bound of ProgramRequest.name

void CheckCommon(std::string_view name, std::string_view label) {
  if (name.empty()) Invalid(fmt::format("empty {} name", label));
  for (std::size_t i = 0; i < name.size(); ++i) {
    auto c = static_cast<unsigned char>(name[i]);
    if (c < 0x20 || c >= 0x7f) {
      Invalid(fmt::format("{} name contains a non-printable or non-ASCII byte 0x{:02x} at position {}", label,
                          c, i + 1));
    }
    if (c == '*' || c == '?') {
      Invalid(fmt::format("{} name '{}' contains the wildcard '{}' (wildcards are for listing only)", label,
                          name, static_cast<char>(c)));
    }
    if (c == '/' || c == '\\') {
      Invalid(
          fmt::format("{} name '{}' contains a path separator '{}'; the namespace is given separately "
                      "(--node)",
                      label, name, static_cast<char>(c)));
    }
  }
  if (name.front() == ' ' || name.back() == ' ') {
    Invalid(fmt::format("{} name '{}' has leading or trailing spaces", label, name));
  }
}

void CheckKtapl(std::string_view name, FileType type) {
  CheckCommon(name, "KT-APL");
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
  bool fxt = Upper(ext) == "FXT";
  if (type == FileType::kFixtureOffsets && !fxt) {
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
          fmt::format("KT-APL name '{}' contains '{}'; allowed: letters, digits, spaces, '.', '-', '_' "
                      "and one ';' before the extension",
                      name, c));
    }
  }
}

void CheckOkuma(std::string_view name) {
  CheckCommon(name, "Okuma");
  if (name.find(':') != std::string_view::npos) {
    Invalid(fmt::format(
        "Okuma name '{}' contains ':'; device prefixes such as MD1: are not part of stored names", name));
  }
  std::size_t dot = name.rfind('.');
  std::string_view base = name.substr(0, dot);
  std::string_view ext = dot == std::string_view::npos ? std::string_view() : name.substr(dot + 1);
  if (base.empty() || !IsAlpha(base.front())) {
    Invalid(fmt::format("Okuma file name '{}' must begin with a letter", name));
  }
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

void CheckHostName(std::string_view name, std::string_view label) {
  CheckCommon(name, label);
  if (name.size() > 32) {
    Invalid(fmt::format("{} name '{}' is too long: {} characters, at most 32", label, name, name.size()));
  }
  if (!IsAlnum(name.front()))
    Invalid(fmt::format("{} name '{}' must begin with a letter or digit", label, name));
  for (char c : name) {
    if (!(IsAlnum(c) || c == '.' || c == '-' || c == '_')) {
      Invalid(
          fmt::format("{} name '{}' contains '{}'; allowed: letters, digits, '.', '-', '_'", label, name, c));
    }
  }
}

}  // namespace

void ValidateName(std::string_view name, FileType type, Dialect dialect) {
  if (type == FileType::kFixtureOffsets) return CheckKtapl(name, type);
  switch (dialect) {
    case Dialect::kKtapl:
      return CheckKtapl(name, type);
    case Dialect::kOkuma:
      return CheckOkuma(name);
    case Dialect::kEmco:
      return CheckHostName(name, "EMCO");
    case Dialect::kBalt:
      return CheckHostName(name, "Balt-System");
    case Dialect::kNone:
      break;
  }
  CheckCommon(name, "file");
  if (name.size() > kMaxGenericName) {
    Invalid(fmt::format("file name is too long: {} characters, at most {}", name.size(), kMaxGenericName));
  }
}

// ---------------------------------------------------------------------------------------------------------
// Detection

std::string Detection::Explain() const {
  auto list = [&](Dialect d) {
    std::string s;
    int n = 0;
    for (const Evidence& e : evidence) {
      if (e.dialect != d || n >= 3) continue;
      s += fmt::format("{}{} on line {}", n == 0 ? "" : ", ", e.what, e.line);
      ++n;
    }
    return s;
  };
  std::string out;
  for (Dialect d : {Dialect::kKtapl, Dialect::kOkuma, Dialect::kEmco, Dialect::kBalt}) {
    std::string items = list(d);
    if (items.empty()) continue;
    if (!out.empty()) out += "; ";
    out += fmt::format("{} ({})", DialectName(d), items);
  }
  return out.empty() ? "no dialect-specific statements found" : out;
}

Detection DetectDialect(std::string_view content) {
  // Dialect evidence is in the heading and the first blocks; reading the first 1 MiB keeps detection of a
  // 20 MB program cheap. Cut at a line boundary.
  constexpr std::size_t kWindow = 1u << 20;
  if (content.size() > kWindow) {
    std::size_t cut = content.rfind('\n', kWindow);
    content = content.substr(0, cut == std::string_view::npos ? kWindow : cut + 1);
  }
  Detection det;
  std::map<std::pair<Dialect, std::string>, int> seen;  // keep the first line of each kind of evidence
  auto add = [&](Dialect d, int line, std::string what, bool strong) {
    auto key = std::make_pair(d, what);
    if (seen.count(key) > 0) return;
    seen[key] = line;
    det.evidence.push_back({d, line, std::move(what), strong});
  };
  std::vector<std::string_view> lines = Lines(content);
  int n4_blocks = 0, other_numbered = 0, first_significant = 0;
  bool emco_cycle = false, starts_percent = false;
  int emco_cycle_line = 0;
  for (std::size_t idx = 0; idx < lines.size(); ++idx) {
    int ln = static_cast<int>(idx) + 1;
    std::string upper = Upper(Trim(lines[idx]));
    if (upper.empty()) continue;
    if (first_significant == 0) {
      first_significant = ln;
      // EMCO: "A program may begin with % or with the letter O" (a program number O0000-O9999).
      starts_percent = upper[0] == '%' || (upper.size() >= 2 && upper.size() <= 5 && upper[0] == 'O' &&
                                           AllDigits(std::string_view(upper).substr(1)));
    }
    for (const std::string& m : Mnemonics(upper)) {
      if (In(m, kKtaplOnly)) add(Dialect::kKtapl, ln, fmt::format("({},...) statement", m), true);
      if (In(m, kBaltOnly)) add(Dialect::kBalt, ln, fmt::format("({},...) statement", m), true);
    }
    if (upper.rfind("%:", 0) == 0) add(Dialect::kBalt, ln, "%:NAME program header", true);
    if (upper[0] == ';') add(Dialect::kBalt, ln, "';' comment line", false);
    if (upper[0] == '!') add(Dialect::kKtapl, ln, "'!' comment", false);
    if (upper[0] == '$' && upper.find('.') != std::string::npos) {
      add(Dialect::kOkuma, ln, "$FILE.EXT tape header", false);
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
    // Okuma: a sequence *name* with letters ("NAT01 G81"), statements, variables.
    {
      std::string_view s = Trim(upper);
      if (s.size() >= 3 && s[0] == 'N' && IsUpperAlpha(s[1])) {
        std::size_t i = 1;
        while (i < s.size() && (IsUpperAlpha(s[i]) || IsDigit(s[i]))) ++i;
        if (i <= 5 && i < s.size() && (s[i] == ' ' || s[i] == '\t')) {
          add(Dialect::kOkuma, ln, "sequence name with letters", true);
          body = Trim(s.substr(i));
        }
      }
    }
    std::size_t word_end = 0;
    while (word_end < body.size() && IsUpperAlpha(body[word_end])) ++word_end;
    std::string_view word = body.substr(0, word_end);
    if (In(word, kOkumaStatements) &&
        (word_end == body.size() || body[word_end] == ' ' || (word == "IF" && body[word_end] == '['))) {
      add(Dialect::kOkuma, ln, fmt::format("{} statement", word), true);
    }
    if (!OkumaProgramName(upper).empty()) add(Dialect::kOkuma, ln, "O program name", false);
    // Balt-System E parameter assignment "E40=..."
    if (body.size() >= 3 && body[0] == 'E' && IsDigit(body[1])) {
      std::size_t i = 1;
      while (i < body.size() && IsDigit(body[i])) ++i;
      while (i < body.size() && body[i] == ' ') ++i;
      if (i < body.size() && body[i] == '=') add(Dialect::kBalt, ln, "E parameter assignment", true);
    }
    // KT-APL parameter addresses "XL1500"
    for (std::size_t i = 0; i + 2 < body.size(); ++i) {
      if (In(std::string_view(&body[i], 1), {"X", "Y", "Z", "A", "B", "C", "F", "S"}) && body[i + 1] == 'L' &&
          IsDigit(body[i + 2]) && (i == 0 || !IsUpperAlpha(body[i - 1]))) {
        add(Dialect::kKtapl, ln, "L parameter address", false);
        break;
      }
    }
    // EMCO cycle parameters "D3=..." / "P0 = ..." and subroutine call "G25 L..."
    for (std::size_t i = 0; i + 2 < body.size(); ++i) {
      if ((body[i] == 'D' || body[i] == 'P') && IsDigit(body[i + 1]) &&
          (i == 0 || body[i - 1] == ' ' || body[i - 1] == '/')) {
        std::size_t k = i + 2;
        while (k < body.size() && body[k] == ' ') ++k;
        if (k < body.size() && body[k] == '=') {
          add(Dialect::kEmco, ln, fmt::format("{} cycle parameter", body[i]), true);
          break;
        }
      }
    }
    for (std::string_view g : {"G25", "G27"}) {
      std::size_t pos = body.find(g);
      if (pos != std::string_view::npos) {
        std::string_view after = Trim(body.substr(pos + 3));
        if (after.size() >= 2 && after[0] == 'L' && IsDigit(after[1])) {
          add(Dialect::kEmco, ln, fmt::format("{} L subroutine/jump", g), true);
        }
      }
    }
    if (!emco_cycle) {
      for (std::string_view g : {"G84", "G85", "G86", "G87", "G88", "G33"}) {
        if (HasWord(body, g)) {
          emco_cycle = true;
          emco_cycle_line = ln;
        }
      }
    }
    if (HasWord(body, "G01") || HasWord(body, "G00") || HasWord(body, "G1") || HasWord(body, "G0") ||
        HasWord(body, "G2") || HasWord(body, "G3") || HasWord(body, "G02") || HasWord(body, "G03") ||
        HasMCode(body, 30) || HasMCode(body, 2) || HasMCode(body, 6) || HasMCode(body, 3)) {
      det.looks_like_nc = true;
    }
  }
  // EMCO TM02: "%" (or an O number) first, then 4-digit block numbers throughout, with lathe cycles.
  if (starts_percent && n4_blocks >= 3 && other_numbered == 0) {
    add(Dialect::kEmco, first_significant, "%/O header with 4-digit N blocks", false);
    if (emco_cycle) add(Dialect::kEmco, emco_cycle_line, "4-digit N blocks with G84-G88/G33 cycles", true);
  }
  if (n4_blocks + other_numbered > 0) det.looks_like_nc = true;

  std::array<std::pair<int, Dialect>, 4> scores = {{{Score(det.evidence, Dialect::kKtapl), Dialect::kKtapl},
                                                    {Score(det.evidence, Dialect::kOkuma), Dialect::kOkuma},
                                                    {Score(det.evidence, Dialect::kEmco), Dialect::kEmco},
                                                    {Score(det.evidence, Dialect::kBalt), Dialect::kBalt}}};
  std::stable_sort(scores.begin(), scores.end(), [](auto& a, auto& b) { return a.first > b.first; });
  int top = scores[0].first, second = scores[1].first;
  if (top >= 10 && second >= 10) {
    det.ambiguous = true;
  } else if ((top >= 10) || (top >= 2 && second == 0)) {
    det.dialect = scores[0].second;
  } else if (top > 0) {
    det.ambiguous = true;  // only weak hints for more than one dialect
  }
  if (det.dialect != Dialect::kNone || det.ambiguous) det.looks_like_nc = true;
  return det;
}

// ---------------------------------------------------------------------------------------------------------
// Extraction

std::uint64_t CountLines(std::string_view content) {
  if (content.empty()) return 0;
  auto n = static_cast<std::uint64_t>(std::count(content.begin(), content.end(), '\n'));
  return content.back() == '\n' ? n : n + 1;
}

namespace {

void ProgramNames(const std::vector<std::string_view>& lines, Dialect dialect, Metadata& md) {
  std::map<std::string, int> first_line;
  for (std::size_t idx = 0; idx < lines.size(); ++idx) {
    int ln = static_cast<int>(idx) + 1;
    std::string upper = Upper(Trim(lines[idx]));
    if (upper.empty()) continue;
    std::string name;
    if (dialect == Dialect::kOkuma || dialect == Dialect::kEmco) {
      name = OkumaProgramName(upper);
      if (dialect == Dialect::kEmco && !name.empty() && !AllDigits(std::string_view(name).substr(1)))
        name.clear();
      if (dialect == Dialect::kEmco && name.empty() && upper.size() > 1 && upper[0] == '%' &&
          AllDigits(std::string_view(upper).substr(1))) {
        name = upper;  // "%10"
      }
    } else if (dialect == Dialect::kBalt && upper.rfind("%:", 0) == 0) {
      name = std::string(Trim(std::string_view(upper).substr(2)));
    }
    if (name.empty()) continue;
    auto [it, inserted] = first_line.emplace(name, ln);
    if (!inserted) {
      md.warnings.push_back(
          fmt::format("line {}: program name {} appears again (first on line {}); selection "
                      "by name is ambiguous",
                      ln, name, it->second));
      continue;
    }
    if (dialect == Dialect::kOkuma && name.rfind("OO", 0) == 0) {
      md.warnings.push_back(fmt::format("line {}: program names OO... are reserved for the system", ln));
    }
    md.program_names.push_back(name);
  }
}

bool NeedsDialect(FileType type) {
  return type == FileType::kPartProgram || type == FileType::kLibrary || type == FileType::kSchedule;
}

}  // namespace

Metadata ExtractMetadata(std::string_view content, const ExtractOptions& options) {
  CheckText(content);
  Metadata md;
  md.size = content.size();
  md.lines = CountLines(content);
  std::vector<std::string_view> lines = Lines(content);

  std::optional<FileType> type = options.type;
  if (!type) type = TypeFromName(options.name);
  if (type == FileType::kSchedule && !options.dialect) {
    md.dialect = Dialect::kOkuma;  // schedule programs are Okuma OSP's
  } else if (type == FileType::kFixtureOffsets && !options.dialect) {
    md.dialect = Dialect::kKtapl;  // ;FXT files are KT-APL's
  } else if (options.dialect) {
    md.dialect = *options.dialect;
    if (md.dialect != Dialect::kNone) {
      Detection det = DetectDialect(content);
      if (det.dialect != Dialect::kNone && det.dialect != md.dialect && !det.ambiguous) {
        md.warnings.push_back(fmt::format("declared dialect {}, but the content looks like {}",
                                          DialectName(md.dialect), det.Explain()));
      }
    }
  } else if (!type || NeedsDialect(*type) || *type == FileType::kToolTable) {
    Detection det = DetectDialect(content);
    const Dialect station = options.namespace_dialect;
    bool station_has_evidence = std::any_of(det.evidence.begin(), det.evidence.end(),
                                            [&](const Evidence& e) { return e.dialect == station; });
    bool wants_dialect =
        det.looks_like_nc || (type && (NeedsDialect(*type) || *type == FileType::kToolTable));
    if (det.dialect != Dialect::kNone) {
      md.dialect = det.dialect;
      md.dialect_detected = true;
    } else if (det.ambiguous && station != Dialect::kNone && station_has_evidence) {
      md.dialect = station;
      md.dialect_detected = true;
      md.warnings.push_back(
          fmt::format("the content fits more than one dialect ({}); took {}, the dialect of the "
                      "station namespace",
                      det.Explain(), DialectName(station)));
    } else if (det.ambiguous) {
      Invalid(
          fmt::format("cannot tell the dialect: the content fits more than one: {}; declare it (--dialect "
                      "ktapl|okuma|emco|balt)",
                      det.Explain()));
    } else if (wants_dialect && station != Dialect::kNone) {
      md.dialect = station;  // nothing dialect-specific: the station's own dialect
      md.dialect_detected = true;
    } else if (wants_dialect) {
      Invalid(
          fmt::format("cannot tell the dialect: {} (the content looks like an NC program but has no "
                      "dialect-specific statement); declare it (--dialect ktapl|okuma|emco|balt)",
                      det.Explain()));
    }
  }

  ContentFacts facts = Facts(lines);
  if (!type) {
    switch (md.dialect) {
      case Dialect::kKtapl:
        if (facts.tld_blocks > 0 && facts.only_tld) {
          type = FileType::kToolTable;
        } else if (facts.defines_cycles && facts.blocks_outside_definitions == 0) {
          type = FileType::kLibrary;
        } else {
          type = FileType::kPartProgram;
        }
        break;
      case Dialect::kOkuma:
        if (facts.has_pselect) {
          type = FileType::kSchedule;
        } else if (facts.has_rts && !facts.has_m30_or_m02) {
          type = FileType::kLibrary;
        } else {
          type = FileType::kPartProgram;
        }
        break;
      case Dialect::kEmco:
        type = facts.has_m17 && !facts.has_m30_or_m02 ? FileType::kLibrary : FileType::kPartProgram;
        break;
      case Dialect::kBalt:
        type = FileType::kPartProgram;
        break;
      case Dialect::kNone:
        type = FileType::kData;
        break;
    }
  }
  md.type = *type;
  if (NeedsDialect(md.type) && md.dialect == Dialect::kNone) {
    Invalid(fmt::format("a {} needs a dialect; declare it (--dialect ktapl|okuma|emco|balt)",
                        FileTypeName(md.type)));
  }
  if (md.type == FileType::kSchedule && md.dialect != Dialect::kOkuma) {
    Invalid(fmt::format("schedule programs (.SDF) are Okuma OSP programs, not {}", DialectName(md.dialect)));
  }

  if (md.dialect == Dialect::kKtapl) {
    interp::KtaplMetadata heading =
        interp::ExtractKtaplMetadata(content, {.part_program = md.type == FileType::kPartProgram});
    md.nam = heading.name.value_or("");
    md.utl = std::move(heading.tools);
    md.ucy_s = heading.cycle_s;
    for (const interp::KtaplMetaWarning& w : heading.warnings) md.warnings.push_back(w.Format());
  } else if (md.dialect != Dialect::kNone) {
    ProgramNames(lines, md.dialect, md);
  }
  return md;
}

std::string DefaultName(std::string_view file_path, const Metadata& metadata) {
  if (metadata.dialect == Dialect::kKtapl && !metadata.nam.empty()) return metadata.nam;
  std::size_t slash = file_path.find_last_of('/');
  return std::string(slash == std::string_view::npos ? file_path : file_path.substr(slash + 1));
}

}  // namespace cell::program_store
