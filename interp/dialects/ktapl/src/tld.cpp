#include "tld.h"

#include <fmt/format.h>

#include <cmath>

#include "cell/error/error.h"
#include "interp_internal.h"

namespace cell::interp::ktapl {
namespace {

// The manual's ranges for tool data (ln 3975-4097), for the TLD parser (in the unit a statement is read in)
// and for CheckToolEntry (millimetres). Sign is never an error: "Plus (+) is assumed unless a minus (-) is
// entered" (ln 4039, 4045), and the manual's own example writes D-.25 (ln 4063).
struct CompLimit {
  double mm, inch;
  std::string_view lines;
};
constexpr CompLimit kDataSetComp{999.999, 39.37, "ln 4041-4049"};  // P, D of a primary or suffix set
constexpr CompLimit kProcessComp{9.999, 0.3937, "ln 4091"};        // P, D with W (the NOTE, ln 4019: .3936)
constexpr int kMaxSocket = 999;                                    // S
constexpr int kMaxLifeHhmm = 9959;                                 // L, hhmm (ln 4051-4055)
constexpr double kMaxHp = 99.9;                                    // H (ln 4059)

// Values are shown as written (10 significant digits drop the binary noise of a converted inch value:
// 39.371 stays 39.371).
std::string RangeText(char letter, double v, const CompLimit& lim, bool metric, std::string_view unit) {
  return fmt::format("TLD {} VALUE {:.10g}{} OUTSIDE +-{}{} (manual {})", letter, v, unit,
                     metric ? lim.mm : lim.inch, unit, lim.lines);
}

class TldParser {
 public:
  TldParser(std::string_view body, const TldContext& ctx) : b_(body), ctx_(ctx) {}

  TldStatement Parse() {
    std::string tool;
    std::optional<int> socket, pallet, life;
    std::optional<double> length, diameter, hp;
    bool check = false, manual = false, broken = false, worn = false;
    std::string seen;
    int tool_col = 0, manual_col = 0, length_col = 0, diameter_col = 0;
    Blanks();
    if (i_ >= b_.size()) Error(Col(), "TLD NEEDS A T TOOL NUMBER");
    while (i_ < b_.size()) {
      const int col = Col();
      const char letter = Up(b_[i_]);
      if (seen.find(letter) != std::string::npos)
        Error(col, fmt::format("TLD LETTER {} GIVEN TWICE", letter));
      seen.push_back(letter);
      ++i_;
      Blanks();
      switch (letter) {
        case 'S':
          socket = Integer(letter, 1, kMaxSocket);
          break;
        case 'T':
          tool_col = col;
          tool = Tool();
          break;
        case 'W':
          pallet = Integer(letter, 1, ctx_.max_pallet);
          break;
        case 'P':
          length_col = col;
          length = Offset(letter);
          break;
        case 'D':
          diameter_col = col;
          diameter = Offset(letter);
          break;
        case 'L': {
          // hhmm right-aligned (ln 4051-4055: "L2241 = 22 Hours and 41 Minutes").
          const int v = Integer(letter, 0, kMaxLifeHhmm);
          if (v % 100 > 59) Error(col, "TLD TOOL LIFE IS hhmm (MINUTES <= 59)");
          life = (v / 100) * 60 + v % 100;
          break;
        }
        case 'H': {
          const double v = Plain(letter);
          if (v < 0 || v > kMaxHp) Error(col, "TLD H HORSEPOWER OUTSIDE 0-99.9");
          hp = v;
          break;
        }
        case 'C':
          check = true;
          break;
        case 'M':
          manual = true;
          manual_col = col;
          break;
        case 'B':
          broken = true;
          break;
        case 'E':
          worn = true;
          break;
        default:
          Error(col,
                fmt::format("Input Source Error (TLD letter {})", b_[static_cast<size_t>(col - ctx_.col0)]));
      }
      Blanks();
    }
    if (tool.empty()) Error(ctx_.col0, "TLD NEEDS A T TOOL NUMBER");
    TldStatement st;
    const double mm = ctx_.metric ? 1.0 : kInch;
    if (pallet) {
      // ln 4085-4089: only T, W, P and D in a process compensation; +-9.999 mm / +-.3937 in (ln 4091).
      for (char c : seen) {
        if (c != 'T' && c != 'W' && c != 'P' && c != 'D') {
          Error(tool_col, fmt::format("TLD PROCESS COMPENSATION ALLOWS ONLY T, W, P AND D, NOT {}", c));
        }
      }
      Range(length, kProcessComp, 'P', length_col);
      Range(diameter, kProcessComp, 'D', diameter_col);
      st.process = tooltable::ProcessComp{tool, *pallet, length.value_or(0) * mm, diameter.value_or(0) * mm};
      return st;
    }
    Range(length, kDataSetComp, 'P', length_col);
    Range(diameter, kDataSetComp, 'D', diameter_col);
    if (socket && manual) Error(manual_col, "TLD MANUAL TOOL (M) CANNOT HAVE A SOCKET (S)");
    tooltable::ToolEntry e;
    e.tool = tool;
    e.socket = socket.value_or(0);
    e.length = length.value_or(0) * mm;
    e.diameter = diameter.value_or(0) * mm;
    e.life_left_min = life.value_or(0);
    e.worn = worn;
    e.broken = broken;
    e.check = check;
    e.manual = manual;
    e.max_hp = hp.value_or(0);
    st.entry = e;
    return st;
  }

