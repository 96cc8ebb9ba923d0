// E parameters and their five formats (Table 5.8, ln 5409-5423; conversion on assignment ln 5470),
// expressions with degree trigonometry and the GTL accessors FEL/FEP/FEC (ln 5437-5472), indirect E(En)
// (K14, ln 5429), the global system variables (Table 4.3, §5.14) and the SA / SK / SYVAR byte areas with
// their access formats (ln 4171-4243).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "interp_internal.h"

namespace cell::interp::balt {

// The expression grammar: sums of products of factors; a factor is a number, an E parameter, E(En), a
// global variable, a function call, a bracketed expression, or a signed factor.
class ExprParser {
 public:
  ExprParser(BaltRun& run, std::string_view s, int col0) : run_(run), s_(s), col0_(col0) {}

  double Parse() {
    Skip();
    if (End()) Fail(Col(), 12, "operand missing");
    double v = Sum();
    Skip();
    if (!End()) {
      if (Peek() == ')') Fail(Col(), 11, "redundant closing bracket");
      Fail(Col(), 11, fmt::format("unexpected '{}' in the expression", Peek()));
    }
    return v;
  }

 private:
  bool End() const { return i_ >= s_.size(); }
  char Peek() const { return i_ < s_.size() ? s_[i_] : '\0'; }
  int Col() const { return col0_ + static_cast<int>(i_); }
  void Skip() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\t')) ++i_;
  }

  double Sum() {
    double v = Product();
    for (;;) {
      Skip();
      char c = Peek();
      if (c != '+' && c != '-') return v;
      ++i_;
      double w = Product();
      v = c == '+' ? v + w : v - w;
    }
  }

  double Product() {
    double v = Factor();
    for (;;) {
      Skip();
      char c = Peek();
      if (c != '*' && c != '/') return v;
      int col = Col();
      ++i_;
      double w = Factor();
      if (c == '*') {
        v *= w;
      } else {
        if (w == 0) Fail(col, 19, "division by zero");
        v /= w;
      }
    }
  }

  double Factor() {
    Skip();
    int col = Col();
    char c = Peek();
    if (End() || c == ')' || c == ',') Fail(col, 12, "operand missing");
    if (c == '+' || c == '-') {
      ++i_;
      double v = Factor();
      return c == '-' ? -v : v;
    }
    if (c == '(') {
      ++i_;
      double v = Sum();
      Skip();
      if (Peek() != ')') Fail(Col(), 11, "closing bracket missing");
      ++i_;
      return v;
    }
    if (IsDigit(c) || c == '.') return Number();
    if (c == '"') Fail(col, 24, "a string is not a number");
    if (!IsUpper(c)) Fail(col, 11, fmt::format("unexpected '{}' in the expression", c));
    std::size_t n0 = i_;
    while (IsUpper(Peek())) ++i_;
    std::string_view name = s_.substr(n0, i_ - n0);
    if (name == "E" && (IsDigit(Peek()) || Peek() == '(')) {
      if (Peek() == '(') {
        ++i_;
        Skip();
        // E(n) with a number n is En (ln 5435).
        const bool number = IsDigit(Peek());
        if (!number && Peek() != 'E') Fail(Col(), 11, "E(n) needs a number or an E parameter");
        if (!number) ++i_;
        int idx = Index(col);
        Skip();
        if (Peek() != ')') Fail(Col(), 11, "closing bracket missing");
        ++i_;
        if (number) return run_.Param(idx, col);
        Val v;
        v.kind = Val::kIndirect;
        v.param = idx;
        return run_.ValueOf(v, col);
      }
      return run_.Param(Index(col), col);
    }
    Skip();
    if (Peek() == '(') return Function(name, col);
    bool has_index = false;
    int index = 0;
    if (IsDigit(Peek())) {
      has_index = true;
      index = Index(col);
    }
    std::string_view fmt_text;
    if (Peek() == '.' && i_ + 1 < s_.size() && (IsUpper(s_[i_ + 1]) || IsDigit(s_[i_ + 1]))) {
      ++i_;
      std::size_t f0 = i_;
      while (IsUpper(Peek()) || IsDigit(Peek())) ++i_;
      fmt_text = s_.substr(f0, i_ - f0);
    }
    return run_.Global(name, has_index, index, fmt_text, col);
  }

