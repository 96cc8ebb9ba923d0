// The Okuma tape format (manual SECTION 1, seed ln 488-715; SECTION 13 ln 7414-7472, 7924-7950, 8029-8229):
// blocks, sequence names, words and extended addresses, assignments, control statements.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "block.h"

namespace cell::interp::okuma {
namespace {

bool IsBlank(char c) {
  return c == ' ' || c == '\t';
}

// Extended addresses that take a value (ln 537, 1537, 1871, 2075, 3933, 4234, 5121, 1612).
bool IsExtendedAddress(std::string_view n) {
  if (n.size() != 2) return false;  // every block's two-letter names pass here: no string compares
  switch (MakeAddr(n[0], n[1])) {
    case MakeAddr('S', 'A'):
    case MakeAddr('S', 'B'):
    case MakeAddr('Q', 'A'):
    case MakeAddr('D', 'A'):
    case MakeAddr('D', 'B'):
    case MakeAddr('F', 'A'):
    case MakeAddr('F', 'B'):
    case MakeAddr('X', 'A'):
    case MakeAddr('X', 'B'):
    case MakeAddr('Z', 'A'):
    case MakeAddr('Z', 'B'):
    case MakeAddr('P', 'Z'):
    case MakeAddr('P', 'W'):
      return true;
    default:
      return false;
  }
}

class Lexer {
 public:
  Lexer(std::string_view s, Block& b) : s_(s), b_(b) {}

  void Run() {
    Blanks();
    if (i_ < s_.size() && s_[i_] == '/') {
      b_.deleted = true;
      ++i_;
      Blanks();
    }
    if (i_ < s_.size() && Up(s_[i_]) == 'N' && i_ + 1 < s_.size() && IsAlnumC(s_[i_ + 1])) Sequence();
    Blanks();
    if (i_ < s_.size() && s_[i_] == '/') {
      if (b_.deleted) Error("block delete '/' given twice");
      b_.deleted = true;
      ++i_;
      Blanks();
    }
    if (i_ < s_.size() && Up(s_[i_]) == 'O' && b_.seq.empty() && !b_.deleted) {
      std::string name = ProgramNameOf(s_.substr(i_));
      if (!name.empty()) {
        b_.stmt = Stmt::kProgramName;
        b_.program = name;
        b_.program_col = Col();
        return;
      }
    }
    if (Statement()) return;
    Items();
  }

 private:
  int Col() const { return static_cast<int>(i_) + 1; }
  [[noreturn]] void Error(const std::string& text) const { Fail(Col(), text); }
  [[noreturn]] void ErrorAt(size_t at, const std::string& text) const {
    Fail(static_cast<int>(at) + 1, text);
  }

  void Blanks() {
    while (i_ < s_.size() && IsBlank(s_[i_])) ++i_;
  }
  bool AtEnd() {
    Blanks();
    while (i_ < s_.size() && s_[i_] == '(') Comment();
    return i_ >= s_.size();
  }
  void Comment() {
    size_t close = s_.find(')', i_);
    if (close == std::string_view::npos) Error("comment '(' is not closed by ')'");
    i_ = close + 1;
    Blanks();
  }
  std::string Run(bool alnum) {
    size_t start = i_;
    while (i_ < s_.size() && (alnum ? IsAlnumC(s_[i_]) : IsLetter(s_[i_]))) ++i_;
    std::string out(s_.substr(start, i_ - start));
    for (char& c : out) c = Up(c);
    return out;
  }

  // A sequence name: N and up to five letters or digits (a name with letters begins with a letter), then a
  // blank or a tab (ln 508-525, 7455-7472).
  void Sequence() {
    b_.seq_col = Col();
    std::string name = Run(true);
    std::string_view rest = std::string_view(name).substr(1);
    bool ok = !rest.empty() && rest.size() <= 5 &&
              (std::all_of(rest.begin(), rest.end(), IsDigit) || IsLetter(rest[0]));
    if (!ok) {
      Fail(b_.seq_col, fmt::format("sequence name {}: N and at most five letters or digits (a name with "
                                   "letters begins with a letter), followed by a space or tab",
                                   name));
    }
    if (i_ < s_.size() && !IsBlank(s_[i_]) && s_[i_] != '(') {
      Fail(b_.seq_col, fmt::format("sequence name {} must be followed by a space or tab", name));
    }
    b_.seq = name;
  }

