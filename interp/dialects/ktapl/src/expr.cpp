#include "expr.h"

#include "cell/interp/ktapl_statements.h"

#include <cctype>
#include <cmath>
#include <optional>

namespace cell::interp::ktapl {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMax = 999999999.0;

bool IsValueLetter(char c) {
  switch (c) {
    case 'A':
    case 'B':
    case 'C':
    case 'E':
    case 'F':
    case 'I':
    case 'J':
    case 'K':
    case 'P':
    case 'Q':
    case 'R':
    case 'S':
    case 'T':
    case 'U':
    case 'V':
    case 'W':
    case 'X':
    case 'Y':
    case 'Z':
      return true;
    default:
      return false;
  }
}

// A number as written (digits, a point, digits) from `pos`, moved past it: the digits read (0: none). The
// descent and the fast path both read numbers here, so they compute the same double.
int ReadNumber(std::string_view s, size_t& pos, double& v) {
  v = 0;
  int digits = 0;
  while (pos < s.size() && std::isdigit(static_cast<unsigned char>(s[pos]))) {
    v = v * 10 + (s[pos] - '0');
    ++pos;
    ++digits;
  }
  if (pos < s.size() && s[pos] == '.') {
    ++pos;
    double scale = 0.1;
    while (pos < s.size() && std::isdigit(static_cast<unsigned char>(s[pos]))) {
      v += (s[pos] - '0') * scale;
      scale /= 10;
      ++pos;
      ++digits;
    }
  }
  return digits;
}

bool Blank(char c) {
  return c == ' ' || c == '\t';
}

// The forms most expressions take, without the descent: operands (a number, L0-L2999, a value letter), each
// with at most one sign, joined by + - * / with no * or / after a + or -, so that left to right is the
// precedence (`-L5`, `L101+.001`, `L101*2.+1.`). The same operations in the same order as the descent, so the
// same value. Anything else, and anything the descent reports (an undefined parameter, an overflow, a
// division by zero), gives nullopt: the descent then evaluates the text from its start. System parameters
// (L3000-L3999) are left to the descent, as the environment may answer some of them.
std::optional<double> FastValue(std::string_view s, ExprContext& ctx) {
  size_t i = 0;
  double v = 0;
  char op = 0;  // the operator before this operand; 0 for the first
  bool additive = false;
  auto skip = [&] {
    while (i < s.size() && Blank(s[i])) ++i;
  };
  for (;;) {
    skip();
    bool neg = false;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) {
      neg = s[i] == '-';
      ++i;
      skip();
    }
    if (i >= s.size()) return std::nullopt;
    const char c = Up(s[i]);
    double x;
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
      if (ReadNumber(s, i, x) == 0 || x > kMax) return std::nullopt;
    } else if (c == 'L') {
      const size_t start = ++i;
      int n = 0;
      while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) {
        n = n * 10 + (s[i] - '0');
        if (n > 2999) return std::nullopt;
        ++i;
      }
      if (i == start) return std::nullopt;  // L(expr)
      try {
        x = ctx.Param(n);
      } catch (const ExprError&) {
        return std::nullopt;
      }
    } else if (IsValueLetter(c) &&
               !(i + 1 < s.size() && std::isalpha(static_cast<unsigned char>(s[i + 1])))) {
      ++i;
      x = ctx.Letter(c);
    } else {
      return std::nullopt;
    }
    if (neg) x = -x;
    switch (op) {
      case 0:
        v = x;
        break;
      case '+':
        v = v + x;
        break;
      case '-':
        v = v - x;
        break;
      case '*':
        v = v * x;
        break;
      default:
        if (x == 0) return std::nullopt;
        v = v / x;
        break;
    }
    if (op != 0 && (!std::isfinite(v) || std::fabs(v) > kMax)) return std::nullopt;
    skip();
    if (i >= s.size()) return v;
    op = s[i++];
    if (op == '+' || op == '-') {
      additive = true;
    } else if (op != '*' && op != '/') {
      return std::nullopt;
    } else if (additive) {
      return std::nullopt;
    }
  }
}

}  // namespace

void ExprParser::Fail(const std::string& text) {
  throw ExprError{text, pos_};
}

double ExprParser::Check(double v) {
  if (!std::isfinite(v) || std::fabs(v) > kMax) Fail("CALCULATION ERROR - INTERNAL OVERFLOW");
  return v;
}

void ExprParser::SkipSpaces() {
  while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\t')) ++pos_;
}

bool ExprParser::AtEnd() {
  SkipSpaces();
  return pos_ >= s_.size();
}

char ExprParser::Peek() {
  SkipSpaces();
  return pos_ < s_.size() ? Up(s_[pos_]) : '\0';
}

bool ExprParser::Accept(char c) {
  if (Peek() == c) {
    ++pos_;
    return true;
  }
  return false;
}

bool ExprParser::AcceptWord(std::string_view w) {
  SkipSpaces();
  if (s_.size() - pos_ < w.size()) return false;
  for (size_t i = 0; i < w.size(); ++i) {
    if (Up(s_[pos_ + i]) != w[i]) return false;
  }
  pos_ += w.size();
  return true;
}

