// Okuma User Task expressions (manual SECTION 13, seed ln 582-617, 7924-7950, 8280-8474): constants (integer,
// real, $hex), common variables V1-V200, local variables, system variables with a [suffix], + - * /, the
// comparisons LT LE EQ NE GT GE, the boolean operators OR AND EOR NOT, the functions SIN ... MOD, and [ ]
// grouping. A block's expressions are parsed once into a small tree (a pool of nodes per block) and
// evaluated each time the block runs.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "cell/interp/run_error.h"
#include "cell/interp/scan.h"

namespace cell::interp::okuma {

// Program errors: RunError and Fail (cell/interp/run_error.h), `alarm` the manual's alarm number where it
// has one.

// Character classes of the tape (ASCII; lower case is read as upper case, ln 540-715).
inline bool IsLetter(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
}
using scan::IsDigit;
inline bool IsAlnumC(char c) {
  return IsLetter(c) || IsDigit(c);
}
inline char Up(char c) {
  return (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : c;
}

// An unsigned decimal constant at s[i] (digits and at most one point), as a word and an expression read it:
// its value, its digits as the 8-digit rule counts them (not the whole part's leading zeros, ln 1095-1100),
// the digits written, whether it has a point. `i` is left after it, on a second point when there is one (a
// number the caller refuses). The whole part is summed as an integer: up to 15 digits every partial sum is
// exact in a double too, so the value is the one summing in doubles gives (a longer one is summed so).
struct Decimal {
  double v = 0;
  int digits = 0;
  int written = 0;
  bool point = false;
};
inline Decimal ReadDecimal(std::string_view s, size_t& at) {
  // Locals throughout, `at` and the result written once: this runs for every number of every block.
  const char* p = s.data();
  const size_t n = s.size();
  size_t i = at;
  while (i < n && p[i] == '0') ++i;
  const size_t first = i;
  uint64_t whole = 0;
  for (; i < n && IsDigit(p[i]); ++i) whole = whole * 10 + static_cast<uint64_t>(p[i] - '0');
  int digits = static_cast<int>(i - first);
  int written = static_cast<int>(i - at);
  double v = 0;
  if (digits <= 15) {
    v = static_cast<double>(whole);
  } else {
    for (size_t k = first; k < i; ++k) v = v * 10 + (p[k] - '0');
  }
  bool point = false;
  if (i < n && p[i] == '.') {
    point = true;
    double scale = 0.1;
    const size_t frac = ++i;
    for (; i < n && IsDigit(p[i]); ++i) {
      v += (p[i] - '0') * scale;
      scale /= 10;
    }
    digits += static_cast<int>(i - frac);
    written += static_cast<int>(i - frac);
  }
  at = i;
  return {v, digits, written, point};
}

// Names (variables, system variables) packed into one integer: up to 8 upper-case characters.
uint64_t PackName(std::string_view name);
std::string UnpackName(uint64_t packed);

// The manual's data types (ln 8343-8446): integers stay integers through + and -, everything else is real;
// comparisons give a logical 0/1 (held as an integer).
struct Value {
  double v = 0;
  bool integer = false;
};

enum class Fn : uint8_t {
  kSin,
  kCos,
  kTan,
  kAtan,
  kAtan2,
  kSqrt,
  kAbs,
  kBin,
  kBcd,
  kRound,
  kFix,
  kFup,
  kDround,
  kDfix,
  kDfup,
  kMod,
};

enum class NodeOp : uint8_t {
  kNum,
  kCommon,  // V1-V200 (num = the number)
  kLocal,   // name
  kSystem,  // name, a = suffix expression or -1
  kNeg,
  kNot,
  kAdd,
  kSub,
  kMul,
  kDiv,
  kOr,
  kAnd,
  kEor,
  kLt,
  kLe,
  kEq,
  kNe,
  kGt,
  kGe,
  kFn,  // fn, a (and b for ATAN2 and MOD)
};

struct Node {
  NodeOp op = NodeOp::kNum;
  Fn fn = Fn::kSin;
  bool integer = false;  // kNum: written without a decimal point
  int32_t a = -1, b = -1;
  double num = 0;
  uint64_t name = 0;
  int col = 1;  // 1-based column in the block
};

// Where an expression reads its variables. Every call may throw RunError (undefined local variable, ...).
class VarReader {
 public:
  virtual ~VarReader() = default;
  virtual double Common(int n, int col) = 0;
  virtual double Local(uint64_t name, int col) = 0;
  virtual Value System(uint64_t name, const Value* index, int col) = 0;
  // 1 um unit system: trigonometric arguments written as integers are 1/1000 degree, ATAN results x1000.
  virtual bool MicronUnits() const { return false; }
  // DROUND/DFIX/DFUP's setting unit (0.001 mm, 0.0001 inch).
  virtual double SettingUnit() const { return 0.001; }
};

// Known system variable names (appendix "Table of System Variables", seed ln 9882-10087, plus the I/O
// variables VDIN VDOUT VIRD VORD).
bool IsSystemVariable(std::string_view name);
// Function names, comparison and boolean operators and extended addresses: names a local variable may not
// take (ln 7593-7603).
bool IsReservedName(std::string_view name);
// A legal local variable name: a letter, a letter, up to two letters or digits, not starting with O, N or V
// (ln 7586-7590).
bool IsLocalName(std::string_view name);

// Parses one expression of the block text `s` starting at `pos` (1-based column of s[0] is `col0`). The
// expression ends where the block's next item begins: at a blank (outside brackets) that is not followed by
// an operator, at a comment, or at the end of the text. Nodes are appended to `pool`; returns the root.
class ExprParser {
 public:
  ExprParser(std::string_view s, size_t pos, std::vector<Node>& pool, int col0 = 1)
      : s_(s), pos_(pos), pool_(pool), col0_(col0) {}
  int32_t Parse();
  size_t pos() const { return pos_; }

 private:
  int32_t Or();
  int32_t And();
  int32_t Compare();
  int32_t Sum();
  int32_t Product();
  int32_t Binary(NodeOp op, int32_t a, int32_t b, int col);  // adds the node a op b
  // The operand is a template argument: a direct call the compiler can inline (this runs for every operand).
  template <int32_t (ExprParser::*operand)()>
  int32_t LeftAssociative(char c1, NodeOp op1, char c2, NodeOp op2);
  int32_t Unary();
  int32_t Primary();
  int32_t Number(int col);  // an unsigned constant at pos_ (its first character is a digit or '.')
  int32_t Simple();
  int32_t SimpleOperand();
  int32_t Add(Node n);
  void SkipBlanks();
  bool AtOperatorAfterBlanks();
  std::string_view PeekWord() const;
  bool AcceptWord(std::string_view w);
  // The next non-blank word is a word operator (OR, AND, EOR, LT ... GE) standing alone: AcceptWord can
  // only succeed there, so the operator levels test this once instead of trying each word.
  bool WordOperatorAfterBlanks() const;
  int Col() const { return static_cast<int>(pos_) + col0_; }
  [[noreturn]] void Error(const std::string& text) const;

  std::string_view s_;
  size_t pos_;
  std::vector<Node>& pool_;
  int col0_;
  int depth_ = 0;  // bracket depth: blanks inside brackets never end the expression
};

Value Evaluate(const std::vector<Node>& pool, int32_t root, VarReader& vars);

// The manual's integer conversions (ln 611-617, 8448-8474): ROUND rounds half away from zero, FIX
// truncates, FUP raises away from zero; DROUND/DFIX/DFUP do the same to `unit`.
// Values within 1e-9 (relative) of a whole number are that number (0.3/0.1 is 3, not 2.999...).
double Snap(double v);
double RoundAway(double v);
double RaiseAway(double v);
double TruncSnap(double v);

}  // namespace cell::interp::okuma
