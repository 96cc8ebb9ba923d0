// The EMCO tool data file (see tool_table.h).
#include "tool_table.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "cell/error/error.h"
#include "cell/interp/scan.h"

namespace cell::interp::emco {

namespace {

struct Cursor {
  std::string_view s;
  std::size_t i = 0;
  int Col() const { return static_cast<int>(i) + 1; }
  void Blanks() {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  }
};

// A number as on tape: sign, digits, optional point; `point` says whether it had one.
bool Number(Cursor& c, double& v, bool& point, int& digits) {
  std::size_t start = c.i;
  bool neg = false;
  if (c.i < c.s.size() && (c.s[c.i] == '+' || c.s[c.i] == '-')) neg = c.s[c.i++] == '-';
  double whole = 0;
  int frac = 0;
  point = false;
  digits = 0;
  while (c.i < c.s.size()) {
    char ch = c.s[c.i];
    if (scan::IsDigit(ch)) {
      whole = whole * 10 + (ch - '0');
      ++digits;
      if (point) ++frac;
    } else if (ch == '.' && !point) {
      point = true;
    } else {
      break;
    }
    ++c.i;
  }
  if (digits == 0) {
    c.i = start;
    return false;
  }
  v = (neg ? -whole : whole) / std::pow(10.0, frac);
  return true;
}

}  // namespace

tooltable::ToolTable ParseToolData(std::string_view text, std::string_view source,
                                   const tooltable::ToolTable& base) {
  tooltable::ToolTable table = base;  // all or nothing
  int line_no = 0, found = 0;
  auto fail = [&](int col, const std::string& what) {
    throw Error(Errc::kInvalidArgument, fmt::format("{}:{}:{}: error: {}", source, line_no, col, what));
  };
  for (std::string_view raw : scan::Lines(text)) {
    ++line_no;
    std::string line(raw);
    bool comment = false;  // comments in round brackets become blanks (columns stay where they were)
    for (char& ch : line) {
      if (ch == '(') comment = true;
      if (!comment) continue;
      if (ch == ')') comment = false;
      ch = ' ';
    }
    Cursor c{line};
    c.Blanks();
    if (c.i >= line.size() || line[c.i] == '%') continue;
    // The correction: "07", "7", or "T0307".
    int col = c.Col();
    int socket = -1, corr = 0;
    bool t_word = line[c.i] == 'T' || line[c.i] == 't';
    if (t_word) ++c.i;
    std::size_t d0 = c.i;
    while (c.i < line.size() && scan::IsDigit(line[c.i])) ++c.i;
    std::string digits = line.substr(d0, c.i - d0);
    if (digits.empty())
      fail(col, "a line of tool data starts with its correction number (01-99) or T<turret><correction>");
    if (t_word && digits.size() == 4) {
      socket = std::stoi(digits.substr(0, 2));
      corr = std::stoi(digits.substr(2));
      if (socket == 0)
        fail(col, fmt::format("[430] INVALID T-WORD (T{}: a correction needs its tool number)", digits));
    } else if (digits.size() <= 2) {
      corr = std::stoi(digits);
    } else {
      fail(col, fmt::format("[690] INVALID INDEX ENTERED (correction {}: 01-99)", digits));
    }
    if (corr < 1 || corr > 99)
      fail(col, fmt::format("[690] INVALID INDEX ENTERED (correction {}: 01-99)", corr));
    std::string name = std::to_string(corr);
    tooltable::ToolEntry e;
    if (const tooltable::ToolEntry* old = table.Find(name)) e = *old;
    e.tool = name;
    if (socket >= 0) e.socket = socket;
    bool any = false;
    for (;;) {
      c.Blanks();
      if (c.i >= line.size()) break;
      int wcol = c.Col();
      char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(line[c.i])));
      if (letter != 'X' && letter != 'Z' && letter != 'R' && letter != 'L') {
        fail(wcol, fmt::format("unexpected '{}' (tool data are X, Z, R and L)", line[c.i]));
      }
      ++c.i;
      c.Blanks();
      if (c.i < line.size() && line[c.i] == '=') {
        ++c.i;
        c.Blanks();
      }
      double v = 0;
      bool point = false;
      int nd = 0;
      if (!Number(c, v, point, nd)) fail(wcol, fmt::format("{} without a value", letter));
      if (letter == 'L') {
        if (point || v < 0 || v > 9) fail(wcol, "L is the tip position code 0-9");
        e.tip = static_cast<int>(v);
      } else {
        double mm = point ? v : v / 1000.0;  // um without a decimal point, as on tape
        if (std::fabs(mm) > 9999.999)
          fail(wcol, fmt::format("[620] INPUT VALUE OUT OF NUMERICAL RANGE ({})", letter));
        if (letter == 'X') e.x_offset = 2 * mm;  // X is a radius; the cell's model keeps the diameter
        if (letter == 'Z') e.z_offset = mm;
        if (letter == 'R') {
          if (mm < 0) fail(wcol, "R (nose radius) may not be negative");
          e.nose_radius = mm;
        }
      }
      any = true;
    }
    if (!any) fail(col, fmt::format("correction {} has no X, Z, R or L", corr));
    table.Upsert(e);
    ++found;
  }
  if (found == 0) {
    throw Error(
        Errc::kInvalidArgument,
        fmt::format("{}: no tool data found (an EMCO tool table is lines of <correction> X.. Z.. R.. L..)",
                    source));
  }
  return table;
}

std::string FormatToolData(const tooltable::ToolTable& table) {
  std::map<int, const tooltable::ToolEntry*> by_corr;
  for (const auto& e : table.entries()) {
    if (e.tool.empty() || e.tool.size() > 2 || !scan::AllDigits(e.tool)) continue;
    int corr = std::stoi(e.tool);
    if (corr >= 1 && corr <= 99) by_corr[corr] = &e;
  }
  std::string out;
  for (const auto& [corr, e] : by_corr) {
    std::string head = e->socket > 0 && e->socket <= 99 ? fmt::format("T{:02d}{:02d}", e->socket, corr)
                                                        : fmt::format("{:02d}", corr);
    out += fmt::format("{} X{:.3f} Z{:.3f} R{:.3f} L{}\n", head, e->x_offset / 2, e->z_offset, e->nose_radius,
                       e->tip);
  }
  return out;
}

}  // namespace cell::interp::emco
