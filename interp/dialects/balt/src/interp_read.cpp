// The Balt-System tape format (manual §5.3-5.7, ln 2314-2502): prefixes '/', "label", N, '#'/'&'; the four
// block types (comment ';', ISO words, assignments, three-letter commands in brackets); upper-case ISO
// addresses and lower-case GTL / corner / paraxial words; an address without a number is 0; implicit values
// "XE32".
#include <fmt/format.h>

#include <array>
#include <cstdint>

#include "interp_internal.h"

namespace cell::interp::balt {

namespace {

bool IsAlnum(char c) {
  return IsDigit(c) || IsUpper(c) || IsLower(c);
}

// Table 5.1 (ln 2350-2369), plus 'b' (the bevel word, ln 3190) and '@' (K14 execution, ln 4203).
constexpr bool Allowed(char c) {
  if ((c >= '0' && c <= '9') || (c >= 'A' && c <= 'Z')) return true;
  switch (c) {
    case 'a':
    case 'b':
    case 'c':
    case 'd':
    case 'l':
    case 'm':
    case 'o':
    case 'p':
    case 'r':
    case 's':
    case 't':
    case 'u':
    case 'v':
    case 'w':
    case '+':
    case '-':
    case '*':
    case '/':
    case '.':
    case '"':
    case '(':
    case ')':
    case ';':
    case ',':
    case '=':
    case ':':
    case '#':
    case '&':
    case '@':
    case ' ':
    case '\t':
      return true;
    default:
      return false;
  }
}

class Reader {
 public:
  explicit Reader(std::string_view s) : s_(s) {}
  bool End() const { return i_ >= s_.size(); }
  char Peek(std::size_t k = 0) const { return i_ + k < s_.size() ? s_[i_ + k] : '\0'; }
  void Skip() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\t')) ++i_;
  }
  int Col() const { return static_cast<int>(i_) + 1; }
  std::size_t pos() const { return i_; }
  void Advance(std::size_t k = 1) { i_ += k; }
  std::string_view Rest() const { return s_.substr(i_); }

  // A value after an address: [sign] (number | E<n> | E(<n>) | E(E<n>)) or nothing.
  Val Value() {
    Val v;
    Skip();
    if (Peek() == '+' || Peek() == '-') {
      v.neg = Peek() == '-';
      Advance();
      Skip();
    }
    if (Peek() == 'E' && (IsDigit(Peek(1)) || Peek(1) == '(')) {
      int col = Col();
      Advance();
      if (Peek() == '(') {
        Advance();
        Skip();
        // "n can be a number or an E parameter" (ln 5435): E(25) is E25, its range checked where it is used.
        if (IsDigit(Peek())) {
          v.kind = Val::kParam;
        } else {
          if (Peek() != 'E' || !IsDigit(Peek(1)))
            Fail(col, 11, "E(n) needs a number or a byte or integer E parameter");
          Advance();
          v.kind = Val::kIndirect;
        }
        v.param = Digits(col);
        Skip();
        if (Peek() != ')') Fail(col, 11, "closing bracket missing in E(En)");
        Advance();
      } else {
        v.kind = Val::kParam;
        v.param = Digits(col);
      }
      return v;
    }
    if (IsDigit(Peek()) || (Peek() == '.' && IsDigit(Peek(1)))) {
      v.kind = Val::kNum;
      double n = 0;
      int digits = 0;
      while (IsDigit(Peek())) {
        n = n * 10 + (Peek() - '0');
        Advance();
        if (++digits > 12) Fail(Col(), 13, "too many digits");
      }
      if (Peek() == '.') {
        v.point = true;
        Advance();
        double scale = 0.1;
        int frac_digits = 0;
        v.frac = 0;
        while (IsDigit(Peek())) {
          n += (Peek() - '0') * scale;
          if (frac_digits < 8) v.frac = v.frac * 10 + (Peek() - '0');
          scale /= 10;
          Advance();
          if (++frac_digits > 8) Fail(Col(), 13, "too many decimals");
        }
      }
      v.num = n;
    }
    return v;
  }

  int Digits(int col) {
    if (!IsDigit(Peek())) Fail(col, 11, "digits expected");
    long n = 0;
    while (IsDigit(Peek())) {
      n = n * 10 + (Peek() - '0');
      if (n > 99999) Fail(col, 18, "index too large");
      Advance();
    }
    return static_cast<int>(n);
  }