  bool Keyword(std::string_view kw, bool needs_blank) {
    // Every block tries each keyword: the first letter rejects nearly all of them at once.
    if (s_.size() - i_ < kw.size() || Up(s_[i_]) != kw[0]) return false;
    for (size_t k = 1; k < kw.size(); ++k) {
      if (Up(s_[i_ + k]) != kw[k]) return false;
    }
    size_t end = i_ + kw.size();
    if (end < s_.size() && IsAlnumC(s_[end])) return false;
    if (end < s_.size() && s_[end] == '=') return false;  // an assignment to a name (caught later)
    if (needs_blank && end < s_.size() && !IsBlank(s_[end]) && s_[end] != '(') {
      Fail(Col(), fmt::format("{} must be followed by a space or tab", kw));
    }
    b_.stmt_col = Col();
    i_ = end;
    return true;
  }

  std::string Label() {
    Blanks();
    if (i_ >= s_.size() || Up(s_[i_]) != 'N') Error("sequence name (N...) expected");
    b_.label_col = Col();
    std::string name = Run(true);
    if (name.size() < 2 || name.size() > 6) Fail(b_.label_col, fmt::format("bad sequence name {}", name));
    return name;
  }

  // CALL's repeat count (later OSP controls; the E100L figure is lost, ln 7966), written as PSELECT's Q (ln
  // 8855-8862): "Q=n", "Q n" or "Qn", n 1-9999 as digits. A local variable's name has two letters at least
  // (ln 7585), so "Q" with digits is no variable. False when the name is not Q or Q and digits.
  bool RepeatCount(const std::string& name, size_t at) {
    std::string digits = name.substr(1);
    if (!digits.empty() && !std::all_of(digits.begin(), digits.end(), IsDigit)) return false;
    Blanks();
    if (digits.empty() && i_ < s_.size() && s_[i_] == '=') {
      ++i_;
      Blanks();
    }
    if (digits.empty()) {
      size_t start = i_;
      while (i_ < s_.size() && IsDigit(s_[i_])) ++i_;
      digits = std::string(s_.substr(start, i_ - start));
      if (digits.empty()) ErrorAt(at, "CALL ... Q: the repeat count (1-9999) expected after Q");
    }
    if (b_.repeat != 1) ErrorAt(at, "CALL: Q (the repeat count) given twice");
    if (digits.size() > 4 || std::stoi(digits) < 1) ErrorAt(at, "CALL ... Q: the repeat count is 1-9999");
    b_.repeat = std::stoi(digits);
    Blanks();
    return true;
  }

  std::string ProgramArg() {
    Blanks();
    b_.program_col = Col();
    if (i_ >= s_.size() || Up(s_[i_]) != 'O') Error("program name (O...) expected");
    std::string name = Run(true);
    if (ProgramNameOf(name).empty()) {
      Fail(b_.program_col, fmt::format("bad program name {}: O and 1-4 letters or digits, all digits or "
                                       "beginning with a letter",
                                       name));
    }
    return name;
  }

  void ExpectEnd(std::string_view what) {
    if (!AtEnd()) Error(fmt::format("unexpected text after {}", what));
  }

