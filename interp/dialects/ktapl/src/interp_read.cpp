// KT-APL tape format: blocks, words and the implied decimals of each letter's number format (manual ch. 1
// and 5 "format", App. B).
#include <fmt/format.h>

#include <cmath>
#include <optional>

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

namespace {

// One row of the format tables: digits at most, decimals at most (the resolution), largest magnitude.
struct Format {
  int digits;
  int decimals;
  double max;
  const char* range;  // as the message prints it
  const char* table = "";
};

std::optional<Format> FormatOf(char letter, bool metric) {
  switch (letter) {
    case 'X':
    case 'Y':
    case 'Z':
    case 'I':
    case 'J':
    case 'K':
    case 'R':
    case 'E':  // ln 893-915, 981-1047: inch 4.4, metric 5.3, 8 digits
      return metric ? Format{8, 3, 42949.672, "+-42949.672 MM", " (METRIC FORMAT 5.3)"}
                    : Format{8, 4, 1690.9320, "+-1690.9320 IN", " (INCH FORMAT 4.4)"};
    case 'A':
    case 'B':
    case 'C':  // ln 917-979: 5.3 (index B whole degrees: checked with the move)
      return Format{8, 3, 99999.999, "+-99999.999 DEGREES", " (FORMAT 5.3)"};
    case 'U':
    case 'V':
    case 'W':  // ln 4409: the rotary format 5.3 in both units (judgement call 5)
      return Format{8, 3, 99999.999, "+-99999.999", " (FORMAT 5.3)"};
    case 'H':  // ln 1051-1057: 8.0 (the range 0-32 is checked with the offset)
      return Format{8, 0, 1e300, "", " (FORMAT 8.0)"};
    case 'G':  // ln 1077-1083: 2.0 (G801-G899 three digits, ln 1294; the codes are checked by name)
    case 'M':  // ln 1093-1099: 2.0
      return Format{2, 0, 1e300, "", " (FORMAT 2.0)"};
    case 'S':  // ln 1187-1193: 5.0 (the range is checked with the speed)
      return Format{5, 0, 1e300, "", " (FORMAT 5.0)"};
    case 'T':  // ln 1212-1225: decimal 7.0 (the range is checked with the selection)
      return Format{7, 0, 1e300, "", " (FORMAT 7.0)"};
    default:  // F has its own tables (CheckFeedFormat); D O P Q have none
      return std::nullopt;
  }
}

void CheckFormat(const Word& w, const Format& f, const char* table) {
  if (w.literal) {
    int digits = f.digits;
    if (w.letter == 'G' && w.num.digits == 3 && w.v >= 800 && w.v <= 899) digits = 3;
    if (w.num.digits > digits)
      Fail(w.col, fmt::format("{} WORD HAS MORE THAN {} DIGITS{}", w.letter, digits, table));
    if (w.num.frac_digits > f.decimals) {
      Fail(w.col, f.decimals == 0
                      ? fmt::format("{} WORD TAKES A WHOLE NUMBER{}", w.letter, table)
                      : fmt::format("{} WORD HAS MORE THAN {} DECIMALS{}", w.letter, f.decimals, table));
    }
  }
  // Values are compared at the format's resolution: a computed 1690.93201 in is 1690.9320.
  static constexpr double kHalfStep[] = {0.5, 0.05, 0.005, 0.0005, 0.00005};
  if (!(std::fabs(w.v) < f.max + kHalfStep[f.decimals])) {
    Fail(w.col, fmt::format("{} WORD OUT OF RANGE {}{}", w.letter, f.range, table));
  }
}

}  // namespace

void CheckWordFormat(const Word& w, bool metric) {
  if (auto f = FormatOf(w.letter, metric)) CheckFormat(w, *f, f->table);
}

void CheckFeedFormat(const Word& w, FeedFormat fmt, bool metric) {
  switch (fmt) {
    case FeedFormat::kLinear:
      // Table 1-A, ln 1145-1157 ("3" in the metric range is read as 1). Metric is 6.0, but App. D's own G82
      // programs F12.7 in G71 (ln 11596) and ln 4403 only says a point is never required: a tenth is
      // accepted (judgement call 63).
      return metric ? CheckFormat(w, {7, 1, 999999.9, "1-999999"}, " (G94 METRIC FORMAT 6.0)")
                    : CheckFormat(w, {6, 1, 99999.9, ".1-99999.9"}, " (G94 INCH FORMAT 5.1)");
    case FeedFormat::kRotary:  // ln 5976-5978, 2416: rotary departures only, whole degrees per minute
      return metric ? CheckFormat(w, {4, 0, 2537, "1-2537"}, " (METRIC ROTARY DEGREES PER MINUTE)")
                    : CheckFormat(w, {3, 0, 999, "1-999"}, " (ROTARY FORMAT 3.0 DEGREES PER MINUTE)");
    case FeedFormat::kInverseTime:  // Table 1-B, ln 1159-1163
      return metric ? CheckFormat(w, {6, 1, 99999.9, ".1-99999.9"}, " (G93 METRIC FORMAT 5.1)")
                    : CheckFormat(w, {4, 1, 999.9, ".1-999.9"}, " (G93 INCH FORMAT 3.1)");
  }
}

double MinArcRadiusMm(bool metric) {
  return metric ? 0.01 : 0.001 * 25.4;
}

double MaxArcRadiusMm(bool metric) {
  return metric ? 42949.672 : 1690.9320 * 25.4;
}

void AddWord(RawWords& words, const RawWord& w) {
  if (!words.push_back(w)) Fail(w.col, "TOO MANY WORDS IN THE BLOCK");
}

void ParseBlock(std::string_view s, bool fragment, ParsedBlock& pb) {
  pb.Clear();
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
    const int n_col = static_cast<int>(i) + 1;
    ++i;
    double v = 0, scale = 0;
    int frac = 0;
    while (i < s.size() && (IsDigit(s[i]) || s[i] == '.')) {
      if (s[i] == '.') {
        if (pb.n.point) Fail(static_cast<int>(i) + 1, "ILLEGAL SEQUENCE NUMBER");
        pb.n.point = true;
        scale = 0.1;
      } else if (pb.n.point) {
        v += (s[i] - '0') * scale;
        scale /= 10;
        ++frac;
        if (s[i] != '0') pb.n.frac_digits = frac;
      } else {
        v = v * 10 + (s[i] - '0');
        ++pb.n.digits;  // integer digits (format 8.0 / 5.4)
      }
      ++i;
    }
    pb.n.as_written = v;
    // ln 1109-1125: 8.0 (0-99999999), or with a point 5.4 (0-99999.9999).
    if (pb.n.point ? (pb.n.digits > 5 || pb.n.frac_digits > 4) : pb.n.digits > 8) {
      Fail(n_col, "N WORD FORMAT IS 8.0 OR 5.4 (0-99999999, 0-99999.9999)");
    }
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
      Statement& st = pb.stmts.emplace_back();
      size_t at = 0;
      if (!NextStatement(s.substr(i), at, st, &err)) {
        Fail(static_cast<int>(i) + 1, err.empty() ? "TYPE II COMMAND SYNTAX ERROR" : err);
      }
      st.col += static_cast<int>(i);
      if (st.mnemonic.size() != 3) Fail(st.col, "TYPE II COMMAND SYNTAX ERROR");
      i += st.end;
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
      int frac = 0;
      while (i < s.size() && IsDigit(s[i])) {
        v += (s[i] - '0') * scale;
        scale /= 10;
        ++digits;
        ++frac;
        if (s[i] != '0') num.frac_digits = frac;
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
}

}  // namespace cell::interp::ktapl