  int Index(int col) {
    if (!IsDigit(Peek())) Fail(col, 11, "index expected");
    long n = 0;
    while (IsDigit(Peek())) {
      n = n * 10 + (Peek() - '0');
      if (n > 99999) Fail(col, 18, "index too large");
      ++i_;
    }
    return static_cast<int>(n);
  }

  double Number() {
    double v = 0;
    int digits = 0;
    while (IsDigit(Peek())) {
      v = v * 10 + (Peek() - '0');
      ++i_;
      ++digits;
    }
    if (Peek() == '.') {
      ++i_;
      double s = 0.1;
      while (IsDigit(Peek())) {
        v += (Peek() - '0') * s;
        s /= 10;
        ++i_;
        ++digits;
      }
    }
    if (digits == 0) Fail(Col(), 13, "number expected");
    return v;
  }

  double Function(std::string_view name, int col) {
    ++i_;  // '('
    double args[2] = {0, 0};
    int n = 0;
    for (;;) {
      Skip();
      if (n == 2) Fail(Col(), 23, fmt::format("{} has at most 2 operands", name));
      args[n++] = Sum();
      Skip();
      if (Peek() == ',') {
        ++i_;
        continue;
      }
      if (Peek() != ')') Fail(Col(), 11, "closing bracket missing");
      ++i_;
      break;
    }
    auto want = [&](int k) {
      if (n != k) Fail(col, 23, fmt::format("{} takes {} operand{}", name, k, k == 1 ? "" : "s"));
    };
    constexpr double kRad = kPi / 180.0;
    double a = args[0], b = args[1];
    auto domain = [&](bool ok) {
      if (!ok) Fail(col, 63, fmt::format("{}({}) is not defined", name, a));
    };
    if (name == "SIN") return want(1), std::sin(a * kRad);
    if (name == "COS") return want(1), std::cos(a * kRad);
    if (name == "TAN") {
      want(1);
      domain(std::fabs(std::cos(a * kRad)) > 1e-12);
      return std::tan(a * kRad);
    }
    if (name == "ARS") return want(1), domain(a >= -1 && a <= 1), std::asin(a) / kRad;
    if (name == "ARC") return want(1), domain(a >= -1 && a <= 1), std::acos(a) / kRad;
    if (name == "ART") return want(1), std::atan(a) / kRad;
    if (name == "SQR") return want(1), domain(a >= 0), std::sqrt(a);
    if (name == "ABS") return want(1), std::fabs(a);
    if (name == "INT") return want(1), std::trunc(a);
    if (name == "NEG") return want(1), -a;
    if (name == "LOG") return want(1), domain(a > 0), std::log10(a);
    if (name == "MOD") {
      want(2);
      if (b == 0) Fail(col, 19, "division by zero");
      return std::fmod(a, b);
    }
    if (name == "FEL" || name == "FEP" || name == "FEC") {
      want(2);
      char kind = name == "FEL" ? 'l' : (name == "FEP" ? 'p' : 'c');
      int idx = static_cast<int>(std::lround(a)), what = static_cast<int>(std::lround(b));
      const gtl::Element* e = run_.Geometry().Get(kind, idx);
      if (!e) Fail(col, 15, fmt::format("{}{} is not defined", kind, idx));
      double unit = run_.UnitFactorPublic();
      switch (kind) {
        case 'l':  // 1 sine, 2 cosine of its angle, 3 its distance from the origin
          if (what == 1) return e->d.y;
          if (what == 2) return e->d.x;
          if (what == 3) return std::fabs(Cross(e->d, e->p)) / unit;
          break;
        case 'p':
          if (what == 1) return e->p.x / unit;
          if (what == 2) return e->p.y / unit;
          break;
        default:
          if (what == 1) return e->p.x / unit;
          if (what == 2) return e->p.y / unit;
          if (what == 3) return std::fabs(e->r) / unit;
          break;
      }
      Fail(col, 24, fmt::format("{}: no value number {}", name, what));
    }
    Fail(col, 17, fmt::format("{} is not a function", name));
  }

  BaltRun& run_;
  std::string_view s_;
  int col0_;
  std::size_t i_ = 0;
};

double BaltRun::Eval(std::string_view text, int col) {
  double v = ExprParser(*this, text, col).Parse();
  if (!std::isfinite(v)) Fail(col, 63, "the result is not a number");
  return v;
}

