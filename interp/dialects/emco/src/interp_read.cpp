// The EMCO tape format (ISO input, manual ln 780-1160 and 5619-5781): program headers "%"/"%nn"/"Onnnn",
// N0000-N9999 block numbers with the skip "/" after them, addresses with their numbers, indexed P/D
// parameters in every written form ("D3=600", "D3 = 600", "D420", "P0-4.199"), comments in round
// brackets, the block length limit. Values are kept as written; the executor scales them (µm without a
// decimal point, inch).
#include <fmt/format.h>

#include <cmath>

#include "cell/interp/scan.h"
#include "interp_internal.h"

namespace cell::interp::emco {

namespace {

using scan::IsDigit;

char Up(char c) {
  return (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : c;
}
bool IsBlank(char c) {
  return c == ' ' || c == '\t';
}

// The letters a turning program may use (ln 1102-1158; L in G25/G26/G27).
bool ProgramLetter(char c) {
  switch (c) {
    case 'G':
    case 'M':
    case 'X':
    case 'Z':
    case 'U':
    case 'W':
    case 'I':
    case 'K':
    case 'F':
    case 'S':
    case 'T':
    case 'L':
    case 'P':
    case 'D':
      return true;
    default:
      return false;
  }
}

struct Cursor {
  std::string_view s;
  std::size_t i = 0;
  void SkipBlanks() {
    while (i < s.size() && IsBlank(s[i])) ++i;
  }
  bool AtEnd() const { return i >= s.size(); }
  char Peek() const { return i < s.size() ? s[i] : '\0'; }
  int Col() const { return static_cast<int>(i) + 1; }
};

// A number: optional sign (blanks allowed around it), digits, an optional decimal point. Returns false when
// there are no digits.
bool ReadNumber(Cursor& c, double& value, bool& point, bool& sign, int& int_digits) {
  bool neg = false;
  sign = c.Peek() == '+' || c.Peek() == '-';
  if (sign) {
    neg = c.Peek() == '-';
    ++c.i;
    c.SkipBlanks();
  }
  // The digits before the point, then the point and the digits after it: one test per character (the same
  // sum, digit by digit, as one loop over both).
  double digits = 0;
  const char* const s = c.s.data();
  const std::size_t n = c.s.size();
  std::size_t i = c.i;
  const std::size_t int_begin = i;
  while (i < n && IsDigit(s[i])) digits = digits * 10 + (s[i++] - '0');
  int_digits = static_cast<int>(i - int_begin);
  int frac = 0;
  point = i < n && s[i] == '.';
  if (point) {
    const std::size_t frac_begin = ++i;
    while (i < n && IsDigit(s[i])) digits = digits * 10 + (s[i++] - '0');
    frac = static_cast<int>(i - frac_begin);
  }
  c.i = i;
  if (int_digits + frac == 0) return false;
  static constexpr double kPow10[] = {1, 10, 100, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12};
  // No division without fraction digits (most words): x / 1 is x.
  value = frac == 0 ? digits : frac < 13 ? digits / kPow10[frac] : digits / std::pow(10.0, frac);
  if (neg) value = -value;
  return true;
}

}  // namespace

std::string_view AlarmTitle(int code) {
  switch (code) {
    case 1:
      return "X-AXIS SOFTWARE LIMIT SWITCH";
    case 3:
      return "Z-AXIS SOFTWARE LIMIT SWITCH";
    case 160:
      return "BAD PARAMETER FOR G02 OR G03";
    case 170:
      return "TRIED TO START WITH FEED = 0";
    case 180:
      return "WRONG CENTER COORDINATE SPECIFIED";
    case 190:
      return "RADIUS TOO LARGE";
    case 200:
      return "INVALID VALUE OF D OR P PARAMETER";
    case 210:
      return "INVALID TAPER PARAMETER";
    case 220:
      return "INVALID REMINDER";
    case 230:
      return "INVALID CYCLE TARGET";
    case 240:
      return "NO OR INVALID STEP DEPTH";
    case 250:
      return "D OR P PARAMETER FOR GIVEN CYCLE MISSING";
    case 260:
      return "DRILL NOT CENTERED";
    case 300:
      return "MORE THAN 10 SUBROUTINES NESTED";
    case 310:
      return "SUBROUTINE NOT IN MEMORY";
    case 330:
      return "M17 WITHOUT G25 OR M30 IN A SUBROUTINE";
    case 340:
      return "G25/G27 NOT ALLOWED IN LAST BLOCK OF PROGRAM";
    case 350:
      return "INVALID CUTTER RADIUS";
    case 360:
      return "NO CHANGE OF T-WORD WITH G41/G42 ACTIVE";
    case 361:
      return "NO M65 WITH G41/G42 ACTIVE";
    case 370:
      return "NO CHANGE OF SCALE WHEN CYCLE ACTIVE";
    case 371:
      return "NO CHANGE OF PSO WHEN SCALE ACTIVE";
    case 372:
      return "NO RELATIVE MOVES AFTER G51";
    case 373:
      return "NO NEGATIVE SCALE ALLOWED";
    case 374:
      return "INVALID PARAMETER FOR G51";
    case 375:
      return "SCALE CALCULATION OVERFLOW";
    case 380:
      return "BAD OR MISSING PARAMETER IN G25/G27";
    case 381:
      return "AFTER CHAMFER/RADIUS ONLY G01 ALLOWED";
    case 382:
      return "MISSING POSITIONPARAMETER FOR CHAMFER/RADIUS";
    case 384:
      return "CHAMFER/RADIUS CALCULATION OVERFLOW";
    case 385:
      return "NO CHANGE OF PSO IF CHAMFER/RADIUS ACTIVE";
    case 386:
      return "NO CHANGE OF SCALE IF CHAMFER/RADIUS ACTIVE";
    case 387:
      return "NO CHANGE OF TOOL WHEN CHAMFER/RADIUS ACTIVE";
    case 389:
      return "PROGRAMMED CHAMFER/RADIUS TOO GREAT";
    case 390:
      return "CHANGE OF G-CODE GROUP 7/9 ONLY IN FIRST BLOCK";
    case 391:
      return "NEGATIVE CHAMFER/RADIUS NOT ALLOWED";
    case 400:
      return "NO G-CODE FOR GIVEN PARAMETER ACTIVE";
    case 410:
      return "INVALID G-CODE";
    case 420:
      return "INVALID M-CODE";
    case 430:
      return "INVALID T-WORD";
    case 440:
      return "TARGET LIMITS EXCEEDED";
    case 480:
      return "NO OR INVALID PARAMETER FOR G-GROUP 0";
    case 490:
      return "OFFSET CHANGED, GO WITH G00";
    case 500:
      return "TOO MANY BLOCKS WITHOUT SLIDE OPERATION";
    case 510:
      return "TOO FEW POINTS PROGRAMMED";
    case 520:
      return "ERROR AT COMPENSATION START OR END";
    case 530:
      return "NO IMMEDIATE CHANGE OF G41/42";
    case 540:
      return "BAD CIRCLE PARAMETER";
    case 560:
      return "RADIUS TOO LARGE";
    case 570:
      return "RADIUS TOO LARGE FOR GIVEN CONTOUR";
    case 580:
      return "PART PROGRAM MUST END WITH G40 ACTIVE";
    case 620:
      return "INPUT VALUE OUT OF NUMERICAL RANGE";
    case 630:
      return "INVALID SUBROUTINE NUMBER";
    case 650:
      return "BLOCK MEMORY OVERFLOW";
    case 690:
      return "INVALID INDEX ENTERED";
    case 700:
      return "NO CHANGE OF ACTIVE TOOL DATA/PSO";
    case 750:
      return "POLYGON PROGRAM NOT AVAILABLE";
    case 751:
      return "INVALID POLYGON PROGRAM NUMBER";
    case 785:
      return "WPC-PRESET = 0, CYCLE START IGNORED";
    case 940:
      return "NO M20/M21/M25 DURING SPINDLE ROTATION";
    default:
      return {};
  }
}

void Alarm(int code, int col, std::string_view detail) {
  std::string text(AlarmTitle(code));
  if (!detail.empty()) {
    text += " (";
    text += detail;
    text += ')';
  }
  Fail(col, std::move(text), fmt::format("{:03d}", code));
}

bool IsHeaderLine(std::string_view text) {
  std::size_t i = 0;
  while (i < text.size() && IsBlank(text[i])) ++i;
  if (i >= text.size()) return false;
  if (text[i] == '%') return true;
  if (Up(text[i]) != 'O') return false;
  ++i;
  while (i < text.size() && IsBlank(text[i])) ++i;
  bool digits = false;
  while (i < text.size() && IsDigit(text[i])) {
    digits = true;
    ++i;
  }
  while (i < text.size() && (IsBlank(text[i]) || text[i] == '\r')) ++i;
  if (i < text.size() && text[i] == '(') return digits;  // "O0010 (SHAFT)"
  return digits && i >= text.size();
}

void ParseBlock(std::string_view text, Block& out) {
  out.header = false;
  out.program = -1;
  out.skip = false;
  out.has_n = false;
  out.n = 0;
  out.count = 0;
  if (!text.empty() && text.back() == '\r') text.remove_suffix(1);

  // Length without comments and trailing blanks (ln 860: 3-4 screen lines). It is at most the text's size,
  // so only a text longer than the limit is counted (almost no block is).
  std::size_t length = 0, pending_blanks = 0;
  bool in_comment = false;
  if (text.size() > kMaxBlockChars)
    for (char ch : text) {
      if (in_comment) {
        if (ch == ')') in_comment = false;
        continue;
      }
      if (ch == '(') {
        in_comment = true;
      } else if (IsBlank(ch)) {
        ++pending_blanks;
      } else {
        length += pending_blanks + 1;
        pending_blanks = 0;
      }
    }
  if (length > kMaxBlockChars) {
    Alarm(650, static_cast<int>(kMaxBlockChars) + 1,
          fmt::format("{} characters, at most {}", length, kMaxBlockChars));
  }

  Cursor c{text};
  c.SkipBlanks();
  if (c.AtEnd()) return;
  if ((c.Peek() == '%' || Up(c.Peek()) == 'O') && IsHeaderLine(text)) {  // the test IsHeaderLine starts with
    out.header = true;
    char first = text[c.i++];
    c.SkipBlanks();
    if (first != '%') {
      while (!c.AtEnd() && IsBlank(c.Peek())) ++c.i;
    }
    int n = 0, digits = 0;
    while (!c.AtEnd() && IsDigit(c.Peek())) {
      n = n * 10 + (c.Peek() - '0');
      if (++digits > 4) Alarm(620, c.Col(), "program numbers are O0000-O9999");
      ++c.i;
    }
    if (digits > 0) out.program = n;
    return;
  }
  if (c.Peek() == '/') {  // skip flag before the number (common in ISO tapes)
    out.skip = true;
    ++c.i;
    c.SkipBlanks();
  }
  if (Up(c.Peek()) == 'N') {
    int col = c.Col();
    ++c.i;
    c.SkipBlanks();
    int n = 0, digits = 0;
    while (!c.AtEnd() && IsDigit(c.Peek())) {
      if (digits < 9) n = n * 10 + (c.Peek() - '0');  // more digits are an alarm below; no int overflow first
      ++digits;
      ++c.i;
    }
    if (digits == 0) Fail(col, "BLOCK NUMBER N WITHOUT DIGITS");
    if (digits > 4) Alarm(620, col, "block numbers are N0000-N9999");
    out.has_n = true;
    out.n = n;
    c.SkipBlanks();
    if (c.Peek() == '/') {
      out.skip = true;
      ++c.i;
    }
  }
  for (;;) {
    c.SkipBlanks();
    if (c.AtEnd()) break;
    char ch = c.Peek();
    if (ch == '(') {  // a comment: dropped on read-in (ln 5634)
      std::size_t close = text.find(')', c.i);
      c.i = close == std::string_view::npos ? text.size() : close + 1;
      continue;
    }
    int col = c.Col();
    char letter = Up(ch);
    if (letter == ',')
      Fail(col, "',' IS NOT A DECIMAL POINT ON TAPE (ln 5716; --listing reads the manual's style)");
    if (letter == 'N') Fail(col, "BLOCK NUMBER N ONLY AT THE START OF THE BLOCK");
    if (letter == '/') Fail(col, "SKIP '/' ONLY RIGHT AFTER THE BLOCK NUMBER");
    if (!ProgramLetter(letter)) {
      if (letter >= 'A' && letter <= 'Z') Fail(col, fmt::format("INVALID ADDRESS {}", letter));
      Fail(col, fmt::format("UNEXPECTED CHARACTER '{}'", ch));
    }
    ++c.i;
    Word w;
    w.letter = letter;
    w.col = static_cast<uint16_t>(col);
    c.SkipBlanks();
    if (letter == 'P' || letter == 'D') {
      if (!IsDigit(c.Peek())) Fail(col, fmt::format("{} NEEDS ITS INDEX (e.g. {}3=...)", letter, letter));
      int index = c.Peek() - '0';
      ++c.i;
      if (index > 7) Alarm(690, col, fmt::format("{}{}: indices are 0-7", letter, index));
      w.index = static_cast<int8_t>(index);
      c.SkipBlanks();
      if (c.Peek() == '=') {
        ++c.i;
        c.SkipBlanks();
      }
    }
    int int_digits = 0;
    bool point = false, sign = false;
    if (!ReadNumber(c, w.value, point, sign, int_digits)) {
      if (c.Peek() == ',')
        Fail(c.Col(), "',' IS NOT A DECIMAL POINT ON TAPE (ln 5716; --listing reads the manual's style)");
      Fail(col, fmt::format("ADDRESS {} WITHOUT A VALUE", letter));
    }
    w.point = point;
    w.sign = sign;
    if (c.Peek() == ',')
      Fail(c.Col(), "',' IS NOT A DECIMAL POINT ON TAPE (ln 5716; --listing reads the manual's style)");
    if (out.count >= kMaxWords) Alarm(650, col, fmt::format("more than {} words", kMaxWords));
    out.w[out.count++] = w;
  }
}

}  // namespace cell::interp::emco