  bool Statement() {
    // Only the keywords that begin with the block's first letter are tried (most blocks begin with none).
    const char c0 = i_ < s_.size() ? Up(s_[i_]) : '\0';
    if (c0 == 'N' && Keyword("NOEX", true)) {
      b_.noex = true;
      b_.stmt_col = 1;
      Blanks();
      if (Statement()) return true;
      Items();
      return true;
    }
    if (c0 == 'G' && Keyword("GOTO", true)) {
      b_.stmt = Stmt::kGoto;
      b_.label = Label();
      ExpectEnd("the GOTO target");
      return true;
    }
    if (c0 == 'I' && Keyword("IF", false)) {
      b_.stmt = Stmt::kIf;
      Blanks();
      if (i_ < s_.size() && s_[i_] == '[') {
        ExprParser p(s_, i_, b_.pool);
        b_.cond = p.Parse();
        i_ = p.pos();
      } else {
        size_t at = i_;
        std::string name = Run(true);
        if (!IsLocalName(name)) {
          ErrorAt(at, "IF needs [condition] or a local variable name");
        }
        b_.defined = name;
      }
      Blanks();
      if (Keyword("GOTO", true)) Blanks();
      b_.label = Label();
      ExpectEnd("the IF target");
      return true;
    }
    if ((c0 == 'C' && Keyword("CALL", true)) || (c0 == 'M' && Keyword("MODIN", true))) {
      b_.stmt = Up(s_[b_.stmt_col - 1]) == 'C' ? Stmt::kCall : Stmt::kModin;
      b_.program = ProgramArg();
      // Arguments: assignments registered when the subprogram is called (ln 8029-8042).
      while (!AtEnd()) {
        size_t at = i_;
        if (!IsLetter(s_[i_])) Error("variable=value expected");
        std::string name = Run(true);
        if (b_.stmt == Stmt::kCall && name[0] == 'Q' && RepeatCount(name, at)) continue;
        Assignment(name, at);
      }
      return true;
    }
    if (c0 == 'R' && Keyword("RTS", true)) {
      b_.stmt = Stmt::kRts;
      ExpectEnd("RTS");
      return true;
    }
    if (c0 == 'M' && Keyword("MODOUT", true)) {
      b_.stmt = Stmt::kModout;
      ExpectEnd("MODOUT");
      return true;
    }
    if ((c0 == 'R' && Keyword("READ", true)) || (c0 == 'W' && Keyword("WRITE", true))) {
      b_.stmt = Up(s_[b_.stmt_col - 1]) == 'R' ? Stmt::kRead : Stmt::kWrite;
      Blanks();
      if (i_ >= s_.size() || !IsDigit(s_[i_])) Error("RS232C channel number expected");
      int n = 0;
      while (i_ < s_.size() && IsDigit(s_[i_])) n = std::min(99, n * 10 + (s_[i_++] - '0'));
      b_.channel = n;
      ExpectEnd("the channel");
      return true;
    }
    if ((c0 == 'G' && Keyword("GET", true)) || (c0 == 'P' && Keyword("PUT", true))) {
      b_.stmt = Up(s_[b_.stmt_col - 1]) == 'G' ? Stmt::kGet : Stmt::kPut;
      GetPut();
      return true;
    }
    if (c0 != 'P' && c0 != 'V' && c0 != 'E') return false;  // most blocks: no schedule keyword to try
    for (std::string_view kw : {"PSELECT", "VSET", "END"}) {
      if (c0 == kw[0] && Keyword(kw, kw != "END")) {
        b_.stmt = Stmt::kSchedule;
        b_.stmt_word = std::string(kw);
        i_ = s_.size();
        return true;
      }
    }
    return false;
  }

  // GET var,c / GET ,c; PUT var,c / PUT ,c / PUT 'text' / PUT ^'text' / PUT $hex (ln 8115-8153).
  void GetPut() {
    Blanks();
    bool put = b_.stmt == Stmt::kPut;
    if (put && i_ < s_.size() && (s_[i_] == '\'' || s_[i_] == '^' || s_[i_] == '$')) {
      b_.put_text = true;
      if (s_[i_] == '$') {
        ++i_;
        b_.put = Hex();
      } else {
        b_.put = String();
      }
      if (b_.put.size() > 16) Error("PUT text: at most 16 characters");
      ExpectEnd("the PUT text");
      return;
    }
    if (i_ < s_.size() && s_[i_] != ',') {
      size_t at = i_;
      if (!IsLetter(s_[i_])) Error("variable expected");
      std::string name = Run(true);
      Variable(name, at);
      b_.has_var = true;
      Blanks();
    }
    if (i_ < s_.size() && s_[i_] == ',') {
      ++i_;
      ExprParser p(s_, i_, b_.pool);
      b_.count = p.Parse();
      i_ = p.pos();
    } else {
      Error(fmt::format("{} needs ',count'", put ? "PUT" : "GET"));
    }
    ExpectEnd(put ? "PUT" : "GET");
  }