double BaltRun::ValueOfVariable(const Val& v, int col) {
  double r = 0;
  switch (v.kind) {
    case Val::kNone:
      return 0;
    case Val::kNum:
      r = v.num;
      break;
    case Val::kParam:
      r = Param(v.param, col);
      break;
    case Val::kIndirect: {
      // K14 (ln 5429-5435): the index is held by a byte or integer parameter.
      if (v.param > 19) Fail(col, 13, fmt::format("E(E{}): the index parameter must be E0-E19", v.param));
      double idx = Param(v.param, col);
      r = Param(static_cast<int>(std::lround(idx)), col);
      break;
    }
  }
  return v.neg ? -r : r;
}

double BaltRun::Param(int n, int col) {
  if (n < 0 || n > max_e_) Fail(col, 18, fmt::format("E{} (E parameters are E0-E{})", n, max_e_));
  return e_[static_cast<std::size_t>(n)];
}

// The result is converted to the parameter's format (ln 5470): whole formats round to the nearest whole
// number (a judgement call: docs/dialects/balt.md), RE keeps single precision.
void BaltRun::SetParam(int n, double v, int col) {
  if (n < 0 || n > max_e_) Fail(col, 18, fmt::format("E{} (E parameters are E0-E{})", n, max_e_));
  if (!std::isfinite(v)) Fail(col, 63, "the result is not a number");
  auto whole = [&](double lo, double hi, const char* what) {
    double r = std::round(v);
    if (r < lo || r > hi) Fail(col, 13, fmt::format("E{} is {} ({:g} to {:g}): {:g}", n, what, lo, hi, v));
    return r;
  };
  if (n <= 9) {
    v = whole(0, 255, "a byte");
  } else if (n <= 19) {
    v = whole(-32768, 32767, "an integer");
  } else if (n <= 24) {
    v = whole(-2147483647.0, 2147483647.0, "a long integer");
  } else if (n <= 29) {
    if (std::fabs(v) > 3.4e38) Fail(col, 13, fmt::format("E{} is a real: {:g}", n, v));
    v = static_cast<double>(static_cast<float>(v));
  }
  e_[static_cast<std::size_t>(n)] = v;
  e_set_[static_cast<std::size_t>(n)] = true;
}

std::map<std::string, double> BaltRun::Variables() const {
  std::map<std::string, double> out;
  for (std::size_t i = 0; i < e_.size(); ++i) {
    if (e_set_[i]) out["E" + std::to_string(i)] = e_[i];
  }
  return out;
}

namespace {

struct Access {
  char kind = 'B';  // 'L' bit, 'B' byte, 'I' integer, 'J' long, 'R' real, 'D' long real, 'C' characters
  int chars = 1;
  std::size_t size = 1;
};

Access ParseFormat(std::string_view name, std::string_view f, int col) {
  Access a;
  if (f.empty()) {
    a.kind = name == "SA" ? 'L' : 'B';  // SA12=SK: a bit of the A buffer; SK5, SYVAR1: a byte (ln 4132-4152)
    return a;
  }
  std::size_t k = 0;
  int n = 0;
  // Saturates: any count past 32 is refused below, and a long run of digits must not overflow (fuzz).
  while (k < f.size() && IsDigit(f[k])) n = std::min(n * 10 + (f[k++] - '0'), 1000);
  std::string_view t = f.substr(k);
  if (t == "CH") {
    a.kind = 'C';
    a.chars = k == 0 ? 1 : n;
    if (a.chars < 1 || a.chars > 32) Fail(col, 13, "1 to 32 characters");
    a.size = static_cast<std::size_t>(a.chars);
    return a;
  }
  if (k != 0) Fail(col, 13, fmt::format("'.{}': a count goes only before CH", f));
  if (t == "BL")
    a = {'L', 1, 1};
  else if (t == "BY")
    a = {'B', 1, 1};
  else if (t == "IN")
    a = {'I', 1, 2};
  else if (t == "LI")
    a = {'J', 1, 4};
  else if (t == "RE")
    a = {'R', 1, 4};
  else if (t == "LR")
    a = {'D', 1, 8};
  else
    Fail(col, 13, fmt::format("'.{}' is not a format (BL BY IN LI RE LR CH)", f));
  return a;
}

}  // namespace

double BaltRun::UnitFactorPublic() const {
  return UnitFactor();
}

std::vector<unsigned char>& BaltRun::Buffer(std::string_view name, int col) {
  if ((name == "SA" || name == "SK") && !interface_logic_) {
    Fail(col, 103,
         fmt::format("{}: the machine has no interface logic for the A and K buffers (INTERFACE_LOGIC=0)",
                     name));
  }
  if (name == "SA") return sa_;
  if (name == "SK") return sk_;
  if (name == "SYVAR") return syvar_;
  Fail(col, 15, fmt::format("{} is not a variable", name));
}

