// The MP3 data files as text (see tool_files.h).
#include "tool_files.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <optional>
#include <vector>

namespace cell::interp::balt {
namespace {

constexpr double kInch = 25.4;

bool Digit(char c) {
  return c >= '0' && c <= '9';
}
bool Alpha(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
}

// A scanner over record text: positions, '%' delimiters, ';' comments, separators.
class Scanner {
 public:
  explicit Scanner(std::string_view t) : t_(t) {}
  // Skips blanks, commas, '/', '%', comments and the "[TOOL COMP]" key; stops at anything else.
  void Skip() {
    while (i_ < t_.size()) {
      char c = t_[i_];
      if (c == '\n') {
        ++line_;
        line_start_ = ++i_;
      } else if (c == ' ' || c == '\t' || c == '\r' || c == ',' || c == '/' || c == '%') {
        ++i_;
      } else if (c == ';') {
        while (i_ < t_.size() && t_[i_] != '\n') ++i_;
      } else if (c == '[') {
        std::size_t e = t_.find(']', i_);
        if (e == std::string_view::npos) return;
        i_ = e + 1;
      } else {
        return;
      }
    }
  }
  bool End() const { return i_ >= t_.size(); }
  char Peek() const { return i_ < t_.size() ? t_[i_] : '\0'; }
  void Advance() { ++i_; }
  int Line() const { return line_; }
  int Col() const { return static_cast<int>(i_ - line_start_) + 1; }
  // A signed number; nullopt when there is none here.
  std::optional<double> Number() {
    std::size_t j = i_;
    bool neg = false;
    if (j < t_.size() && (t_[j] == '+' || t_[j] == '-')) neg = t_[j++] == '-';
    double v = 0;
    int digits = 0;
    while (j < t_.size() && Digit(t_[j])) {
      v = v * 10 + (t_[j++] - '0');
      ++digits;
    }
    if (j < t_.size() && t_[j] == '.') {
      ++j;
      double s = 0.1;
      while (j < t_.size() && Digit(t_[j])) {
        v += (t_[j++] - '0') * s;
        s /= 10;
        ++digits;
      }
    }
    if (digits == 0) return std::nullopt;
    i_ = j;
    return neg ? -v : v;
  }
  // Blanks within a record line (not newlines).
  void Blanks() {
    while (i_ < t_.size() && (t_[i_] == ' ' || t_[i_] == '\t' || t_[i_] == ',' || t_[i_] == '\r')) ++i_;
  }