  std::string Hex() {
    std::string out;
    size_t start = i_;
    while (i_ + 1 < s_.size() && std::isxdigit(static_cast<unsigned char>(s_[i_])) &&
           std::isxdigit(static_cast<unsigned char>(s_[i_ + 1]))) {
      out.push_back(static_cast<char>(std::stoi(std::string(s_.substr(i_, 2)), nullptr, 16)));
      i_ += 2;
    }
    if (i_ == start || (i_ < s_.size() && std::isxdigit(static_cast<unsigned char>(s_[i_])))) {
      ErrorAt(start, "hexadecimal text: pairs of hexadecimal digits expected");
    }
    for (char c : out) {
      if (c == 0 || c == '%') ErrorAt(start, "NULL or % in hexadecimal text");
    }
    return out;
  }

  // 'TEXT', ^'text' (lower case) or '$41424344' (ln 7814-7882, 8146-8147).
  std::string String() {
    bool lower = false;
    if (s_[i_] == '^') {
      lower = true;
      ++i_;
      Blanks();
    }
    if (i_ >= s_.size() || s_[i_] != '\'') Error("' expected");
    size_t open = i_++;
    size_t close = s_.find('\'', i_);
    if (close == std::string_view::npos) ErrorAt(open, "character string not closed by '");
    std::string_view body = s_.substr(i_, close - i_);
    i_ = close + 1;
    std::string out;
    if (!body.empty() && body[0] == '$') {
      std::string_view hex = body.substr(1);
      if (hex.size() % 2 != 0 || hex.empty() || hex.size() > 8)
        ErrorAt(open, "hexadecimal text: at most four pairs of digits");
      for (size_t k = 0; k < hex.size(); k += 2) {
        if (!std::isxdigit(static_cast<unsigned char>(hex[k])) ||
            !std::isxdigit(static_cast<unsigned char>(hex[k + 1])))
          ErrorAt(open, "hexadecimal text: digits 0-9, A-F");
        out.push_back(static_cast<char>(std::stoi(std::string(hex.substr(k, 2)), nullptr, 16)));
      }
      return out;
    }
    for (char c : body) {
      out.push_back(lower && c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c);
    }
    return out;
  }

  // The left side of an assignment or a GET/PUT variable: V1-V200, a system variable with its [suffix], or a
  // local variable.
  void Variable(const std::string& name, size_t at) {
    // Built in place (an Assign holds a string: no temporary moved in). A refused name leaves it half made,
    // with the block that is refused.
    Assign& a = b_.assigns.emplace_back();
    a.col = static_cast<int>(at) + 1;
    if (name[0] == 'V' && name.size() > 1 && std::all_of(name.begin() + 1, name.end(), IsDigit)) {
      int n = 0;  // V and at most three digits, else out of range
      if (name.size() <= 4) {
        for (size_t k = 1; k < name.size(); ++k) n = n * 10 + (name[k] - '0');
      }
      if (n < 1 || n > 200)
        ErrorAt(at, fmt::format("common variable {}: common variables are V1-V200", name));
      a.kind = VarKind::kCommon;
      a.common = n;
    } else if (name[0] == 'V') {
      if (!IsSystemVariable(name)) ErrorAt(at, fmt::format("illegal system variable name {}", name));
      a.kind = VarKind::kSystem;
      a.name = PackName(name);
      if (i_ < s_.size() && s_[i_] == '[') {
        ++i_;
        ExprParser p(s_, i_, b_.pool);
        a.index = p.Parse();
        i_ = p.pos();
        Blanks();
        if (i_ >= s_.size() || s_[i_] != ']') Error(fmt::format("']' expected after the {} suffix", name));
        ++i_;
      }
    } else {
      if (!IsLocalName(name)) {
        ErrorAt(at, IsReservedName(name)
                        ? fmt::format("{} cannot be a local variable name", name)
                        : fmt::format("'{}' is not a variable name (local variables: two letters, then up to "
                                      "two letters or digits)",
                                      name));
      }
      a.kind = VarKind::kLocal;
      a.name = PackName(name);
    }
    b_.items.push_back({true, static_cast<uint16_t>(b_.assigns.size() - 1)});
  }