double ExprParser::Value() {
  double v = Term();
  for (;;) {
    if (Accept('+')) {
      v = Check(v + Term());
    } else if (Accept('-')) {
      v = Check(v - Term());
    } else {
      return v;
    }
  }
}

double ExprParser::Term() {
  double v = Unary();
  for (;;) {
    if (Accept('*')) {
      v = Check(v * Unary());
    } else if (Accept('/')) {
      size_t at = pos_;
      double d = Unary();
      if (d == 0) {
        pos_ = at;
        Fail("CALCULATION ERROR - DIVISION BY ZERO");
      }
      v = Check(v / d);
    } else {
      return v;
    }
  }
}

double ExprParser::Unary() {
  if (Accept('-')) return -Unary();
  if (Accept('+')) return Unary();
  return Primary();
}

int ExprParser::ParamRef() {
  SkipSpaces();
  if (Peek() != 'L') Fail("PARAMETER REFERENCE EXPECTED");
  ++pos_;
  if (Accept('(')) {
    if (++depth_ > 8) Fail("Error - exceeds 8 open parentheses");
    double v = Value();
    if (!Accept(')')) Fail("MISSING )");
    --depth_;
    double r = std::floor(v + 0.5);
    if (r < 0 || r > 3999) Fail("Error L numbers range from 0..3999");
    return static_cast<int>(r);
  }
  size_t start = pos_;
  long n = 0;
  while (pos_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[pos_]))) {
    n = n * 10 + (s_[pos_] - '0');
    if (n > 99999) Fail("Error L numbers range from 0..3999");
    ++pos_;
  }
  if (pos_ == start) Fail("PARAMETER NUMBER EXPECTED");
  if (n > 3999) Fail("Error L numbers range from 0..3999");
  return static_cast<int>(n);
}

double ExprParser::Primary() {
  SkipSpaces();
  if (pos_ >= s_.size()) Fail("EXPRESSION EXPECTED");
  char c = Up(s_[pos_]);
  if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
    size_t start = pos_;
    double v;
    const int digits = ReadNumber(s_, pos_, v);
    if (digits == 0) {
      pos_ = start;
      Fail("NUMBER EXPECTED");
    }
    if (v > kMax) {
      pos_ = start;
      Fail("CONSTANT OUT OF RANGE");
    }
    return v;
  }
  if (c == '(') {
    if (++depth_ > 8) Fail("Error - exceeds 8 open parentheses");  // at the ninth '('
    ++pos_;
    double v = Value();
    if (!Accept(')')) Fail("MISSING )");
    --depth_;
    return v;
  }
  // Functions, longest names first. Every name has at least two letters: a letter followed by anything else
  // (L5, X) is not a function, and the 15 names need not be tried.
  bool maybe_func = pos_ + 1 < s_.size() && std::isalpha(static_cast<unsigned char>(s_[pos_ + 1]));
  static const char* const kFuncs[] = {"SQRT", "ALOG", "ABS", "SIN", "COS", "TAN", "ASN", "ACS",
                                       "ATN",  "INT",  "FRA", "LOG", "EXP", "SQ",  "LN"};
  for (const char* f : kFuncs) {
    if (!maybe_func) break;
    size_t save = pos_;
    std::string_view name(f);
    if (AcceptWord(name)) {
      if (Peek() == '(') {
        size_t at = save;
        if (++depth_ > 8) Fail("Error - exceeds 8 open parentheses");
        ++pos_;
        double a = Value();
        if (!Accept(')')) Fail("MISSING )");
        --depth_;
        size_t after = pos_;
        pos_ = at;
        double r = 0;
        if (name == "SQRT") {
          if (a < 0) Fail("Error: negative square root attempted");
          r = std::sqrt(a);
        } else if (name == "SQ") {
          r = a * a;
        } else if (name == "ABS") {
          r = std::fabs(a);
        } else if (name == "SIN") {
          r = std::sin(a * kPi / 180.0);
        } else if (name == "COS") {
          r = std::cos(a * kPi / 180.0);
        } else if (name == "TAN") {
          double m = std::fmod(std::fabs(a), 180.0);
          if (std::fabs(m - 90.0) < 1e-9) Fail("CALCULATION ERROR - INTERNAL OVERFLOW");
          r = std::tan(a * kPi / 180.0);
        } else if (name == "ASN") {
          if (a < -1.0 || a > 1.0) Fail("ASN argument error: ASN(n) -1.0000 <= n <= 1.0000");
          r = std::asin(a) * 180.0 / kPi;
        } else if (name == "ACS") {
          if (a < -1.0 || a > 1.0) Fail("ACS argument error: ACS(n) -1.0000 <= n <= 1.0000");
          r = std::acos(a) * 180.0 / kPi;
        } else if (name == "ATN") {
          r = std::atan(a) * 180.0 / kPi;
        } else if (name == "INT") {
          r = std::trunc(a);
        } else if (name == "FRA") {
          r = a - std::trunc(a);
        } else if (name == "LOG") {
          if (a < 0.00000001 || a > kMax) Fail("LOG argument error: LOG(n) .00000001 <= n <= 999999999.");
          r = std::log10(a);
        } else if (name == "LN") {
          if (a < 0.00000001 || a > kMax) Fail("LN argument error: LN(n) .00000001 <= n <= 999999999.");
          r = std::log(a);
        } else if (name == "ALOG") {
          if (a < -7.9999999 || a > 7.9999999) {
            Fail("ALOG argument error: ALOG(n) -7.9999999 <= n <= 7.9999999");
          }
          r = std::pow(10.0, a);
        } else if (name == "EXP") {
          if (a < -18.420680 || a > 18.420680)
            Fail("EXP argument error: EXP(n) -18.420680 <= n <= 18.420680");
          r = std::exp(a);
        }
        r = Check(r);
        pos_ = after;
        return r;
      }
      pos_ = save;
    }
  }
  if (c == 'L') {
    size_t at = pos_;
    int n = ParamRef();
    try {
      return ctx_.Param(n);
    } catch (ExprError& e) {
      e.offset = at;  // the context does not know where the reference stands: point at it
      throw;
    }
  }
  if (IsValueLetter(c)) {
    ++pos_;
    return ctx_.Letter(c);
  }
  Fail(std::string("UNEXPECTED CHARACTER '") + s_[pos_] + "' IN EXPRESSION");
}

