// Okuma User Task expressions: parsing into a node pool and evaluation (see expr.h).
#include "expr.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace cell::interp::okuma {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

struct FnName {
  std::string_view name;
  Fn fn;
  int args;
};
constexpr std::array<FnName, 16> kFunctions = {{
    {"SIN", Fn::kSin, 1},
    {"COS", Fn::kCos, 1},
    {"TAN", Fn::kTan, 1},
    {"ATAN", Fn::kAtan, 1},
    {"ATAN2", Fn::kAtan2, 2},
    {"SQRT", Fn::kSqrt, 1},
    {"ABS", Fn::kAbs, 1},
    {"BIN", Fn::kBin, 1},
    {"BCD", Fn::kBcd, 1},
    {"ROUND", Fn::kRound, 1},
    {"FIX", Fn::kFix, 1},
    {"FUP", Fn::kFup, 1},
    {"DROUND", Fn::kDround, 1},
    {"DFIX", Fn::kDfix, 1},
    {"DFUP", Fn::kDfup, 1},
    {"MOD", Fn::kMod, 2},
}};

const FnName* FindFunction(std::string_view name) {
  for (const auto& f : kFunctions) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

// Appendix "Table of System Variables" (seed ln 9882-10087) and the I/O variables (ln 7892-7918, 8236-8278).
constexpr auto kSystemNames = std::to_array<std::string_view>({
    "VZOFZ", "VZOFX", "VZOFC", "VZOFY", "VZOFW", "VZSHZ", "VZSHX", "VZSHC", "VZSHY", "VZSHW", "VTOFZ",
    "VTOFX", "VTSOY", "VNSRZ", "VNSRX", "VNSRP", "VPVLZ", "VPVLX", "VPVLW", "VNVLZ", "VNVLX", "VNVLW",
    "VCHKL", "VCHKD", "VCHKZ", "VCHKX", "VTSL",  "VTSDA", "VTSDB", "VWKR",  "VINPZ", "VINPX", "VINPC",
    "VINPY", "VPFVZ", "VPFVX", "VPFVC", "VPFVY", "VPFVT", "VPCHZ", "VPCHX", "VRSTT", "VUACM", "VPAI",
    "VTRTS", "VTLGN", "VTLSN", "VTLCN", "VTLST", "VTLCT", "VTLSA", "VTLCA", "VTLOA", "VTLOB", "VTLOC",
    "VTLUS", "VTLNG", "VTLLF", "VGRSL", "VGRLF", "VGRID", "VXMP0", "VXMCD", "VXMON", "VXMTG", "VXMOG",
    "VXMXZ", "VXMNC", "VXMCO", "VXMMC", "VXMMO", "VXMMD", "VXMDR", "VRNGZ", "VRNGX", "VSNZ",  "VSNX",
    "VIMDZ", "VIMDX", "VTOAA", "VTOBA", "VTOCA", "VTOAB", "VTOBB", "VTOCB", "VTHRZ", "VTHRX", "VLMON",
    "VEINT", "VBNCT", "VPWSP", "VPWTP", "VTLIN", "VTLFN", "VTLA1", "VTLA2", "VTLL",  "VTLD",  "VTLW",
    "VTIZN", "VTIZP", "VTIXN", "VTIXP", "VTIPN", "VGRIN", "VGRFN", "VGRA1", "VGRA2", "VGRL",  "VGRD",
    "VGRW",  "VSIDC", "VEXPO", "VEXTR", "VEXAX", "VEXGF", "VEXTO", "VEXOG", "VEXOK", "VEXFB", "VEXDR",
    "VSIOZ", "VSIOY", "VSIOX", "VSIOC", "VAPAZ", "VAPAX", "VSKPZ", "VSKPY", "VSKPX", "VSKPC", "VETFZ",
    "VETFY", "VETFX", "VDIFZ", "VDIFX", "VETON", "VETLN", "VAPPZ", "VAPPX", "VMIRZ", "VCNGC", "VXMD5",
    "VTOPC", "VCEJM", "VMCN",  "VMDT",  "VXMBD", "VXMAB", "VWKCS", "VWKCC", "VSKFA", "VSKFB", "VRZV",
    "VRCV",  "VRRG",  "VRVY",  "VRBV",  "VRVW",  "VRVX",  "VLZV",  "VLYV",  "VLRG",  "VPLOF", "VTLMT",
    "VMXA1", "VMNA1", "VMXA2", "VMNA2", "VCHIO", "VCHSW", "VZARP", "VZBRP", "VZCRP", "VXARP", "VXBRP",
    "VWAP",  "VSNWD", "VSNTU", "VRUND", "VUNIT", "VDIN",  "VDOUT", "VIRD",  "VORD",
});

// Extended addresses (ln 7599-7603), comparison and boolean operators.
constexpr auto kReserved = std::to_array<std::string_view>({
    "AA", "AB", "DA",  "DB",  "FA",  "FB",  "IA",   "IB",   "KA",   "KB",   "LA",  "LB", "RA",
    "RB", "SA", "SB",  "TA",  "TB",  "UA",  "UB",   "WA",   "WB",   "XA",   "XB",  "ZA", "ZB",
    "BC", "LT", "LE",  "EQ",  "NE",  "GT",  "GE",   "OR",   "AND",  "EOR",  "NOT", "QA", "PZ",
    "PW", "IF", "END", "RTS", "GET", "PUT", "CALL", "GOTO", "READ", "VSET",
});

int64_t Trunc(double v, int col) {
  if (!std::isfinite(v) || std::fabs(v) > 2147483647.0) Fail(col, "value out of the integer range");
  return static_cast<int64_t>(std::trunc(v));
}

Value Real(double v) {
  return {v, false};
}
Value Int(double v) {
  return {v, true};
}

// A name of up to 7 characters and its length in one integer: the reserved-name test is a binary search of
// integers (it runs for every local variable name a block reads).
constexpr uint64_t NameKey(std::string_view name) {
  uint64_t out = static_cast<uint64_t>(name.size()) << 56;
  for (size_t i = 0; i < name.size() && i < 7; ++i)
    out |= static_cast<uint64_t>(static_cast<unsigned char>(name[i])) << (8 * i);
  return out;
}
constexpr auto kReservedKeys = [] {
  std::array<uint64_t, kReserved.size() + kFunctions.size()> keys{};
  size_t n = 0;
  for (std::string_view r : kReserved) keys[n++] = NameKey(r);
  for (const FnName& f : kFunctions) keys[n++] = NameKey(f.name);
  std::sort(keys.begin(), keys.end());  // searched by halves
  return keys;
}();
static_assert(std::all_of(kReserved.begin(), kReserved.end(),
                          [](std::string_view r) { return r.size() <= 7; }));
static_assert(std::all_of(kFunctions.begin(), kFunctions.end(),
                          [](const FnName& f) { return f.name.size() <= 7; }));

}  // namespace