  void Assignment(const std::string& name, size_t at) {
    Variable(name, at);
    Blanks();
    if (i_ >= s_.size() || s_[i_] != '=') ErrorAt(at, fmt::format("'=' expected after {}", name));
    ++i_;
    Blanks();
    Assign& a = b_.assigns.back();
    if (i_ < s_.size() && (s_[i_] == '\'' || s_[i_] == '^')) {
      if (a.kind != VarKind::kSystem || UnpackName(a.name) != "VUACM")
        Error("a character string can only be assigned to VUACM");
      a.is_string = true;
      a.text = String();
      return;
    }
    ExprParser p(s_, i_, b_.pool);
    a.value = p.Parse();
    i_ = p.pos();
  }

  void Items() {
    Blanks();
    first_item_ = i_;
    while (!AtEnd()) {
      const size_t at = i_;
      const char c = Up(s_[i_]);
      if (c == '/')
        Error("block delete '/' is allowed only at the start of a block or after its sequence name");
      if (!IsLetter(c)) Error(fmt::format("unexpected character '{}'", s_[i_]));
      const bool two_letters = i_ + 1 < s_.size() && IsLetter(s_[i_ + 1]);
      if (c == 'N' && i_ + 1 < s_.size() && IsAlnumC(s_[i_ + 1])) {
        // A sequence name as an argument (G85-G88 N...).
        if (!b_.label.empty()) Error("only one sequence name argument per block");
        b_.label = Label();
        continue;
      }
      if (c == 'O') Error("a program name must stand alone in its block");
      if (c == 'V' || two_letters) {
        std::string name = Run(true);
        const size_t after_name = i_;
        Blanks();
        const bool assign = i_ < s_.size() && (s_[i_] == '=' || (name[0] == 'V' && s_[i_] == '['));
        if (!assign && name == "CALRG") {
          b_.calrg = true;
          b_.calrg_col = static_cast<int>(at) + 1;
          continue;
        }
        if (IsExtendedAddress(name)) {
          if (!assign) ErrorAt(at, fmt::format("extended address {} needs '=' before its value", name));
          ++i_;
          Word w;
          w.addr = MakeAddr(name[0], name[1]);
          w.col = static_cast<int>(at) + 1;
          WordValue(w, true);
          continue;
        }
        if (!assign) {
          static constexpr std::string_view kStatements[] = {"GOTO",  "IF",     "CALL",    "RTS",
                                                             "MODIN", "MODOUT", "READ",    "WRITE",
                                                             "GET",   "PUT",    "PSELECT", "VSET"};
          for (std::string_view kw : kStatements) {
            if (name == kw) {
              ErrorAt(at, fmt::format("{} must be at the start of the block or right after its sequence name",
                                      name));
            }
            if (name.size() > kw.size() && name.compare(0, kw.size(), kw) == 0 && kw.size() > 2 &&
                at == first_item_) {
              ErrorAt(at, fmt::format("{} must be followed by a space or tab", kw));
            }
          }
          ErrorAt(at, fmt::format("unknown word {}", name));
        }
        i_ = after_name;
        Assignment(name, at);
        continue;
      }
      ++i_;
      Word w;
      w.addr = MakeAddr(c);
      w.col = static_cast<int>(at) + 1;
      if (i_ < s_.size() && s_[i_] == '=') {
        ++i_;
        WordValue(w, true);
      } else {
        WordValue(w, false);
      }
    }
  }