double BaltRun::ReadBuffer(std::string_view name, int index, std::string_view f, int col) {
  std::vector<unsigned char>& buf = Buffer(name, col);
  Access a = ParseFormat(name, f, col);
  if (a.kind == 'C') Fail(col, 24, "a character variable is compared with a string");
  if (name == "SA") {
    // The A buffer holds the machine's signals: the station answers for them (offline: the buffer).
    if (auto v = env_->SystemVariable(fmt::format("SA{}{}{}", index, f.empty() ? "" : ".", f))) return *v;
  }
  std::size_t byte =
      a.kind == 'L' ? static_cast<std::size_t>(index) / 8 : static_cast<std::size_t>(index) * a.size;
  if (index < 0 || byte + a.size > buf.size())
    Fail(col, 18, fmt::format("{}{} is outside the area", name, index));
  const unsigned char* p = buf.data() + byte;
  switch (a.kind) {
    case 'L':
      return (*p >> (index % 8)) & 1;
    case 'B':
      return *p;
    case 'I': {
      std::int16_t v;
      std::memcpy(&v, p, 2);
      return v;
    }
    case 'J': {
      std::int32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
    case 'R': {
      float v;
      std::memcpy(&v, p, 4);
      return v;
    }
    default: {
      double v;
      std::memcpy(&v, p, 8);
      return v;
    }
  }
}

void BaltRun::WriteBuffer(std::string_view name, int index, std::string_view f, double v, int col) {
  std::vector<unsigned char>& buf = Buffer(name, col);
  Access a = ParseFormat(name, f, col);
  if (a.kind == 'C') Fail(col, 24, "a character variable takes a string");
  std::size_t byte =
      a.kind == 'L' ? static_cast<std::size_t>(index) / 8 : static_cast<std::size_t>(index) * a.size;
  if (index < 0 || byte + a.size > buf.size())
    Fail(col, 18, fmt::format("{}{} is outside the area", name, index));
  unsigned char* p = buf.data() + byte;
  auto whole = [&](double lo, double hi) {
    double r = std::round(v);
    if (r < lo || r > hi) Fail(col, 13, fmt::format("{} does not fit the format", v));
    return r;
  };
  switch (a.kind) {
    case 'L':
      if (v != 0 && v != 1) Fail(col, 13, "a bit is 0 or 1");
      *p = static_cast<unsigned char>(v != 0 ? (*p | (1u << (index % 8))) : (*p & ~(1u << (index % 8))));
      break;
    case 'B':
      *p = static_cast<unsigned char>(whole(0, 255));
      break;
    case 'I': {
      auto x = static_cast<std::int16_t>(whole(-32768, 32767));
      std::memcpy(p, &x, 2);
      break;
    }
    case 'J': {
      auto x = static_cast<std::int32_t>(whole(-2147483647.0, 2147483647.0));
      std::memcpy(p, &x, 4);
      break;
    }
    case 'R': {
      auto x = static_cast<float>(v);
      std::memcpy(p, &x, 4);
      break;
    }
    default:
      std::memcpy(p, &v, 8);
      break;
  }
  CheckAbtvu(name, col);
  if (name != "SYVAR") {
    // The A and K buffers are the machine logic's: the write goes out as an output.
    Out<OutputOp>().spec =
        fmt::format("{}{}{}{}={}", name, index, f.empty() ? "" : ".", f, fmt::format("{:g}", v));
  }
}

void BaltRun::WriteBufferString(std::string_view name, int index, std::string_view f, std::string_view s,
                                int col) {
  std::vector<unsigned char>& buf = Buffer(name, col);
  Access a;
  if (f.empty()) {
    a.kind = 'C';
    a.chars = static_cast<int>(s.size());
  } else {
    a = ParseFormat(name, f, col);
  }
  if (a.kind != 'C') Fail(col, 24, "a string goes to a character (CH) variable");
  if (s.size() > 32) Fail(col, 16, "at most 32 characters");
  std::size_t n = static_cast<std::size_t>(a.chars);
  if (index < 0 || static_cast<std::size_t>(index) + n > buf.size()) {
    Fail(col, 18, fmt::format("{}{} is outside the area", name, index));
  }
  for (std::size_t k = 0; k < n; ++k) buf[static_cast<std::size_t>(index) + k] = k < s.size() ? s[k] : ' ';
  CheckAbtvu(name, col);
  if (name != "SYVAR") Out<OutputOp>().spec = fmt::format("{}{}=\"{}\"", name, index, s);
}

// K buffer bit 340, ABTVU (ln 8520): tool life counted while the spindle and the feed are not active. The
// cell counts a tool's life from the servo's cutting time (feed moves with the spindle turning) only, so
// ABTVU=1 has no effect it could give: FILMS4 103; 0 is the cell's state (judgement call 52).
void BaltRun::CheckAbtvu(std::string_view name, int col) {
  if (name == "SK" && sk_.size() > 340 / 8 && ((sk_[340 / 8] >> (340 % 8)) & 1) != 0) {
    sk_[340 / 8] = static_cast<unsigned char>(sk_[340 / 8] & ~(1u << (340 % 8)));
    Fail(col, 103, "SK340.BL=1 (ABTVU): the cell counts tool life only while the tool cuts");
  }
}

std::string BaltRun::GlobalString(std::string_view name, int index, std::string_view f, int col) {
  std::vector<unsigned char>& buf = Buffer(name, col);
  Access a = ParseFormat(name, f.empty() ? std::string_view("CH") : f, col);
  if (a.kind != 'C') Fail(col, 24, "a string is compared with a character (CH) variable");
  std::size_t n = static_cast<std::size_t>(a.chars);
  if (index < 0 || static_cast<std::size_t>(index) + n > buf.size()) {
    Fail(col, 18, fmt::format("{}{} is outside the area", name, index));
  }
  return std::string(reinterpret_cast<const char*>(buf.data()) + index, n);
}

double BaltRun::Global(std::string_view name, bool has_index, int index, std::string_view f, int col) {
  auto plain = [&]() {
    if (has_index || !f.empty()) Fail(col, 11, fmt::format("{} takes no index", name));
  };
  if (name == "SA" || name == "SK" || name == "SYVAR") return ReadBuffer(name, has_index ? index : 0, f, col);
  if (name == "TIM" || name == "TOT") {
    if (!f.empty()) Fail(col, 11, fmt::format("{} takes no format", name));
    if (index < 0 || index > 6) Fail(col, 18, fmt::format("{}{} (0-6)", name, index));
    if (name == "TIM" && index == 0) {
      auto now = env_->Now();  // TIM0: the system clock, seconds (ln 4245-4279)
      return now[3] * 3600.0 + now[4] * 60.0 + now[5];
    }
    return name == "TIM" ? tim_[static_cast<std::size_t>(index)] : tot_[static_cast<std::size_t>(index)];
  }
  plain();
  if (name == "TMR") return tmr_;
  if (name == "UOV") return uov_ / UnitFactor();
  if (name == "RTA") return rta_ / UnitFactor();
  if (name == "RTO") return rto_ / UnitFactor();
  if (name == "ERF") return erf_ / UnitFactor();
  if (name == "MCD") return mcd_;
  if (name == "USB") return block_delete_enabled_ ? 1 : 0;
  if (name == "USO") return optional_stop_ ? 1 : 0;
  if (name == "UVR" || name == "URL" || name == "RAP")
    return 0;  // the only values the cell takes (PanelFlag)
  if (name == "UEP") return 1;
  if (name == "RMS") return rms_;
  if (name == "ERR") return err_;
  if (name == "IOSTA") return iosta_;
  Fail(col, 15, fmt::format("{} is not a variable", name));
}

// Table 4.3 (ln 2166-2177) operator-panel switches a program may set. The cell takes the value that describes
// it and refuses the other (judgement call 41): feed moves always at the programmed feed (UVR=0: the canon
// has no "feed at rapid" test mode), no JOG and so no rapid under the jog selector (URL=0), a feed hold that
// stays on the path with no jog away and so nothing to return from (RAP=0; RAP=1 is the control's own FILMS4
// 05), the servo's following-error check always on (UEP=1: alarm 410 "DIFF over").
void BaltRun::PanelFlag(std::string_view name, double v, int col) {
  if (v != 0 && v != 1) Fail(col, 13, fmt::format("{} is 0 or 1", name));
  const bool on = v != 0;
  if (name == "UVR" && on) Fail(col, 103, "UVR=1 (feed moves at rapid for testing): not on the cell");
  if (name == "URL" && on) Fail(col, 103, "URL=1 (rapid under the JOG selector): the cell has no JOG");
  if (name == "RAP" && on)
    Fail(col, 5, "RAP=1: a feed hold on the cell stays on the profile, there is no jog to return from");
  if (name == "UEP" && !on) Fail(col, 103, "UEP=0: the servo always checks the following error");
}

void BaltRun::AssignGlobal(const Assignment& a) {
  const std::string_view name = a.name;
  const int col = a.col;
  const int index = a.has_index ? static_cast<int>(a.gindex.num) : 0;
  if (name == "JOG" || name == "UCV" || name == "UAS" || name == "VOL" || name == "MBR") {
    Fail(col, 59, fmt::format("{} is set from the keyboard only", name));
  }
  if (name == "SA" || name == "SK" || name == "SYVAR") {
    if (!a.rhs.empty() && a.rhs.front() == '"') {
      if (a.rhs.size() < 2 || a.rhs.back() != '"') Fail(a.rhs_col, 11, "closing '\"' missing");
      WriteBufferString(name, index, a.fmt, a.rhs.substr(1, a.rhs.size() - 2), col);
    } else {
      WriteBuffer(name, index, a.fmt, Eval(a.rhs, a.rhs_col), col);
    }
    return;
  }
  if (name == "IOSTA") Fail(col, 24, "IOSTA is read only");
  if (name == "TIM" || name == "TOT") {
    if (!a.fmt.empty()) Fail(col, 11, fmt::format("{} takes no format", name));
    if (index < 0 || index > 6) Fail(col, 18, fmt::format("{}{} (0-6)", name, index));
    if (name == "TIM" && index == 0)
      Fail(col, 24, "TIM0 is the system clock (set with PTM from the keyboard)");
    // RE format (ln 4245-4315).
    double v = static_cast<float>(Eval(a.rhs, a.rhs_col));
    (name == "TIM" ? tim_ : tot_)[static_cast<std::size_t>(index)] = v;
    return;
  }
  if (a.has_index || !a.fmt.empty()) Fail(col, 11, fmt::format("{} takes no index", name));
  double v = Eval(a.rhs, a.rhs_col);
  auto flag = [&](bool& b) {
    if (v != 0 && v != 1) Fail(a.rhs_col, 13, fmt::format("{} is 0 or 1", name));
    b = v != 0;
  };
  if (name == "TMR") {
    if (v < 0 || v > 99999.999) Fail(a.rhs_col, 13, "TMR is 0-99999.999 seconds");
    tmr_ = v;
  } else if (name == "UOV") {
    uov_ = ToMm(v);
  } else if (name == "RTA") {
    rta_ = ToMm(v);
  } else if (name == "RTO") {
    rto_ = ToMm(v);
  } else if (name == "ERF") {
    if (v < 0) Fail(a.rhs_col, 13, "ERF (a form error) is not negative");
    erf_ = ToMm(v);
  } else if (name == "MCD") {
    if (v < 0 || v > 2) Fail(a.rhs_col, 13, "MCD is 0-2");
    mcd_ = v;
  } else if (name == "USB") {
    flag(block_delete_enabled_);
  } else if (name == "USO") {
    flag(optional_stop_);
  } else if (name == "UVR" || name == "URL" || name == "RAP" || name == "UEP") {
    PanelFlag(name, v, a.rhs_col);
  } else if (name == "ERR") {
    bool b = false;
    flag(b);
    err_ = b ? 1 : 0;
  } else if (name == "RMS") {
    if (v < 0 || v > 255 || v != std::floor(v)) Fail(a.rhs_col, 13, "RMS is a byte (0-255)");
    rms_ = static_cast<int>(v);
  } else {
    Fail(col, 15, fmt::format("{} is not a variable", name));
  }
}

void BaltRun::Assign(const Assignment& a) {
  switch (a.kind) {
    case Assignment::kParam:
      SetParam(a.index, Eval(a.rhs, a.rhs_col), a.col);
      return;
    case Assignment::kIndirect: {
      Val v;
      v.kind = Val::kParam;
      v.param = a.index;
      if (a.index > 19) Fail(a.col, 13, fmt::format("E(E{}): the index parameter must be E0-E19", a.index));
      int n = static_cast<int>(std::lround(ValueOf(v, a.col)));
      SetParam(n, Eval(a.rhs, a.rhs_col), a.col);
      return;
    }
    case Assignment::kGlobal:
      AssignGlobal(a);
      return;
    case Assignment::kGeometry:
      DefineElement(a);
      return;
  }
}

}  // namespace cell::interp::balt