 private:
  [[noreturn]] static void Error(int col, std::string text) { throw TldError{col, std::move(text)}; }
  int Col() const { return ctx_.col0 + static_cast<int>(i_); }
  void Blanks() {
    while (i_ < b_.size() && (b_[i_] == ' ' || b_[i_] == '\t')) ++i_;
  }
  void Range(const std::optional<double>& v, const CompLimit& lim, char letter, int col) const {
    if (v && std::fabs(*v) > (ctx_.metric ? lim.mm : lim.inch) + 1e-9) {
      Error(col, RangeText(letter, *v, lim, ctx_.metric, ""));
    }
  }
  // Ln (parameter substitution) at the current position: its value, or nullopt.
  std::optional<double> Parameter(char letter, bool neg) {
    if (i_ >= b_.size() || Up(b_[i_]) != 'L' || i_ + 1 >= b_.size() || !IsDigit(b_[i_ + 1]))
      return std::nullopt;
    const int col = Col();
    if (!ctx_.param) Error(col, fmt::format("TLD {}: PARAMETERS ARE ONLY ALLOWED IN A PROGRAM", letter));
    size_t j = i_ + 1;
    long n = 0;
    while (j < b_.size() && IsDigit(b_[j])) {
      n = n * 10 + (b_[j] - '0');
      if (n > 3999) Error(col, "Error L numbers range from 0..3999");
      ++j;
    }
    i_ = j;
    double v = ctx_.param(static_cast<int>(n), col);
    return neg ? -v : v;
  }
  int Integer(char letter, int lo, int hi) {
    const int col = Col();
    size_t start = i_;
    while (i_ < b_.size() && IsDigit(b_[i_])) ++i_;
    if (i_ == start) Error(col, fmt::format("TLD {} NEEDS A WHOLE NUMBER", letter));
    if (i_ - start > 6) Error(col, fmt::format("TLD {} VALUE TOO LONG", letter));
    const int v = std::stoi(std::string(b_.substr(start, i_ - start)));
    if (v < lo || v > hi) Error(col, fmt::format("TLD {} VALUE {} OUTSIDE {}-{}", letter, v, lo, hi));
    return v;
  }
  // A number with the implied decimals of an axis word when written without a point (a P or D).
  double Offset(char letter) {
    const int col = Col();
    bool neg = false;
    if (i_ < b_.size() && (b_[i_] == '+' || b_[i_] == '-')) neg = b_[i_++] == '-';
    if (auto p = Parameter(letter, neg)) return *p;
    RawNum r = Digits(letter, col);
    r.neg = neg;
    return ScaleLiteral('X', r, ctx_.metric, false, false);
  }
  double Plain(char letter) {
    const int col = Col();
    RawNum r = Digits(letter, col);
    return r.as_written;
  }
  RawNum Digits(char letter, int col) {
    RawNum r;
    double v = 0;
    int digits = 0;
    while (i_ < b_.size() && IsDigit(b_[i_])) {
      v = v * 10 + (b_[i_++] - '0');
      ++digits;
    }
    if (i_ < b_.size() && b_[i_] == '.') {
      r.point = true;
      ++i_;
      double sc = 0.1;
      while (i_ < b_.size() && IsDigit(b_[i_])) {
        v += (b_[i_++] - '0') * sc;
        sc /= 10;
        ++digits;
      }
    }
    if (digits == 0) Error(col, fmt::format("TLD {} NEEDS A NUMBER", letter));
    if (digits > 9) Error(col, fmt::format("TLD {} VALUE TOO LONG", letter));
    r.as_written = v;
    r.digits = digits;
    return r;
  }
  std::string Tool() {
    const int col = Col();
    if (auto p = Parameter('T', false)) return ToolName(*p);
    size_t start = i_;
    while (i_ < b_.size() && IsDigit(b_[i_])) ++i_;
    if (i_ < b_.size() && b_[i_] == '.' && i_ + 1 < b_.size() && IsDigit(b_[i_ + 1])) i_ += 2;
    try {
      return tooltable::NormalizeToolNumber(b_.substr(start, i_ - start));
    } catch (const cell::Error& e) {
      Error(col, e.what());
    }
  }

