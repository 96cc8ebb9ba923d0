#include "tld.h"

#include <fmt/format.h>

#include <cmath>

#include "cell/error/error.h"
#include "interp_internal.h"

namespace cell::interp::ktapl {
namespace {

class TldParser {
 public:
  TldParser(std::string_view body, const TldContext& ctx) : b_(body), ctx_(ctx) {}

  TldStatement Parse() {
    std::string tool;
    std::optional<int> socket, pallet, life;
    std::optional<double> length, diameter, hp;
    bool check = false, manual = false, broken = false, worn = false;
    std::string seen;
    int tool_col = 0, manual_col = 0;
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
          socket = Integer(letter, 1, 999);
          break;
        case 'T':
          tool_col = col;
          tool = Tool();
          break;
        case 'W':
          pallet = Integer(letter, 1, ctx_.max_pallet);
          break;
        case 'P':
          length = Offset(letter);
          break;
        case 'D':
          diameter = Offset(letter);
          break;
        case 'L': {
          // hhmm right-aligned (ln 4051-4055: "L2241 = 22 Hours and 41 Minutes").
          const int v = Integer(letter, 0, 9959);
          if (v % 100 > 59) Error(col, "TLD TOOL LIFE IS hhmm (MINUTES <= 59)");
          life = (v / 100) * 60 + v % 100;
          break;
        }
        case 'H': {
          const double v = Plain(letter);
          if (v < 0 || v > 99.9) Error(col, "TLD H HORSEPOWER OUTSIDE 0-99.9");
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
      const double lim = ctx_.metric ? 9.999 : 0.3937;
      Range(length, lim, 'P');
      Range(diameter, lim, 'D');
      st.process = tooltable::ProcessComp{tool, *pallet, length.value_or(0) * mm, diameter.value_or(0) * mm};
      return st;
    }
    // ln 4039-4045: +-999.999 mm / +-39.37 in.
    const double lim = ctx_.metric ? 999.999 : 39.37;
    Range(length, lim, 'P');
    Range(diameter, lim, 'D');
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
  void Range(const std::optional<double>& v, double lim, char letter) const {
    if (v && std::fabs(*v) > lim + 1e-9) {
      Error(ctx_.col0,
            fmt::format("TLD {} VALUE {} OUTSIDE +-{}", letter, FormatKtNumber(*v), FormatKtNumber(lim)));
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

}  // namespace cell::interp::ktapl