uint64_t PackName(std::string_view name) {
  uint64_t out = 0;
  for (size_t i = 0; i < name.size() && i < 8; ++i) out |= static_cast<uint64_t>(Up(name[i])) << (8 * i);
  return out;
}

std::string UnpackName(uint64_t packed) {
  std::string out;
  for (int i = 0; i < 8; ++i) {
    char c = static_cast<char>((packed >> (8 * i)) & 0xff);
    if (c == 0) break;
    out.push_back(c);
  }
  return out;
}

bool IsSystemVariable(std::string_view name) {
  return std::find(kSystemNames.begin(), kSystemNames.end(), name) != kSystemNames.end();
}

bool IsReservedName(std::string_view name) {
  if (name.size() > 7) return false;  // longer than any reserved name
  const uint64_t key = NameKey(name);
  return std::binary_search(kReservedKeys.begin(), kReservedKeys.end(), key);
}

bool IsLocalName(std::string_view name) {
  if (name.size() < 2 || name.size() > 4) return false;
  if (!IsLetter(name[0]) || !IsLetter(name[1])) return false;
  if (name[0] == 'O' || name[0] == 'N' || name[0] == 'V') return false;
  for (char c : name) {
    if (!IsAlnumC(c)) return false;
  }
  return !IsReservedName(name);
}

double Snap(double v) {
  double r = std::round(v);
  return std::fabs(v - r) <= 1e-9 * std::max(1.0, std::fabs(v)) ? r : v;
}