 private:
  std::string_view s_;
  std::size_t i_ = 0;
};

// A three-letter command at the reader: "(MNE" [","|'"'] operands ")".
Command ReadCommand(Reader& r, std::string_view s) {
  Command c;
  c.col = r.Col();
  r.Advance();  // '('
  r.Skip();
  std::size_t m0 = r.pos();
  while (IsUpper(r.Peek())) r.Advance();
  c.mnemonic = s.substr(m0, r.pos() - m0);
  if (c.mnemonic.size() != 3) Fail(c.col, 11, "a three-letter command is expected after '('");
  // The body runs to the matching ')' (quotes and brackets respected).
  std::size_t body0 = r.pos();
  int depth = 0;
  bool quote = false;
  while (!r.End()) {
    char ch = r.Peek();
    if (ch == '"') quote = !quote;
    if (!quote && ch == '(') ++depth;
    if (!quote && ch == ')') {
      if (depth == 0) break;
      --depth;
    }
    r.Advance();
  }
  if (r.End()) Fail(c.col, 11, "closing bracket missing");
  std::string_view body = s.substr(body0, r.pos() - body0);
  r.Advance();  // ')'
  std::size_t k = 0;
  while (k < body.size() && (body[k] == ' ' || body[k] == '\t')) ++k;
  // "(DIS,...)"; also "(DIS"text")" and "(CLS.P800)" as the manual prints them. "(URT,)": one empty operand.
  bool sep = k < body.size() && (body[k] == ',' || body[k] == '.');
  if (sep) ++k;
  std::string_view ops = body.substr(k);
  if (sep || ops.find_first_not_of(" \t") != std::string_view::npos) {
    c.ops = SplitOperands(ops, static_cast<int>(body0 + k) + 1);
  }
  return c;
}

// An assignment's left side: En, E(En), a global variable, a GTL element. Returns false when `lhs` is
// none of those.
bool ReadAssignTarget(std::string_view lhs, int col0, Assignment& a) {
  Reader r(lhs);
  r.Skip();
  a.col = col0 + r.Col() - 1;
  char c0 = r.Peek();
  if (c0 == 'E' && (IsDigit(r.Peek(1)) || r.Peek(1) == '(')) {
    Val v = r.Value();
    if (v.neg) return false;
    a.kind = v.kind == Val::kIndirect ? Assignment::kIndirect : Assignment::kParam;
    a.index = v.param;
  } else if (c0 == 'o' || c0 == 'p' || c0 == 'l' || c0 == 'c') {
    a.kind = Assignment::kGeometry;
    a.name = lhs.substr(r.pos(), 1);
    r.Advance();
    r.Skip();
    Val v = r.Value();
    if (v.kind == Val::kNone || v.neg) Fail(col0, 11, "a GTL element needs an index");
    a.gindex = v;
  } else if (IsUpper(c0)) {
    a.kind = Assignment::kGlobal;
    std::size_t n0 = r.pos();
    while (IsUpper(r.Peek())) r.Advance();
    a.name = lhs.substr(n0, r.pos() - n0);
    r.Skip();
    if (IsDigit(r.Peek())) {
      a.has_index = true;
      a.gindex.kind = Val::kNum;
      a.gindex.num = r.Digits(col0);
    }
    r.Skip();
    if (r.Peek() == '.') {
      r.Advance();
      std::size_t f0 = r.pos();
      while (IsDigit(r.Peek()) || IsUpper(r.Peek())) r.Advance();
      a.fmt = lhs.substr(f0, r.pos() - f0);
      if (a.fmt.empty()) Fail(col0, 11, "format expected after '.'");
    }
  } else {
    return false;
  }
  r.Skip();
  return r.End();
}

}  // namespace

std::vector<Operand> SplitOperands(std::string_view body, int col0) {
  std::vector<Operand> out;
  std::size_t start = 0;
  int depth = 0;
  bool quote = false;
  for (std::size_t i = 0; i <= body.size(); ++i) {
    char c = i < body.size() ? body[i] : ',';
    if (c == '"') quote = !quote;
    if (!quote && c == '(') ++depth;
    if (!quote && c == ')') --depth;
    if ((c == ',' && !quote && depth == 0) || i == body.size()) {
      std::string_view t = body.substr(start, i - start);
      std::size_t b = t.find_first_not_of(" \t");
      std::size_t e = t.find_last_not_of(" \t");
      Operand o;
      o.col = col0 + static_cast<int>(start + (b == std::string_view::npos ? 0 : b));
      o.text = b == std::string_view::npos ? std::string_view() : t.substr(b, e - b + 1);
      out.push_back(o);
      start = i + 1;
    }
  }
  return out;
}