bool ExprParser::Condition() {
  return OrCond();
}

bool ExprParser::OrCond() {
  bool v = AndCond();
  while (AcceptWord("OR")) {
    bool r = AndCond();
    v = v || r;
  }
  return v;
}

bool ExprParser::AndCond() {
  bool v = NotCond();
  while (AcceptWord("AND")) {
    bool r = NotCond();
    v = v && r;
  }
  return v;
}

bool ExprParser::NotCond() {
  if (AcceptWord("NOT")) return !NotCond();
  return Atom();
}

bool ExprParser::Atom() {
  SkipSpaces();
  if (AcceptWord("DEF")) {
    if (!Accept('(')) Fail("DEF( EXPECTED");
    int n = ParamRef();
    if (!Accept(')')) Fail("MISSING )");
    return ctx_.ParamDefined(n);
  }
  char c = Peek();
  if ((c == 'G' || c == 'M') && pos_ + 1 < s_.size() &&
      std::isdigit(static_cast<unsigned char>(s_[pos_ + 1]))) {
    ++pos_;
    int code = 0;
    while (pos_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[pos_]))) {
      code = code * 10 + (s_[pos_] - '0');
      if (code > 9999) Fail("ILLEGAL CODE IN CONDITION");
      ++pos_;
    }
    return ctx_.ActiveCode(c, code);
  }
  // value relop value, or a parenthesised condition.
  size_t start = pos_;
  int depth = depth_;
  try {
    double a = Value();
    SkipSpaces();
    int op = 0;  // 1 '=', 2 '<>', 3 '<', 4 '>', 5 '<=', 6 '>='
    if (Accept('<')) {
      if (Accept('>'))
        op = 2;
      else if (Accept('='))
        op = 5;
      else
        op = 3;
    } else if (Accept('>')) {
      op = Accept('=') ? 6 : 4;
    } else if (Accept('=')) {
      if (Accept('<'))
        op = 5;
      else if (Accept('>'))
        op = 6;
      else
        op = 1;
    } else {
      Fail("RELATIONAL OPERATOR EXPECTED");
    }
    double b = Value();
    // Compare at the control's precision (about 10 significant digits).
    double tol = 1e-10 * std::max(1.0, std::max(std::fabs(a), std::fabs(b)));
    bool eq = std::fabs(a - b) <= tol;
    switch (op) {
      case 1:
        return eq;
      case 2:
        return !eq;
      case 3:
        return a < b && !eq;
      case 4:
        return a > b && !eq;
      case 5:
        return a < b || eq;
      default:
        return a > b || eq;
    }
  } catch (const ExprError& first) {
    pos_ = start;
    depth_ = depth;
    if (Peek() != '(') throw;
    ++pos_;
    if (++depth_ > 8) Fail("Error - exceeds 8 open parentheses");
    bool v;
    try {
      v = OrCond();
    } catch (const ExprError&) {
      throw first;
    }
    if (!Accept(')')) throw first;
    --depth_;
    return v;
  }
}

double EvalValue(std::string_view text, ExprContext& ctx) {
  if (const std::optional<double> v = FastValue(text, ctx)) return *v;
  ExprParser p(text, ctx);
  double v = p.Value();
  if (!p.AtEnd()) throw ExprError{"SYNTAX ERROR IN EXPRESSION", p.pos()};
  return v;
}

bool EvalCondition(std::string_view text, ExprContext& ctx) {
  ExprParser p(text, ctx);
  bool v = p.Condition();
  if (!p.AtEnd()) throw ExprError{"SYNTAX ERROR IN CONDITION", p.pos()};
  return v;
}

}  // namespace cell::interp::ktapl