double RoundAway(double v) {
  v = Snap(v);
  return v < 0 ? -std::floor(-v + 0.5) : std::floor(v + 0.5);
}

double RaiseAway(double v) {
  v = Snap(v);
  return v < 0 ? -std::ceil(-v) : std::ceil(v);
}

double TruncSnap(double v) {
  return std::trunc(Snap(v));
}

// ---------------------------------------------------------------------------------------------------------
// Parsing

void ExprParser::Error(const std::string& text) const {
  Fail(Col(), text);
}

int32_t ExprParser::Add(Node n) {
  pool_.push_back(n);
  return static_cast<int32_t>(pool_.size() - 1);
}

void ExprParser::SkipBlanks() {
  while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\t')) ++pos_;
}

std::string_view ExprParser::PeekWord() const {
  size_t i = pos_;
  while (i < s_.size() && (s_[i] == ' ' || s_[i] == '\t')) ++i;
  size_t j = i;
  while (j < s_.size() && IsLetter(s_[j])) ++j;
  return s_.substr(i, j - i);
}

// At bracket depth 0 a blank ends the expression unless an operator follows it; inside brackets blanks are
// always skipped.
bool ExprParser::AtOperatorAfterBlanks() {
  size_t i = pos_;
  while (i < s_.size() && (s_[i] == ' ' || s_[i] == '\t')) ++i;
  if (i >= s_.size()) return false;
  if (depth_ > 0) return true;
  if (i == pos_) return true;  // no blank: whatever follows is looked at by the caller
  char c = s_[i];
  if (c == '+' || c == '-' || c == '*' || c == '/') return true;
  std::string_view w = PeekWord();
  size_t end = i + w.size();
  bool boundary = end >= s_.size() || !IsAlnumC(s_[end]);
  if (!boundary) return false;
  return w == "OR" || w == "AND" || w == "EOR" || w == "LT" || w == "LE" || w == "EQ" || w == "NE" ||
         w == "GT" || w == "GE";
}

bool ExprParser::WordOperatorAfterBlanks() const {
  size_t i = pos_;
  while (i < s_.size() && (s_[i] == ' ' || s_[i] == '\t')) ++i;
  size_t j = i;
  while (j < s_.size() && IsLetter(s_[j])) ++j;
  if (j == i || j - i > 3 || (j < s_.size() && IsDigit(s_[j]))) return false;
  const std::string_view w = s_.substr(i, j - i);
  return w == "OR" || w == "AND" || w == "EOR" || w == "LT" || w == "LE" || w == "EQ" || w == "NE" ||
         w == "GT" || w == "GE";
}

bool ExprParser::AcceptWord(std::string_view w) {
  if (!AtOperatorAfterBlanks()) return false;
  size_t i = pos_;
  while (i < s_.size() && (s_[i] == ' ' || s_[i] == '\t')) ++i;
  if (s_.substr(i, w.size()) != w) return false;
  size_t end = i + w.size();
  if (end < s_.size() && IsAlnumC(s_[end])) return false;
  pos_ = end;
  return true;
}

int32_t ExprParser::Parse() {
  SkipBlanks();
  if (pos_ >= s_.size() || s_[pos_] == '(') Error("expression expected");
  if (const int32_t e = Simple(); e >= 0) return e;
  return Or();
}

// Most values are operands joined by + - * / with no * or / after a + or - (V1+0.001, X=V2+100, V1*2+1):
// built here, left to right, into the nodes the descent would build, without its seven levels each looking
// ahead. Anything else, a blank inside included, goes back (-1, pos_ and the pool as they were) to the
// descent.
int32_t ExprParser::Simple() {
  const size_t start = pos_;
  const size_t pool_size = pool_.size();
  auto back = [&] {
    pos_ = start;
    pool_.resize(pool_size);
    return -1;
  };
  int32_t l = SimpleOperand();
  if (l < 0) return back();
  bool sum = false;  // a + or - seen: a * or / after it binds first, which only the descent builds
  while (pos_ < s_.size()) {
    const char c = s_[pos_];
    NodeOp op;
    if (c == '+') {
      op = NodeOp::kAdd;
    } else if (c == '-') {
      op = NodeOp::kSub;
    } else if (c == '*') {
      op = NodeOp::kMul;
    } else if (c == '/') {
      op = NodeOp::kDiv;
    } else {
      break;
    }
    const bool product = c == '*' || c == '/';
    if (product && sum) return back();
    sum = sum || !product;
    const int col = Col();
    ++pos_;
    const int32_t r = SimpleOperand();
    if (r < 0) return back();
    l = Binary(op, l, r, col);
  }
  // The expression must end here: at the end of the text or at a blank the descent stops at too.
  if (pos_ < s_.size() && ((s_[pos_] != ' ' && s_[pos_] != '\t') || AtOperatorAfterBlanks())) return back();
  return l;
}

