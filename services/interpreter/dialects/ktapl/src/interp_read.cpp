// KT-APL tape format: blocks, words and the implied decimals of each letter's number format (manual ch. 1
// and 5 "format", App. B).
#include <fmt/format.h>

#include "interp_internal.h"

namespace cell::interp::ktapl {

// Implied decimals of a letter when written without a point.
int ImpliedDecimals(char letter, bool metric, bool dwell, bool passing) {
  switch (letter) {
    case 'A':
    case 'B':
    case 'C':
      return 3;
    case 'U':
    case 'V':
    case 'W':
      return passing ? (metric ? 3 : 4) : 3;
    case 'F':
      return dwell ? 1 : (metric ? 0 : 1);
    case 'D':
    case 'O':
      return passing ? 4 : (metric ? 3 : 4);
    case 'N':
      return passing ? 4 : 0;
    case 'G':
    case 'H':
    case 'M':
    case 'P':
    case 'S':
    case 'T':
      return 0;
    default:
      return metric ? 3 : 4;  // E I J K Q R X Y Z
  }
}

bool IntegerLetter(char c) {
  return c == 'G' || c == 'H' || c == 'M' || c == 'P' || c == 'S' || c == 'T';
}

double ScaleLiteral(char letter, const RawNum& n, bool metric, bool dwell, bool passing) {
  static constexpr double kPow10[] = {1.0, 10.0, 100.0, 1000.0, 10000.0};
  double v = n.as_written;
  if (!n.point) v /= kPow10[ImpliedDecimals(letter, metric, dwell, passing)];
  return n.neg ? -v : v;
}

void AddWord(RawWords& words, const RawWord& w) {
  if (!words.push_back(w)) Fail(w.col, "TOO MANY WORDS IN THE BLOCK");
}

// Parses one block (or an IFT action fragment) into words and statements. Expression words view `s`.
ParsedBlock ParseBlock(std::string_view s, bool fragment) {
  ParsedBlock pb;
  size_t i = 0;
  auto skip = [&] {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  };
  skip();
  if (!fragment && i < s.size() && s[i] == '/') {
    pb.deleted = true;
    ++i;
    skip();
  }
  if (!fragment && i < s.size() && Up(s[i]) == 'N' && i + 1 < s.size() &&
      (IsDigit(s[i + 1]) || s[i + 1] == '.')) {
    pb.has_n = true;
    ++i;
    double v = 0, scale = 0;
    while (i < s.size() && (IsDigit(s[i]) || s[i] == '.')) {
      if (s[i] == '.') {
        if (pb.n.point) Fail(static_cast<int>(i) + 1, "ILLEGAL SEQUENCE NUMBER");
        pb.n.point = true;
        scale = 0.1;
      } else if (pb.n.point) {
        v += (s[i] - '0') * scale;
        scale /= 10;
      } else {
        v = v * 10 + (s[i] - '0');
      }
      ++i;
    }
    pb.n.as_written = v;
  }
  while (true) {
    skip();
    if (i >= s.size()) break;
    char c = s[i];
    if (c == '!') {
      pb.comment = Trim(s.substr(i + 1));
      break;
    }
    if (c == '(' || (c == '%' && i + 1 < s.size() && IsAlpha(s[i + 1]))) {
      std::string err;
      auto sts = FindStatements(s.substr(i), &err);
      if (sts.empty()) Fail(static_cast<int>(i) + 1, err.empty() ? "TYPE II COMMAND SYNTAX ERROR" : err);
      Statement st = sts[0];
      st.col += static_cast<int>(i);
      if (st.mnemonic.size() != 3) Fail(st.col, "TYPE II COMMAND SYNTAX ERROR");
      i += st.end;
      pb.stmts.push_back(std::move(st));
      continue;
    }
    if (c == '%') {  // stray rewind stop / EIA framing character
      ++i;
      continue;
    }
    if (!IsAlpha(c)) Fail(static_cast<int>(i) + 1, fmt::format("ILLEGAL CHARACTER '{}'", c));
    RawWord w;
    w.letter = Up(c);
    w.col = static_cast<int>(i) + 1;
    if (w.letter == 'N') Fail(w.col, "N WORD MUST BE THE FIRST WORD OF THE BLOCK");
    if (w.letter == 'L') Fail(w.col, "ILLEGAL ADDRESS L");
    ++i;
    skip();
    if (i < s.size() && s[i] == ',') {
      // Expression form: up to the next top-level comma, a comment, or the end of the block.
      ++i;
      size_t start = i;
      int depth = 0;
      while (i < s.size()) {
        char d = s[i];
        if (d == '(') ++depth;
        if (d == ')') {
          if (depth == 0) break;
          --depth;
        }
        if ((d == ',' || d == '!') && depth == 0) break;
        ++i;
      }
      w.kind = WordKind::kExpr;
      w.expr = s.substr(start, i - start);
      if (TrimView(w.expr).empty()) Fail(w.col, "EXPRESSION EXPECTED AFTER ','");
      if (i < s.size() && s[i] == ',') ++i;
      AddWord(pb.words, w);
      continue;
    }
    bool neg = false;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) {
      neg = s[i] == '-';
      ++i;
      skip();
    }
    if (i < s.size() && Up(s[i]) == 'L' && i + 1 < s.size() && IsDigit(s[i + 1])) {
      ++i;
      long n = 0;
      while (i < s.size() && IsDigit(s[i])) {
        n = n * 10 + (s[i] - '0');
        if (n > 99999) Fail(w.col, "Error L numbers range from 0..3999");
        ++i;
      }
      if (n > 3999) Fail(w.col, "Error L numbers range from 0..3999");
      w.kind = neg ? WordKind::kNegParam : WordKind::kParam;
      w.param = static_cast<int>(n);
      AddWord(pb.words, w);
      continue;
    }
    RawNum num;
    num.neg = neg;
    int digits = 0;
    double v = 0;
    while (i < s.size() && IsDigit(s[i])) {
      v = v * 10 + (s[i] - '0');
      ++digits;
      ++i;
    }
    if (i < s.size() && s[i] == '.') {
      num.point = true;
      ++i;
      double scale = 0.1;
      while (i < s.size() && IsDigit(s[i])) {
        v += (s[i] - '0') * scale;
        scale /= 10;
        ++digits;
        ++i;
      }
    }
    if (digits == 0) Fail(w.col, fmt::format("NUMBER EXPECTED AFTER {}", w.letter));
    if (digits > 9) Fail(w.col, fmt::format("TOO MANY DIGITS IN {} WORD", w.letter));
    num.as_written = v;
    num.digits = digits;
    w.num = num;
    AddWord(pb.words, w);
  }
  return pb;
}

}  // namespace cell::interp::ktapl
