#include "cell/tooltable/tooltable.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

#include "cell/error/error.h"

namespace cell::tooltable {
namespace {

constexpr double kMmPerInch = 25.4;

char Upper(char c) {
  return static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
}
bool IsDigit(char c) {
  return c >= '0' && c <= '9';
}

[[noreturn]] void Fail(std::string_view source, int line, int col, const std::string& text) {
  throw Error(Errc::kInvalidArgument, std::string(source) + ":" + std::to_string(line) + ":" +
                                          std::to_string(col) + ": error: " + text);
}

// Parses the body of one TLD statement (the text after "TLD,"), `col0` being the 1-based column of body[0].
class BodyParser {
 public:
  BodyParser(std::string_view body, std::string_view source, int line, int col0, bool metric, int max_pallet)
      : body_(body), source_(source), line_(line), col0_(col0), metric_(metric), max_pallet_(max_pallet) {}

  TldStatement Parse() {
    std::string tool;
    std::optional<int> socket, pallet, life;
    std::optional<double> length, diameter, hp;
    bool check = false, manual = false, broken = false, worn = false;
    std::string seen;
    int tool_col = 0, manual_col = 0;
    SkipBlanks();
    if (pos_ >= body_.size()) Fail(source_, line_, Col(), "TLD needs at least a T tool number");
    while (pos_ < body_.size()) {
      const int letter_col = Col();
      const char letter = Upper(body_[pos_]);
      if (seen.find(letter) != std::string::npos) {
        Fail(source_, line_, letter_col, std::string("TLD letter ") + letter + " given twice");
      }
      seen.push_back(letter);
      ++pos_;
      SkipBlanks();
      switch (letter) {
        case 'S':
          socket = Integer(letter, 1, 999);
          break;
        case 'T':
          tool_col = letter_col;
          tool = Tool();
          break;
        case 'W':
          pallet = Integer(letter, 1, max_pallet_);
          break;
        case 'P':
          length = Decimal(letter);
          break;
        case 'D':
          diameter = Decimal(letter);
          break;
        case 'L': {
          // hhmm right-aligned (seed line 4051-4055: "L2241 = 22 Hours and 41 Minutes").
          const int v = Integer(letter, 0, 9959);
          if (v % 100 > 59) Fail(source_, line_, letter_col, "TLD L minutes (last two digits) exceed 59");
          life = (v / 100) * 60 + v % 100;
          break;
        }
        case 'H': {
          const double v = Decimal(letter);
          if (v < 0 || v > 99.9) Fail(source_, line_, letter_col, "TLD H horsepower outside 0-99.9");
          hp = v;
          break;
        }
        case 'C':
          check = true;
          break;
        case 'M':
          manual = true;
          manual_col = letter_col;
          break;
        case 'B':
          broken = true;
          break;
        case 'E':
          worn = true;
          break;
        default:
          Fail(source_, line_, letter_col,
               std::string("unknown TLD letter '") + body_[letter_col - col0_] + "'");
      }
      SkipBlanks();
    }
    if (tool.empty()) Fail(source_, line_, col0_, "TLD without a T tool number");
    // Range of compensations: +-999.999 mm / +-39.37 in for data sets, +-9.999 mm / +-.3937 in for process
    // compensations (seed lines 4039-4045, 4089-4091).
    TldStatement st;
    st.line = line_;
    if (pallet) {
      for (char c : seen) {
        if (c != 'T' && c != 'W' && c != 'P' && c != 'D') {
          Fail(source_, line_, tool_col,
               std::string("TLD process compensation allows only T, W, P and D, not ") + c);
        }
      }
      const double lim = metric_ ? 9.999 : 0.3937;
      CheckRange(length, lim, 'P');
      CheckRange(diameter, lim, 'D');
      st.process = ProcessComp{tool, *pallet, Mm(length.value_or(0)), Mm(diameter.value_or(0))};
    } else {
      const double lim = metric_ ? 999.999 : 39.37;
      CheckRange(length, lim, 'P');
      CheckRange(diameter, lim, 'D');
      if (socket && manual) Fail(source_, line_, manual_col, "TLD manual tool (M) cannot have a socket (S)");
      ToolEntry e;
      e.tool = tool;
      e.socket = socket.value_or(0);
      e.length = Mm(length.value_or(0));
      e.diameter = Mm(diameter.value_or(0));
      e.life_left_min = life.value_or(0);
      e.worn = worn;
      e.broken = broken;
      e.check = check;
      e.manual = manual;
      e.max_hp = hp.value_or(0);
      st.entry = e;
    }
    return st;
  }