// An unsigned constant or a common variable V1-V200 (Primary's nodes for them), else -1.
int32_t ExprParser::SimpleOperand() {
  if (pos_ >= s_.size()) return -1;
  const int col = Col();
  const char c = s_[pos_];
  if (IsDigit(c) || c == '.') return Number(col);
  if (Up(c) != 'V') return -1;
  size_t end = pos_ + 1;
  while (end < s_.size() && IsAlnumC(s_[end])) ++end;
  if (end - pos_ < 2 || end - pos_ > 4) return -1;
  int v = 0;
  for (size_t k = pos_ + 1; k < end; ++k) {
    if (!IsDigit(s_[k])) return -1;
    v = v * 10 + (s_[k] - '0');
  }
  if (v < 1 || v > 200) return -1;
  pos_ = end;
  Node n;
  n.op = NodeOp::kCommon;
  n.num = v;
  n.col = col;
  return Add(n);
}

int32_t ExprParser::Binary(NodeOp op, int32_t a, int32_t b, int col) {
  Node n;
  n.op = op;
  n.a = a;
  n.b = b;
  n.col = col;
  return Add(n);
}

int32_t ExprParser::Or() {
  int32_t l = And();
  for (;;) {
    if (!WordOperatorAfterBlanks()) return l;  // what AcceptWord below needs (most expressions end here)
    int col = Col();
    NodeOp op;
    if (AcceptWord("OR")) {
      op = NodeOp::kOr;
    } else if (AcceptWord("EOR")) {
      op = NodeOp::kEor;
    } else {
      return l;
    }
    l = Binary(op, l, And(), col);
  }
}

int32_t ExprParser::And() {
  int32_t l = Compare();
  for (;;) {
    if (!WordOperatorAfterBlanks()) return l;
    int col = Col();
    if (!AcceptWord("AND")) return l;
    l = Binary(NodeOp::kAnd, l, Compare(), col);
  }
}

int32_t ExprParser::Compare() {
  int32_t l = Sum();
  static constexpr std::array<std::pair<std::string_view, NodeOp>, 6> kOps = {{{"LT", NodeOp::kLt},
                                                                               {"LE", NodeOp::kLe},
                                                                               {"EQ", NodeOp::kEq},
                                                                               {"NE", NodeOp::kNe},
                                                                               {"GT", NodeOp::kGt},
                                                                               {"GE", NodeOp::kGe}}};
  for (;;) {
    if (!WordOperatorAfterBlanks()) return l;
    int col = Col();
    bool found = false;
    for (const auto& [w, op] : kOps) {
      if (AcceptWord(w)) {
        l = Binary(op, l, Sum(), col);
        found = true;
        break;
      }
    }
    if (!found) return l;
  }
}

int32_t ExprParser::Sum() {
  return LeftAssociative<&ExprParser::Product>('+', NodeOp::kAdd, '-', NodeOp::kSub);
}

int32_t ExprParser::Product() {
  return LeftAssociative<&ExprParser::Unary>('*', NodeOp::kMul, '/', NodeOp::kDiv);
}

// One precedence level of two left-associative operators over `operand`; an operator counts only where
// AtOperatorAfterBlanks says the expression goes on (ln 6601: a blank ends it otherwise).
template <int32_t (ExprParser::*operand)()>
int32_t ExprParser::LeftAssociative(char c1, NodeOp op1, char c2, NodeOp op2) {
  int32_t l = (this->*operand)();
  for (;;) {
    if (!AtOperatorAfterBlanks()) return l;
    size_t save = pos_;
    SkipBlanks();
    if (pos_ >= s_.size() || (s_[pos_] != c1 && s_[pos_] != c2)) {
      pos_ = save;
      return l;
    }
    const int col = Col();
    const NodeOp op = s_[pos_] == c1 ? op1 : op2;
    ++pos_;
    l = Binary(op, l, (this->*operand)(), col);
  }
}