  std::string_view b_;
  const TldContext& ctx_;
  size_t i_ = 0;
};

}  // namespace

TldStatement ParseTld(std::string_view body, const TldContext& ctx) {
  return TldParser(body, ctx).Parse();
}

std::string CheckToolEntry(const tooltable::ToolEntry& e) {
  try {
    if (tooltable::NormalizeToolNumber(e.tool) != e.tool) return fmt::format("bad tool number '{}'", e.tool);
  } catch (const cell::Error& err) {
    return err.what();
  }
  if (e.socket < 0 || e.socket > kMaxSocket)
    return fmt::format("TLD S VALUE {} OUTSIDE 1-{}", e.socket, kMaxSocket);
  if (e.manual && e.socket != 0) return "TLD MANUAL TOOL (M) CANNOT HAVE A SOCKET (S)";
  for (auto [letter, v] : {std::pair{'P', e.length}, std::pair{'D', e.diameter}}) {
    if (!std::isfinite(v) || std::fabs(v) > kDataSetComp.mm + 1e-9)
      return RangeText(letter, v, kDataSetComp, true, " MM");
  }
  // L hhmm: at most 99 hours 59 minutes of tool life.
  const double max_life_min = (kMaxLifeHhmm / 100) * 60 + kMaxLifeHhmm % 100;
  if (!std::isfinite(e.life_left_min) || e.life_left_min < 0 || e.life_left_min > max_life_min) {
    return fmt::format("TLD L TOOL LIFE {} MIN OUTSIDE 0-{} MIN (L{}: 99 HOURS 59 MINUTES, manual ln 4051)",
                       e.life_left_min, max_life_min, kMaxLifeHhmm);
  }
  if (!std::isfinite(e.max_hp) || e.max_hp < 0 || e.max_hp > kMaxHp) return "TLD H HORSEPOWER OUTSIDE 0-99.9";
  // A KT-APL data set has P and D only: a lathe's offsets have no TLD letter.
  if (e.x_offset != 0 || e.z_offset != 0 || e.nose_radius != 0 || e.tip != 0) {
    return "a KT-APL tool has no lathe offsets (x_offset, z_offset, nose_radius, tip): TLD loads P and D";
  }
  return "";
}

}  // namespace cell::interp::ktapl