 private:
  std::string_view t_;
  std::size_t i_ = 0;
  int line_ = 1;
  std::size_t line_start_ = 0;
};

[[noreturn]] void Bad(const Scanner& s, const std::string& why) {
  throw FileError{s.Line(), s.Col(), 71, why};
}

// A record: its number and its letter fields in order, as written.
struct Record {
  int n = 0;
  bool alt = false;  // negative number: values in the alternative unit
  int line = 1, col = 1;
  std::vector<std::pair<char, double>> fields;
};

std::vector<Record> ReadRecords(std::string_view text, int max_n) {
  Scanner s(text);
  std::vector<Record> out;
  for (s.Skip(); !s.End(); s.Skip()) {
    Record r;
    r.line = s.Line();
    r.col = s.Col();
    auto n = s.Number();
    if (!n) Bad(s, fmt::format("a record starts with its number, not '{}'", s.Peek()));
    if (*n != std::floor(*n) || std::fabs(*n) > max_n)
      Bad(s, fmt::format("record number {} out of range", *n));
    r.alt = *n < 0;
    r.n = static_cast<int>(std::fabs(*n));
    for (;;) {
      s.Blanks();
      if (s.End() || !Alpha(s.Peek())) break;
      char letter = s.Peek();
      s.Advance();
      s.Blanks();
      auto v = s.Number();
      if (!v) {
        // "K.." is a field left empty (a value of 0 as on the keyboard echo).
        if (s.Peek() == '.') {
          while (s.Peek() == '.') s.Advance();
        }
        v = 0;
      }
      r.fields.emplace_back(letter, *v);
    }
    out.push_back(std::move(r));
  }
  return out;
}

std::string Num3(double v) {
  return fmt::format("{:+.3f}", std::fabs(v) < 5e-4 ? 0.0 : v);
}

}  // namespace

tooltable::ToolTable ParseOffsets(std::string_view text, const tooltable::ToolTable& base,
                                  bool metric_machine) {
  tooltable::ToolTable table = base;  // all or nothing
  std::vector<Record> records = ReadRecords(text, 9999);
  if (records.empty()) throw FileError{1, 1, 71, "no offset record (\"n Z.. K..\") found"};
  for (const Record& r : records) {
    if (r.n == 0) throw FileError{r.line, r.col, 71, "offset numbers start at 1"};
    tooltable::ToolEntry e;
    e.tool = std::to_string(r.n);
    if (const auto* old = base.Find(e.tool)) e = *old;
    double unit = r.alt ? (metric_machine ? kInch : 1.0 / kInch) : 1.0;
    bool length = false, diameter = false;
    int wear = 0;
    for (auto [letter, v] : r.fields) {
      switch (letter) {
        case 'X':
        case 'Y':
        case 'Z':
          if (length) throw FileError{r.line, r.col, 71, fmt::format("offset {} has two length values", r.n)};
          length = true;
          e.length_axis = letter;
          e.length = v * unit;
          break;
        case 'K':
          if (diameter) throw FileError{r.line, r.col, 71, fmt::format("offset {} has two K values", r.n)};
          diameter = true;
          e.diameter = v * unit;
          break;
        case 'c':
        case 'm':
          if (++wear > 4)
            throw FileError{r.line, r.col, 71, fmt::format("offset {}: more than c.. m.. c.. m..", r.n)};
          break;
        default:
          throw FileError{
              r.line, r.col, 71,
              fmt::format("offset {}: '{}' is not an offset field (Z, X or Y length, K diameter, c, m)", r.n,
                          letter)};
      }
    }
    // ln 8284: the length and K must both be written, even when 0.
    if (!length || !diameter) {
      throw FileError{r.line, r.col, 71, fmt::format("offset {} needs a length (Z, X or Y) and K", r.n)};
    }
    table.Upsert(e);
  }
  return table;
}

std::string FormatOffsets(const tooltable::ToolTable& table) {
  std::string out = "%\n";
  for (const auto& e : table.entries()) {
    out += fmt::format("{} {}{} K{}\n", e.tool, e.length_axis, Num3(e.length), Num3(e.diameter));
  }
  out += "%\n";
  return out;
}

ToolLifeFile ParseToolLife(std::string_view text) {
  ToolLifeFile f;
  int line_no = 0;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t nl = text.find('\n', start);
    std::string_view line =
        text.substr(start, nl == std::string_view::npos ? text.size() - start : nl - start);
    start = nl == std::string_view::npos ? text.size() + 1 : nl + 1;
    ++line_no;
    // Fields: VTU, tool, T<alt>, [TOOL COMP]<offset>, t<max>, t<min>, t<left>, status.
    std::vector<std::pair<std::string, int>> fields;
    std::string cur;
    int cur_col = 1;
    bool comment = false;
    for (std::size_t i = 0; i <= line.size(); ++i) {
      char c = i < line.size() ? line[i] : ',';
      if (c == ';') comment = true;
      if (comment) c = ',';
      if (c == ',') {
        std::size_t b = cur.find_first_not_of(" \t\r");
        std::size_t e = cur.find_last_not_of(" \t\r");
        fields.emplace_back(b == std::string::npos ? "" : cur.substr(b, e - b + 1), cur_col);
        cur.clear();
        cur_col = static_cast<int>(i) + 2;
        if (comment) break;
        continue;
      }
      cur += c;
    }
    while (!fields.empty() && fields.back().first.empty()) fields.pop_back();
    if (fields.empty() || fields[0].first == "%" || fields[0].first.empty()) continue;
    auto bad = [&](std::size_t k, const std::string& why) -> void {
      int col = k < fields.size() ? fields[k].second : 1;
      throw FileError{line_no, col, 71, why};
    };
    if (fields[0].first != "VTU") bad(0, "a tool life record starts with VTU");
    if (fields.size() != 8)
      bad(0, "VTU,tool,T<alternative>,[TOOL COMP]<offset>,t<max>,t<min>,t<left>,<status>");
    auto number = [&](std::size_t k, std::string_view prefix) -> double {
      std::string s = fields[k].first;
      if (!prefix.empty()) {
        if (s.rfind(prefix, 0) != 0) bad(k, fmt::format("expected {}<number>", prefix));
        s = s.substr(prefix.size());
      }
      std::size_t key = s.find(']');
      if (key != std::string::npos) s = s.substr(key + 1);
      std::size_t b = s.find_first_not_of(' ');
      s = b == std::string::npos ? "" : s.substr(b);
      if (s.empty() || !std::all_of(s.begin(), s.end(), [](char c) { return Digit(c) || c == '.'; })) {
        bad(k, fmt::format("'{}' is not an unsigned number", fields[k].first));
      }
      return std::stod(s);
    };
    ToolLife t;
    t.tool = static_cast<int>(number(1, ""));
    t.alt_tool = static_cast<int>(number(2, "T"));
    t.alt_offset = static_cast<int>(number(3, ""));
    t.max_min = number(4, "t");
    t.min_min = number(5, "t");
    t.left_min = number(6, "t");
    const std::string& st = fields[7].first;
    if (st.size() != 1 || st[0] < 'A' || st[0] > 'F') bad(7, "status is one of A B C D E F");
    t.status = st[0];
    f.tools[t.tool] = t;
  }
  return f;
}