int32_t ExprParser::Unary() {
  SkipBlanks();
  if (pos_ >= s_.size()) Error("operand expected");
  int col = Col();
  if (s_[pos_] == '-' || s_[pos_] == '+') {
    bool neg = s_[pos_] == '-';
    ++pos_;
    int32_t a = Unary();
    if (!neg) return a;
    Node n;
    n.op = NodeOp::kNeg;
    n.a = a;
    n.col = col;
    return Add(n);
  }
  if (s_.substr(pos_, 3) == "NOT" && (pos_ + 3 >= s_.size() || !IsAlnumC(s_[pos_ + 3]))) {
    pos_ += 3;
    int32_t a = Unary();
    Node n;
    n.op = NodeOp::kNot;
    n.a = a;
    n.col = col;
    return Add(n);
  }
  return Primary();
}

int32_t ExprParser::Number(int col) {
  Node n;
  n.col = col;
  const Decimal d = ReadDecimal(s_, pos_);
  if (d.point && pos_ < s_.size() && s_[pos_] == '.') Error("two decimal points in a number");
  n.integer = !d.point;
  if (d.digits > 8) Fail(col, "a constant has at most 8 digits");
  n.num = d.v;
  return Add(n);
}

int32_t ExprParser::Primary() {
  SkipBlanks();
  if (pos_ >= s_.size()) Error("operand expected");
  const int col = Col();
  const char c = s_[pos_];
  if (c == '[') {
    ++pos_;
    ++depth_;
    if (depth_ > 32) Error("brackets nested too deeply");
    int32_t e = Or();
    SkipBlanks();
    if (pos_ >= s_.size() || s_[pos_] != ']') Error("']' expected");
    ++pos_;
    --depth_;
    return e;
  }
  if (c == '(') Error("'(' starts a comment: group expressions with [ ]");
  if (IsDigit(c) || c == '.') return Number(col);
  if (c == '$') {
    ++pos_;
    size_t start = pos_;
    int64_t v = 0;
    while (pos_ < s_.size() && std::isxdigit(static_cast<unsigned char>(s_[pos_]))) {
      char d = Up(s_[pos_]);
      v = v * 16 + (IsDigit(d) ? d - '0' : d - 'A' + 10);
      if (v > 0xffffffffLL) Error("hexadecimal constant too long");
      ++pos_;
    }
    if (pos_ == start) Error("hexadecimal digits expected after '$'");
    Node n;
    n.col = col;
    n.integer = true;
    n.num = static_cast<double>(v);
    return Add(n);
  }
  if (!IsLetter(c)) Error(fmt::format("unexpected '{}' in an expression", c));
  size_t start = pos_;
  while (pos_ < s_.size() && IsAlnumC(s_[pos_])) ++pos_;
  std::string name(s_.substr(start, pos_ - start));
  for (char& ch : name) ch = Up(ch);
  // No function name begins with V: variables (most names) skip the function table.
  if (const FnName* f = name[0] == 'V' ? nullptr : FindFunction(name)) {
    SkipBlanks();
    if (pos_ >= s_.size() || s_[pos_] != '[') Fail(col, fmt::format("{} needs its argument in [ ]", name));
    ++pos_;
    ++depth_;
    Node n;
    n.op = NodeOp::kFn;
    n.fn = f->fn;
    n.col = col;
    n.a = Or();
    SkipBlanks();
    if (f->args == 2) {
      if (pos_ >= s_.size() || s_[pos_] != ',') Fail(col, fmt::format("{} takes two arguments [a,b]", name));
      ++pos_;
      n.b = Or();
      SkipBlanks();
    }
    if (pos_ >= s_.size() || s_[pos_] != ']')
      Fail(col, fmt::format("']' expected after the {} argument", name));
    ++pos_;
    --depth_;
    return Add(n);
  }
  if (name[0] == 'V' && name.size() > 1 && std::all_of(name.begin() + 1, name.end(), IsDigit)) {
    if (name.size() > 4) Fail(col, fmt::format("common variable {}: common variables are V1-V200", name));
    int v = 0;  // at most three digits (checked above)
    for (size_t k = 1; k < name.size(); ++k) v = v * 10 + (name[k] - '0');
    if (v < 1 || v > 200) Fail(col, fmt::format("common variable {}: common variables are V1-V200", name));
    Node n;
    n.op = NodeOp::kCommon;
    n.num = v;
    n.col = col;
    return Add(n);
  }
  if (name[0] == 'V') {
    if (!IsSystemVariable(name)) Fail(col, fmt::format("illegal system variable name {}", name));
    Node n;
    n.op = NodeOp::kSystem;
    n.name = PackName(name);
    n.col = col;
    if (pos_ < s_.size() && s_[pos_] == '[') {
      ++pos_;
      ++depth_;
      n.a = Or();
      SkipBlanks();
      if (pos_ >= s_.size() || s_[pos_] != ']')
        Fail(col, fmt::format("']' expected after the {} suffix", name));
      ++pos_;
      --depth_;
    }
    return Add(n);
  }
  if (!IsLocalName(name)) {
    if (IsReservedName(name)) Fail(col, fmt::format("{} cannot be used as a value here", name));
    Fail(col, fmt::format("'{}' is not a variable name (local variables: two letters, then up to two "
                          "letters or digits)",
                          name));
  }
  Node n;
  n.op = NodeOp::kLocal;
  n.name = PackName(name);
  n.col = col;
  return Add(n);
}