 private:
  int Col() const { return col0_ + static_cast<int>(pos_); }
  void SkipBlanks() {
    while (pos_ < body_.size() && (body_[pos_] == ' ' || body_[pos_] == '\t')) ++pos_;
  }
  double Mm(double v) const { return metric_ ? v : v * kMmPerInch; }
  void CheckRange(const std::optional<double>& v, double lim, char letter) {
    if (v && std::fabs(*v) > lim + 1e-9) {
      Fail(source_, line_, col0_,
           std::string("TLD ") + letter + " value " + std::to_string(*v) + " outside +-" +
               std::to_string(lim));
    }
  }

  int Integer(char letter, int lo, int hi) {
    const int col = Col();
    std::size_t start = pos_;
    while (pos_ < body_.size() && IsDigit(body_[pos_])) ++pos_;
    if (pos_ == start) Fail(source_, line_, col, std::string("TLD ") + letter + " needs a whole number");
    if (pos_ - start > 6) Fail(source_, line_, col, std::string("TLD ") + letter + " value too long");
    const int v = std::stoi(std::string(body_.substr(start, pos_ - start)));
    if (v < lo || v > hi) {
      Fail(source_, line_, col,
           std::string("TLD ") + letter + " value " + std::to_string(v) + " outside " + std::to_string(lo) +
               "-" + std::to_string(hi));
    }
    return v;
  }

  double Decimal(char letter) {
    const int col = Col();
    std::size_t start = pos_;
    if (pos_ < body_.size() && (body_[pos_] == '+' || body_[pos_] == '-')) ++pos_;
    std::size_t digits = 0, dots = 0;
    while (pos_ < body_.size() && (IsDigit(body_[pos_]) || body_[pos_] == '.')) {
      if (body_[pos_] == '.')
        ++dots;
      else
        ++digits;
      ++pos_;
    }
    if (digits == 0 || dots > 1) Fail(source_, line_, col, std::string("TLD ") + letter + " needs a number");
    if (digits > 9) Fail(source_, line_, col, std::string("TLD ") + letter + " value too long");
    return std::stod(std::string(body_.substr(start, pos_ - start)));
  }

  std::string Tool() {
    const int col = Col();
    std::size_t start = pos_;
    while (pos_ < body_.size() && IsDigit(body_[pos_])) ++pos_;
    if (pos_ < body_.size() && body_[pos_] == '.' && pos_ + 1 < body_.size() && IsDigit(body_[pos_ + 1])) {
      pos_ += 2;
    }
    try {
      return NormalizeToolNumber(body_.substr(start, pos_ - start));
    } catch (const Error& e) {
      Fail(source_, line_, col, e.what());
    }
  }

