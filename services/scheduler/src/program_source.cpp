#include "cell/scheduler/program_source.h"

#include <algorithm>
#include <cctype>
#include <string>

#include "cell/error/error.h"

namespace cell::scheduler {
namespace {

char Upper(char c) {
  return static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
}
bool IsDigit(char c) {
  return c >= '0' && c <= '9';
}

[[noreturn]] void Fail(std::string_view name, int line, std::size_t col, const std::string& text) {
  throw Error(Errc::kInvalidArgument, std::string(name) + ":" + std::to_string(line) + ":" +
                                          std::to_string(col) + ": error: " + text);
}

bool MnemonicAt(std::string_view line, std::size_t i, std::string_view m) {
  if (i + 1 + m.size() > line.size()) return false;
  for (std::size_t k = 0; k < m.size(); ++k) {
    if (Upper(line[i + 1 + k]) != m[k]) return false;
  }
  return true;
}

}  // namespace

ProgramMeta ExtractKtaplMeta(std::string_view text, std::string_view name) {
  ProgramMeta meta;
  meta.name = std::string(name);
  int line_no = 0;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t eol = text.find('\n', start);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view line = text.substr(start, eol - start);
    ++line_no;
    for (std::size_t i = 0; i < line.size(); ++i) {
      const char c = line[i];
      if (c == '!') break;  // comment to end of line
      if (c != '(' && c != '%') continue;
      const bool utl = MnemonicAt(line, i, "UTL");
      const bool ucy = MnemonicAt(line, i, "UCY");
      if (!utl && !ucy) continue;
      const char close = c == '(' ? ')' : '%';
      std::size_t p = i + 4;
      while (p < line.size() && line[p] == ' ') ++p;
      if (p >= line.size() || line[p] != ',')
        Fail(name, line_no, p + 1, utl ? "expected ',' after UTL" : "expected ',' after UCY");
      const std::size_t end = line.find(close, p + 1);
      if (end == std::string_view::npos) {
        Fail(name, line_no, i + 1,
             std::string(utl ? "UTL" : "UCY") + " statement without closing '" + close + "'");
      }
      // Fields separated by commas, each trimmed.
      std::size_t f = p + 1;
      std::vector<std::pair<std::string_view, std::size_t>> fields;  // text, 1-based column
      while (true) {
        std::size_t comma = line.find(',', f);
        if (comma == std::string_view::npos || comma > end) comma = end;
        std::size_t a = f, b = comma;
        while (a < b && (line[a] == ' ' || line[a] == '\t')) ++a;
        while (b > a && (line[b - 1] == ' ' || line[b - 1] == '\t')) --b;
        fields.emplace_back(line.substr(a, b - a), a + 1);
        if (comma == end) break;
        f = comma + 1;
      }
      if (ucy) {
        if (meta.ucy_s) Fail(name, line_no, i + 1, "second UCY statement");
        if (fields.size() != 1) Fail(name, line_no, fields[1].second, "UCY takes one value: (UCY,seconds)");
        auto [v, col] = fields[0];
        if (v.empty() || v.size() > 7 || !std::all_of(v.begin(), v.end(), IsDigit)) {
          Fail(name, line_no, col, "UCY needs whole seconds of up to 7 digits (UCY,nnnnnnn)");
        }
        meta.ucy_s = std::stoll(std::string(v));
      } else {
        for (auto [v, col] : fields) {
          std::string_view digits = v;
          if (!digits.empty() && Upper(digits.front()) == 'T') digits.remove_prefix(1);
          if (digits.empty() || digits.size() > 7 || !std::all_of(digits.begin(), digits.end(), IsDigit)) {
            Fail(name, line_no, col,
                 "UTL tool number must be up to 7 digits, optionally prefixed with T: '" + std::string(v) +
                     "'");
          }
          while (digits.size() > 1 && digits.front() == '0') digits.remove_prefix(1);
          std::string tool(digits);
          if (std::find(meta.tools.begin(), meta.tools.end(), tool) == meta.tools.end()) {
            meta.tools.push_back(std::move(tool));
          }
        }
      }
      i = end;
    }
    if (eol == text.size()) break;
    start = eol + 1;
  }
  return meta;
}

std::optional<ProgramMeta> TextProgramSource::Lookup(std::string_view name) {
  std::optional<std::string> text = fetch_(name);
  if (!text) return std::nullopt;
  return ExtractKtaplMeta(*text, name);
}

std::optional<ProgramMeta> MemoryProgramSource::Lookup(std::string_view name) {
  auto it = texts_.find(name);
  if (it == texts_.end()) return std::nullopt;
  return ExtractKtaplMeta(it->second, name);
}

}  // namespace cell::scheduler