// ---------------------------------------------------------------------------------------------------------
// Evaluation

namespace {

int64_t Bcd2Bin(int64_t v, int col) {
  if (v < 0) Fail(col, "BIN of a negative value");
  int64_t out = 0, mul = 1;
  while (v > 0) {
    int64_t d = v & 0xf;
    if (d > 9) Fail(col, "BIN: the value is not binary-coded decimal");
    out += d * mul;
    mul *= 10;
    v >>= 4;
  }
  return out;
}

int64_t Bin2Bcd(int64_t v, int col) {
  if (v < 0) Fail(col, "BCD of a negative value");
  int64_t out = 0;
  int shift = 0;
  while (v > 0) {
    out |= (v % 10) << shift;
    shift += 4;
    v /= 10;
  }
  return out;
}

class Evaluator {
 public:
  Evaluator(const std::vector<Node>& pool, VarReader& vars) : pool_(pool), vars_(vars) {}

  Value Eval(int32_t i) {
    const Node& n = pool_[static_cast<size_t>(i)];
    switch (n.op) {
      case NodeOp::kNum:
        return {n.num, n.integer};
      case NodeOp::kCommon:
        return Real(vars_.Common(static_cast<int>(n.num), n.col));
      case NodeOp::kLocal:
        return Real(vars_.Local(n.name, n.col));
      case NodeOp::kSystem: {
        if (n.a < 0) return vars_.System(n.name, nullptr, n.col);
        Value idx = Eval(n.a);
        return vars_.System(n.name, &idx, n.col);
      }
      case NodeOp::kNeg: {
        Value a = Eval(n.a);
        return {-a.v, a.integer};
      }
      case NodeOp::kNot:
        return Int(static_cast<double>(static_cast<int32_t>(~Trunc(Eval(n.a).v, n.col))));
      case NodeOp::kAdd:
      case NodeOp::kSub: {
        Value a = Eval(n.a), b = Eval(n.b);
        double v = n.op == NodeOp::kAdd ? a.v + b.v : a.v - b.v;
        return {v, a.integer && b.integer};
      }
      case NodeOp::kMul:
        return Real(Eval(n.a).v * Eval(n.b).v);
      case NodeOp::kDiv: {
        Value a = Eval(n.a), b = Eval(n.b);
        if (b.v == 0) Fail(n.col, "division by zero");
        return Real(a.v / b.v);
      }
      case NodeOp::kOr:
      case NodeOp::kAnd:
      case NodeOp::kEor: {
        int64_t a = Trunc(Eval(n.a).v, n.col), b = Trunc(Eval(n.b).v, n.col);
        int64_t r = n.op == NodeOp::kOr ? (a | b) : n.op == NodeOp::kAnd ? (a & b) : (a ^ b);
        return Int(static_cast<double>(r));
      }
      case NodeOp::kLt:
      case NodeOp::kLe:
      case NodeOp::kEq:
      case NodeOp::kNe:
      case NodeOp::kGt:
      case NodeOp::kGe: {
        double a = Eval(n.a).v, b = Eval(n.b).v;
        // Values written to 8 digits compare equal when they agree to the 8th digit (0.1+0.2 EQ 0.3).
        const double tol = 1e-9 * std::max({1.0, std::fabs(a), std::fabs(b)});
        bool eq = std::fabs(a - b) <= tol;
        bool r = false;
        switch (n.op) {
          case NodeOp::kLt:
            r = a < b && !eq;
            break;
          case NodeOp::kLe:
            r = a < b || eq;
            break;
          case NodeOp::kEq:
            r = eq;
            break;
          case NodeOp::kNe:
            r = !eq;
            break;
          case NodeOp::kGt:
            r = a > b && !eq;
            break;
          default:
            r = a > b || eq;
            break;
        }
        return Int(r ? 1 : 0);
      }
      case NodeOp::kFn:
        return Function(n);
    }
    return {};
  }