std::string ToolLifeFile::Format() const {
  std::string out;
  for (const auto& [n, t] : tools) {
    out += fmt::format("VTU,{},T{},[TOOL COMP]{},t{:g},t{:g},t{:g},{}\n", t.tool, t.alt_tool, t.alt_offset,
                       t.max_min, t.min_min, t.left_min, t.status);
  }
  return out;
}

OriginFile ParseOrigins(std::string_view text, bool metric_machine) {
  OriginFile f;
  for (const Record& r : ReadRecords(text, 99)) {
    OriginRecord o;
    double unit = r.alt ? (metric_machine ? kInch : 1.0 / kInch) : 1.0;
    for (auto [letter, v] : r.fields) {
      int axis = -1;
      switch (letter) {
        case 'X':
          axis = kX;
          break;
        case 'Y':
          axis = kY;
          break;
        case 'Z':
          axis = kZ;
          break;
        case 'A':
          axis = kA;
          break;
        case 'B':
          axis = kB;
          break;
        case 'C':
          axis = kC;
          break;
        case 'U':
          axis = kU;
          break;
        case 'V':
          axis = kV;
          break;
        case 'W':
          axis = kW;
          break;
        default:
          throw FileError{r.line, r.col, 71, fmt::format("origin {}: '{}' is not an axis", r.n, letter)};
      }
      if (o.axes & (1u << axis))
        throw FileError{r.line, r.col, 71, fmt::format("origin {}: axis {} twice", r.n, letter)};
      o.axes |= 1u << axis;
      o.v[axis] = (axis >= kA && axis <= kC) ? v : v * unit;
    }
    if (std::popcount(o.axes) > 3)
      throw FileError{r.line, r.col, 69, fmt::format("origin {} names more than 3 axes", r.n)};
    f[r.n] = o;
  }
  return f;
}

std::string FormatOrigins(const OriginFile& file) {
  std::string out = "%\n";
  for (const auto& [n, o] : file) {
    out += std::to_string(n);
    for (int a = 0; a < kAxisCount; ++a) {
      if (o.axes & (1u << a))
        out += fmt::format(" {}{}", static_cast<char>(AxisName(a)[0] - 'a' + 'A'), Num3(o.v[a]));
    }
    out += '\n';
  }
  out += "%\n";
  return out;
}

RandomToolFile ParseRandomTools(std::string_view text) {
  RandomToolFile f;
  int line_no = 0, pocket = 0, run_code = -1, run_length = 0, run_line = 0;
  // A special tool's run of records ends: it must be exactly 3 long (ln 8557).
  auto end_run = [&] {
    if (run_code >= 9000 && run_length != 3)
      throw FileError{run_line, 1, 71,
                      fmt::format("special tool {} occupies 3 pockets, not {}", run_code - 9000, run_length)};
  };
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t nl = text.find('\n', start);
    std::string_view line =
        text.substr(start, nl == std::string_view::npos ? text.size() - start : nl - start);
    start = nl == std::string_view::npos ? text.size() : nl + 1;
    ++line_no;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t'))
      line.remove_suffix(1);
    if (line.empty() || line == "%") continue;
    if (line.size() < 4 ||
        !std::all_of(line.begin(), line.begin() + 4, [](char c) { return c >= '0' && c <= '9'; }) ||
        (line.size() > 4 && (line[4] >= '0' && line[4] <= '9')))
      throw FileError{line_no, 1, 71, "a random tool record is 4 digits (ln 8527-8549)"};
    const int code = std::stoi(std::string(line.substr(0, 4)));
    ++pocket;
    if (code == run_code && code >= 9000 && run_length < 3) {
      ++run_length;
      continue;
    }
    end_run();
    run_code = code;
    run_length = 1;
    run_line = line_no;
    if (code == 0) continue;  // an empty pocket
    const int tool = code >= 9000 ? code - 9000 : code;
    if (tool == 0 || f.pocket.count(tool))
      throw FileError{
          line_no, 1, 71,
          fmt::format("tool {} is {} (pocket {})", tool, tool == 0 ? "not a tool" : "in two places", pocket)};
    f.pocket[tool] = pocket;
    f.special[tool] = code >= 9000;
  }
  end_run();
  return f;
}

}  // namespace cell::interp::balt