  // The value of a word: a literal number (the 8-digit rule, ln 1095-1100), an expression after '=', or,
  // leniently, an expression written without '=' as in the manual's own listings (X[200-V1]*SIN[35],
  // Z100-PCH, X100+V1).
  void WordValue(Word& w, bool expr) {
    if (!expr) {
      Blanks();
      if (i_ < s_.size() && s_[i_] == '[') expr = true;
    }
    auto expression_from = [&](size_t from) {
      ExprParser p(s_, from, b_.pool);
      w.expr = true;
      w.node = p.Parse();
      i_ = p.pos();
      Push(w);
    };
    if (expr) return expression_from(i_);
    size_t start = i_;
    bool neg = false;
    if (i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-')) {
      neg = s_[i_] == '-';
      ++i_;
    }
    // A sign and a bracket: E-67's X-[200-V1]*SIN[35].
    if (i_ < s_.size() && s_[i_] == '[' && i_ > start) return expression_from(start);
    const Decimal d = ReadDecimal(s_, i_);
    if (d.point && i_ < s_.size() && s_[i_] == '.') Error("two decimal points in a number");
    w.point = d.point;
    const double v = d.v;
    const int digits = d.digits, written = d.written;
    if (written == 0) {
      Fail(w.col, fmt::format("number expected after {}", AddrName(w.addr)));
    }
    if (i_ < s_.size() &&
        (s_[i_] == '+' || s_[i_] == '-' || s_[i_] == '*' || s_[i_] == '/' || s_[i_] == '[')) {
      ExprParser p(s_, start, b_.pool);
      w.expr = true;
      w.node = p.Parse();
      i_ = p.pos();
      Push(w);
      return;
    }
    if (digits > 8) Fail(w.col, fmt::format("{} has more than 8 digits", AddrName(w.addr)));
    w.digits = std::max(digits, written);
    w.num = neg ? -v : v;
    Push(w);
  }

  void Push(const Word& w) {
    b_.words.push_back(w);
    b_.items.push_back({false, static_cast<uint16_t>(b_.words.size() - 1)});
  }

  std::string_view s_;
  Block& b_;
  size_t i_ = 0;
  size_t first_item_ = 0;  // where a control statement would stand
};

}  // namespace

std::string AddrName(Addr a) {
  std::string out(1, static_cast<char>(a & 0xff));
  if (a >> 8) out.push_back(static_cast<char>(a >> 8));
  return out;
}

void Block::Clear() {
  text.clear();
  segments.clear();
  deleted = false;
  seq.clear();
  seq_col = 1;
  noex = false;
  stmt = Stmt::kNone;
  stmt_col = 1;
  stmt_word.clear();
  words.clear();
  assigns.clear();
  items.clear();
  pool.clear();
  label.clear();
  label_col = 1;
  program.clear();
  program_col = 1;
  repeat = 1;
  cond = -1;
  defined.clear();
  channel = 0;
  has_var = false;
  count = -1;
  put_text = false;
  put.clear();
  calrg = false;
  calrg_col = 1;
}

void Block::Locate(int col, int first_line, int* line, int* out_col) const {
  *line = first_line;
  *out_col = col;
  if (segments.empty()) return;
  size_t off = static_cast<size_t>(std::max(col, 1) - 1);
  for (auto it = segments.rbegin(); it != segments.rend(); ++it) {
    if (off >= it->offset) {
      *line = it->line;
      *out_col = static_cast<int>(off - it->offset) + it->col0;
      return;
    }
  }
}

void ParseBlock(std::string_view s, Block& b) {
  Lexer(s, b).Run();
}

std::string ProgramNameOf(std::string_view block) {
  size_t paren = block.find('(');
  std::string_view s = block.substr(0, paren);
  while (!s.empty() && IsBlank(s.back())) s.remove_suffix(1);
  while (!s.empty() && IsBlank(s.front())) s.remove_prefix(1);
  if (s.size() < 2 || s.size() > 5 || Up(s[0]) != 'O') return {};
  std::string out(s);
  for (char& c : out) c = Up(c);
  std::string_view rest = std::string_view(out).substr(1);
  if (std::all_of(rest.begin(), rest.end(), IsDigit)) return out;
  if (!IsLetter(rest[0]) || !std::all_of(rest.begin(), rest.end(), IsAlnumC)) return {};
  return out;
}

}  // namespace cell::interp::okuma