 private:
  double Angle(const Value& a) const { return (vars_.MicronUnits() && a.integer) ? a.v / 1000.0 : a.v; }
  double AngleOut(double deg) const { return vars_.MicronUnits() ? deg * 1000.0 : deg; }

  Value Function(const Node& n) {
    Value a = Eval(n.a);
    const double unit = vars_.SettingUnit();
    switch (n.fn) {
      case Fn::kSin:
        return Real(std::sin(Angle(a) * kDeg));
      case Fn::kCos:
        return Real(std::cos(Angle(a) * kDeg));
      case Fn::kTan: {
        double c = std::cos(Angle(a) * kDeg);
        if (std::fabs(c) < 1e-12) Fail(n.col, "TAN of 90 degrees");
        return Real(std::sin(Angle(a) * kDeg) / c);
      }
      case Fn::kAtan:
        return Real(AngleOut(std::atan(a.v) / kDeg));
      case Fn::kAtan2: {
        Value b = Eval(n.b);
        if (a.v == 0 && b.v == 0) Fail(n.col, "ATAN2[0,0] is undefined");
        return Real(AngleOut(std::atan2(a.v, b.v) / kDeg));
      }
      case Fn::kSqrt:
        if (a.v < 0) Fail(n.col, "SQRT of a negative value");
        return Real(std::sqrt(a.v));
      case Fn::kAbs:
        return Real(std::fabs(a.v));
      case Fn::kBin:
        return Int(static_cast<double>(Bcd2Bin(Trunc(a.v, n.col), n.col)));
      case Fn::kBcd:
        return Int(static_cast<double>(Bin2Bcd(Trunc(a.v, n.col), n.col)));
      case Fn::kRound:
        return Int(RoundAway(a.v));
      case Fn::kFix:
        return Int(TruncSnap(a.v));
      case Fn::kFup:
        return Int(RaiseAway(a.v));
      case Fn::kDround:
        return Real(RoundAway(a.v / unit) * unit);
      case Fn::kDfix:
        return Real(TruncSnap(a.v / unit) * unit);
      case Fn::kDfup:
        return Real(RaiseAway(a.v / unit) * unit);
      case Fn::kMod: {
        Value b = Eval(n.b);
        if (b.v == 0) Fail(n.col, "MOD by zero");
        double r = a.v - TruncSnap(a.v / b.v) * b.v;
        return {r, a.integer && b.integer};
      }
    }
    return {};
  }

  const std::vector<Node>& pool_;
  VarReader& vars_;
};

}  // namespace

Value Evaluate(const std::vector<Node>& pool, int32_t root, VarReader& vars) {
  Evaluator e(pool, vars);
  Value v = e.Eval(root);
  if (!std::isfinite(v.v)) Fail(pool[static_cast<size_t>(root)].col, "the expression has no finite value");
  return v;
}

}  // namespace cell::interp::okuma