namespace {

// What CheckCharacters does at a character: Allowed as a table (one load per character of every block), with
// the two that start something else.
enum CharClass : std::uint8_t { kRefused, kPlain, kComment, kQuote };
constexpr std::array<std::uint8_t, 256> kCharClass = [] {
  std::array<std::uint8_t, 256> t{};
  for (int c = 0; c < 256; ++c) t[c] = Allowed(static_cast<char>(c)) ? kPlain : kRefused;
  t[';'] = kComment;
  t['"'] = kQuote;
  return t;
}();

// Every character of the block is one of Table 5.1 (quoted texts and the comment aside).
void CheckCharacters(std::string_view s) {
  for (std::size_t i = 0; i < s.size(); ++i) {
    const std::uint8_t k = kCharClass[static_cast<unsigned char>(s[i])];
    if (k == kPlain) [[likely]]
      continue;
    if (k == kComment) break;  // the rest is a comment
    if (k == kQuote) {
      std::size_t e = s.find('"', i + 1);
      if (e == std::string_view::npos) Fail(static_cast<int>(i) + 1, 11, "closing '\"' missing");
      i = e;
      continue;
    }
    if (!Allowed(s[i])) {
      Fail(static_cast<int>(i) + 1, 11,
           (s[i] >= 32 && s[i] < 127) ? fmt::format("illegal character '{}'", s[i]) : "illegal character");
    }
  }
}

// The prefixes: '/', "label", N number, '#' / '&'.
void ReadPrefixes(Reader& r, std::string_view s, ParsedBlock& pb) {
  r.Skip();
  if (r.Peek() == '/') {
    pb.slash = true;
    r.Advance();
    r.Skip();
  }
  if (r.Peek() == '"') {
    int col = r.Col();
    r.Advance();
    std::size_t l0 = r.pos();
    while (!r.End() && r.Peek() != '"') r.Advance();
    pb.label = s.substr(l0, r.pos() - l0);
    r.Advance();
    if (pb.label.empty() || pb.label.size() > 6) Fail(col, 11, "a label has 1 to 6 letters or digits");
    for (char c : pb.label) {
      if (!IsAlnum(c)) Fail(col, 11, "a label has 1 to 6 letters or digits");
    }
    r.Skip();
  }
  if (r.Peek() == 'N' && IsDigit(r.Peek(1))) {
    int col = r.Col();
    r.Advance();
    int n = r.Digits(col);
    if (n < 1 || n > 9999) Fail(col, 13, "block numbers are N1-N9999");
    pb.has_n = true;
    pb.n = n;
    r.Skip();
  }
  if (r.Peek() == '#' || r.Peek() == '&') {
    pb.sync = r.Peek();
    r.Advance();
    r.Skip();
  }
}

// "@..." (K14 execution): the rest of the block.
void ReadExec(Reader& r, ParsedBlock& pb) {
  pb.kind = BlockKind::kExec;
  r.Advance();
  r.Skip();
  pb.exec = r.Rest();
  pb.exec_col = r.Col();
  if (std::size_t semi = pb.exec.find(';'); semi != std::string_view::npos) pb.exec = pb.exec.substr(0, semi);
  while (!pb.exec.empty() && (pb.exec.back() == ' ' || pb.exec.back() == '\t')) pb.exec.remove_suffix(1);
}

// An assignment: '=' outside brackets and quotes. False when the block has none.
bool ReadAssignment(std::string_view body, int body_col, ParsedBlock& pb) {
  if (body.find('=') == std::string_view::npos) return false;  // most blocks: one memchr, not the scan below
  int depth = 0;
  bool quote = false;
  for (std::size_t i = 0; i < body.size(); ++i) {
    char c = body[i];
    if (c == ';' && !quote) break;
    if (c == '"') quote = !quote;
    if (quote) continue;
    if (c == '(') ++depth;
    if (c == ')') --depth;
    if (c == '=' && depth == 0) {
      pb.kind = BlockKind::kAssign;
      if (!ReadAssignTarget(body.substr(0, i), body_col, pb.assign)) {
        Fail(body_col, 11, "no variable before '='");
      }
      std::string_view rhs = body.substr(i + 1);
      if (std::size_t semi = rhs.find(';');
          semi != std::string_view::npos && rhs.find('"') == std::string_view::npos) {
        rhs = rhs.substr(0, semi);
      }
      std::size_t b = rhs.find_first_not_of(" \t");
      if (b == std::string_view::npos)
        Fail(body_col + static_cast<int>(i) + 1, 12, "value missing after '='");
      std::size_t e = rhs.find_last_not_of(" \t");
      pb.assign.rhs = rhs.substr(b, e - b + 1);
      pb.assign.rhs_col = body_col + static_cast<int>(i + 1 + b);
      return true;
    }
  }
  return false;
}

// A lower-case word of an ISO block: a GTL element, s2, or a corner / paraxial word (r b t u v w).
void ReadLowerWord(Reader& r, char c, int col, ParsedBlock& pb) {
  if (c == 'p' || c == 'l' || c == 'c') {
    if (pb.elem.kind) Fail(col, 24, "one GTL element per block");
    pb.elem.kind = c;
    pb.elem.col = col;
    r.Advance();
    pb.elem.index = r.Value();
    if (pb.elem.index.kind == Val::kNone || pb.elem.index.neg) Fail(col, 11, "a GTL element needs an index");
    return;
  }
  if (c == 's') {
    r.Advance();
    r.Skip();
    if (r.Peek() != '2') Fail(col, 11, "the intersection selector is s2");
    r.Advance();
    if (pb.s2) Fail(col, 24, "s2 twice");
    pb.s2 = true;
    pb.s2_col = col;
    return;
  }
  if (c == 'r' || c == 'b' || c == 't' || c == 'u' || c == 'v' || c == 'w') {
    Word w;
    w.letter = c;
    w.col = col;
    r.Advance();
    w.v = r.Value();
    if (!pb.words.push_back(w)) Fail(col, 23, "too many words");
    pb.letters |= LetterBit(c);
    return;
  }
  Fail(col, 24, fmt::format("'{}' is a GTL definition word, not allowed in an ISO block", c));
}

// The words and commands of an ISO block.
void ReadIso(Reader& r, std::string_view s, ParsedBlock& pb) {
  bool non_g = false;
  while (true) {
    r.Skip();
    if (r.End() || r.Peek() == ';') break;
    char c = r.Peek();
    int col = r.Col();
    if (c == '(') {
      pb.commands.push_back(ReadCommand(r, s));
      continue;
    }
    if (c == ')') Fail(col, 11, "redundant closing bracket");
    if (c == '-' && (r.Peek(1) == 'l' || r.Peek(1) == 'c')) {
      r.Advance();
      c = r.Peek();
      if (pb.elem.kind) Fail(col, 24, "one GTL element per block");
      pb.elem.kind = c;
      pb.elem.neg = true;
      pb.elem.col = col;
      r.Advance();
      pb.elem.index = r.Value();
      if (pb.elem.index.kind == Val::kNone || pb.elem.index.neg)
        Fail(col, 11, "a GTL element needs an index");
      non_g = true;
      continue;
    }
    if (IsLower(c)) {
      non_g = true;
      ReadLowerWord(r, c, col, pb);
      continue;
    }
    if (!IsUpper(c)) Fail(col, 11, fmt::format("unexpected '{}'", c));
    if (c == 'E') {
      // The result variable of a probing cycle ("G72 X100 Y0 E32"); an implicit value follows its address.
      r.Advance();
      if (!IsDigit(r.Peek())) Fail(col, 11, "E parameter number expected");
      if (pb.result_e >= 0) Fail(col, 24, "two result parameters");
      pb.result_e = r.Digits(col);
      pb.result_col = col;
      non_g = true;
      continue;
    }
    if (c == 'N') Fail(col, 11, "the block number must be at the start of the block");
    if (c == 'L' || c == 'O') Fail(col, 11, fmt::format("'{}' is not an address", c));
    Word w;
    w.letter = c;
    w.col = col;
    r.Advance();
    w.v = r.Value();
    if (c == 'G') {
      // ln 2595: G functions immediately after the block number, before any other operand.
      if (non_g) Fail(col, 11, "G functions must come before the other words of the block");
    } else {
      non_g = true;
    }
    if (!pb.words.push_back(w)) Fail(col, 23, "too many words");
    pb.letters |= LetterBit(c);
  }
}

}  // namespace

ParsedBlock ParseBlock(std::string_view s) {
  ParsedBlock pb;
  CheckCharacters(s);
  Reader r(s);
  ReadPrefixes(r, s, pb);
  if (r.End() || r.Peek() == ';') return pb;  // label or number alone, comment block
  const int body_col = r.Col();
  std::string_view body = r.Rest();
  if (r.Peek() == '@') {
    ReadExec(r, pb);
    return pb;
  }
  if (ReadAssignment(body, body_col, pb)) return pb;
  pb.kind = BlockKind::kIso;
  ReadIso(r, s, pb);
  return pb;
}

}  // namespace cell::interp::balt