  std::string_view body_;
  std::string_view source_;
  int line_;
  int col0_;
  bool metric_;
  int max_pallet_;
  std::size_t pos_ = 0;
};

bool StartsWithCi(std::string_view s, std::size_t pos, std::string_view what) {
  if (pos + what.size() > s.size()) return false;
  for (std::size_t i = 0; i < what.size(); ++i) {
    if (Upper(s[pos + i]) != what[i]) return false;
  }
  return true;
}

}  // namespace

std::string NormalizeToolNumber(std::string_view text) {
  std::string_view s = text;
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  if (!s.empty() && Upper(s.front()) == 'T') s.remove_prefix(1);
  std::string_view number = s, suffix;
  if (auto dot = s.find('.'); dot != std::string_view::npos) {
    number = s.substr(0, dot);
    suffix = s.substr(dot + 1);
  }
  const auto all_digits = [](std::string_view v) {
    return !v.empty() && std::all_of(v.begin(), v.end(), [](char c) { return IsDigit(c); });
  };
  if (!all_digits(number) || number.size() > 7) {
    throw Error(Errc::kInvalidArgument, "bad tool number '" + std::string(text) + "' (1-7 digits expected)");
  }
  if (s.find('.') != std::string_view::npos &&
      (suffix.size() != 1 || !all_digits(suffix) || suffix[0] < '0' || suffix[0] > '7')) {
    throw Error(Errc::kInvalidArgument, "bad tool suffix in '" + std::string(text) + "' (.1-.7 expected)");
  }
  while (number.size() > 1 && number.front() == '0') number.remove_prefix(1);
  std::string out(number);
  if (!suffix.empty() && suffix != "0") out += "." + std::string(suffix);
  return out;
}

std::string_view BaseTool(std::string_view tool) {
  return tool.substr(0, tool.find('.'));
}

std::vector<TldStatement> ParseTld(std::string_view text, std::string_view source,
                                   const ParseOptions& options) {
  std::vector<TldStatement> out;
  bool metric = options.metric;
  int line_no = 0;
  std::size_t line_start = 0;
  while (line_start <= text.size()) {
    std::size_t eol = text.find('\n', line_start);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view line = text.substr(line_start, eol - line_start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    ++line_no;
    bool in_paren = false;
    for (std::size_t i = 0; i < line.size(); ++i) {
      const char c = line[i];
      if (!in_paren && c == '!') break;  // KT-APL comment to end of line
      if ((c == '(' || c == '%') && StartsWithCi(line, i + 1, "TLD")) {
        const char close = c == '(' ? ')' : '%';
        std::size_t p = i + 4;
        while (p < line.size() && line[p] == ' ') ++p;
        if (p >= line.size() || line[p] != ',') {
          Fail(source, line_no, static_cast<int>(p + 1), "expected ',' after TLD");
        }
        const std::size_t end = line.find(close, p + 1);
        if (end == std::string_view::npos) {
          Fail(source, line_no, static_cast<int>(i + 1),
               std::string("TLD statement without closing '") + close + "'");
        }
        BodyParser parser(line.substr(p + 1, end - p - 1), source, line_no, static_cast<int>(p + 2), metric,
                          options.max_pallet);
        TldStatement st = parser.Parse();
        st.column = static_cast<int>(i + 1);
        out.push_back(std::move(st));
        i = end;
        continue;
      }
      if (c == '(') in_paren = true;
      if (c == ')') in_paren = false;
      if (!in_paren && Upper(c) == 'G' && i + 2 < line.size() && line[i + 1] == '7' &&
          (line[i + 2] == '0' || line[i + 2] == '1') && (i + 3 >= line.size() || !IsDigit(line[i + 3]))) {
        metric = line[i + 2] == '1';
      }
    }
    if (eol == text.size()) break;
    line_start = eol + 1;
  }
  return out;
}

ToolTable::ToolTable(std::vector<ToolEntry> entries, std::vector<ProcessComp> process)
    : entries_(std::move(entries)), process_(std::move(process)) {}

const ToolEntry* ToolTable::Find(std::string_view tool) const {
  for (const auto& e : entries_) {
    if (e.tool == tool) return &e;
  }
  return nullptr;
}

void ToolTable::Upsert(const ToolEntry& entry) {
  for (auto& e : entries_) {
    if (e.tool == entry.tool) {
      e = entry;
      return;
    }
  }
  entries_.push_back(entry);
}

std::size_t ToolTable::Merge(const std::vector<TldStatement>& statements, std::string_view source) {
  ToolTable next = *this;  // all or nothing
  for (const auto& st : statements) {
    if (st.entry) {
      next.Upsert(*st.entry);
    } else if (st.process) {
      const ProcessComp& pc = *st.process;
      if (next.Find(pc.tool) == nullptr) {
        throw Error(Errc::kFailedPrecondition, std::string(source) + ":" + std::to_string(st.line) + ":" +
                                                   std::to_string(st.column) +
                                                   ": error: process compensation for tool " + pc.tool +
                                                   " before its primary or suffix data set");
      }
      auto it = std::find_if(next.process_.begin(), next.process_.end(), [&](const ProcessComp& p) {
        return p.tool == pc.tool && p.pallet == pc.pallet;
      });
      if (it != next.process_.end())
        *it = pc;
      else
        next.process_.push_back(pc);
    }
  }
  *this = std::move(next);
  return statements.size();
}

bool ToolTable::Holds(std::string_view tool) const {
  const bool want_suffix = tool.find('.') != std::string_view::npos;
  for (const auto& e : entries_) {
    if (e.broken) continue;
    if (want_suffix ? e.tool == tool : BaseTool(e.tool) == tool) return true;
  }
  return false;
}

}  // namespace cell::tooltable
