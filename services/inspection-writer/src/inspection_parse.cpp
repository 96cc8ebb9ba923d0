// Reading a closed inspection file back into records (the header, each probe cycle's result block, the
// other lines as text), with the line and column of the first thing that is not what the control writes.
#include <fmt/format.h>

#include <array>
#include <charconv>
#include <string>

#include "cell/inspection/inspection_file.h"

namespace cell::inspection {

ParseError::ParseError(int line, int column, const std::string& reason)
    : Error(Errc::kInvalidArgument, fmt::format("{}:{}: {}", line, column, reason)),
      line_(line),
      column_(column),
      reason_(reason) {}

namespace {

// Labels compared without blanks: App. E prints "XSURFACE=", "BALIGNMENT =" and "X CENTER = " alike.
std::string Squeeze(std::string_view s) {
  std::string out;
  for (char c : s)
    if (c != ' ') out += c;
  return out;
}

struct Line {
  std::string_view text;
  int number;
};

class Reader {
 public:
  explicit Reader(std::string_view text) {
    int n = 1;
    std::size_t start = 0;
    while (start < text.size()) {
      std::size_t end = text.find('\n', start);
      std::string_view l =
          text.substr(start, end == std::string_view::npos ? text.size() - start : end - start);
      if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
      lines_.push_back({l, n++});
      if (end == std::string_view::npos) break;
      start = end + 1;
    }
    for (const Line& l : lines_) {
      for (std::size_t i = 0; i < l.text.size(); ++i)
        if (l.text[i] < 0x20 || l.text[i] > 0x7e)
          throw ParseError(l.number, static_cast<int>(i) + 1,
                           fmt::format("character 0x{:02x} is not printable ASCII",
                                       static_cast<unsigned char>(l.text[i])));
      if (l.text.size() > kMaxLineChars)
        throw ParseError(
            l.number, static_cast<int>(kMaxLineChars) + 1,
            fmt::format("line longer than {} characters (ln 8101: the control cuts every line there)",
                        kMaxLineChars));
    }
  }
  bool AtEnd() const { return next_ >= lines_.size(); }
  const Line& Peek() const { return lines_[next_]; }
  const Line& Take() { return lines_[next_++]; }
  int EndLine() const { return static_cast<int>(lines_.size()) + 1; }

 private:
  std::vector<Line> lines_;
  std::size_t next_ = 0;
};

// Scans "NAME = value" pieces of one line, reporting columns.
class Cursor {
 public:
  explicit Cursor(const Line& l) : line_(l) {}
  void Blanks() {
    while (pos_ < line_.text.size() && line_.text[pos_] == ' ') ++pos_;
  }
  bool Done() {
    Blanks();
    return pos_ >= line_.text.size();
  }
  [[noreturn]] void Fail(const std::string& reason) const {
    throw ParseError(line_.number, static_cast<int>(pos_) + 1, reason);
  }
  void Expect(std::string_view word) {
    Blanks();
    if (line_.text.substr(pos_, word.size()) != word) Fail(fmt::format("expected '{}'", word));
    pos_ += word.size();
  }
  // The control's numbers: optional '-', digits with at most one point (9.8000000, -45.670000, .25000000).
  double Number() {
    Blanks();
    std::size_t start = pos_, i = pos_;
    const std::string_view t = line_.text;
    if (i < t.size() && t[i] == '-') ++i;
    std::size_t digits = 0, points = 0;
    for (; i < t.size() && ((t[i] >= '0' && t[i] <= '9') || t[i] == '.'); ++i)
      (t[i] == '.' ? points : digits)++;
    // A number runs to a blank or the end of the line: "5.00O0000" is one bad number, not 5 and text.
    if (digits == 0 || points > 1 || (i < t.size() && t[i] != ' '))
      Fail("expected a number such as 5.0000000 or -.25000000");
    double v = 0;
    auto [end, ec] = std::from_chars(t.data() + start, t.data() + i, v);
    if (ec != std::errc() || end != t.data() + i) Fail("number out of range");
    pos_ = i;
    return v;
  }
  std::string_view Rest() {
    Blanks();
    std::string_view r = line_.text.substr(pos_);
    while (!r.empty() && r.back() == ' ') r.remove_suffix(1);
    return r;
  }
  void Seek(std::size_t p) { pos_ = p; }

 private:
  const Line& line_;
  std::size_t pos_ = 0;
};

// "NAME = value" for a header line; the value is the rest of the line.
std::string_view HeaderValue(const Line& l, std::string_view name, std::string_view what) {
  Cursor c(l);
  if (l.text.substr(0, name.size()) != name)
    c.Fail(fmt::format("expected '{} = ...' ({}): not a KT-APL inspection file", name, what));
  c.Seek(name.size());
  c.Expect("=");
  std::string_view v = c.Rest();
  if (v.empty()) c.Fail(fmt::format("{} without a value", name));
  return v;
}

Stamp ParseStamp(const Line& l) {
  // YY:MM:DD HH:MM, ln 7904-7908.
  static constexpr std::string_view kShape = "99:99:99 99:99";
  const std::string_view t = l.text;
  for (std::size_t i = 0; i < kShape.size(); ++i) {
    bool ok = i < t.size() && (kShape[i] == '9' ? (t[i] >= '0' && t[i] <= '9') : t[i] == kShape[i]);
    if (!ok)
      throw ParseError(l.number, static_cast<int>(i) + 1,
                       "expected the date and time the file was opened, YY:MM:DD HH:MM (ln 7904)");
  }
  if (t.size() > kShape.size())
    throw ParseError(l.number, static_cast<int>(kShape.size()) + 1, "unexpected text after the time");
  auto two = [&](std::size_t at) { return (t[at] - '0') * 10 + (t[at + 1] - '0'); };
  Stamp s;
  int yy = two(0);
  s.year = yy < 70 ? 2000 + yy : 1900 + yy;
  s.month = two(3);
  s.day = two(6);
  s.hour = two(9);
  s.minute = two(12);
  auto bad = [&](std::size_t at, const char* what) {
    throw ParseError(l.number, static_cast<int>(at) + 1, fmt::format("{} out of range", what));
  };
  if (s.month < 1 || s.month > 12) bad(3, "month");
  if (s.day < 1 || s.day > 31) bad(6, "day");
  if (s.hour > 23) bad(9, "hour");
  if (s.minute > 59) bad(12, "minute");
  return s;
}

Header ParseHeader(Reader& r) {
  Header h;
  auto next = [&](const char* what) -> const Line& {
    if (r.AtEnd()) throw ParseError(r.EndLine(), 1, fmt::format("the file ends before {}", what));
    return r.Take();
  };
  if (r.AtEnd()) throw ParseError(1, 1, "empty file: not a KT-APL inspection file");
  h.serial =
      HeaderValue(next("the serial number"), "CONTROL SERIAL NUMBER", "an inspection file's first line");
  h.part = HeaderValue(next("the part number"), "PALLET CODE/PART NUMBER", "the header's second line");
  const Line* l = &next("the date and time");
  constexpr std::string_view kCompleted = "NUMBER OF PART CYCLES COMPLETED";
  if (l->text.substr(0, kCompleted.size()) == kCompleted) {
    std::string_view v = HeaderValue(*l, kCompleted, "the header");
    long n = 0;
    auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
    if (ec != std::errc() || end != v.data() + v.size() || n < 0)
      throw ParseError(l->number, static_cast<int>(v.data() - l->text.data()) + 1,
                       "expected a whole number of part cycles");
    h.parts_completed = n;
    l = &next("the date and time");
  }
  h.created = ParseStamp(*l);
  const Line& d = next("the dashed delimiter line");
  if (d.text.size() < 3 || d.text.find_first_not_of('-') != std::string_view::npos)
    throw ParseError(d.number, 1, "expected the dashed delimiter line after the header (ln 7908)");
  return h;
}

// The quantity a line reports, when its text before '=' is one of the labels.
std::optional<Quantity> LabelOf(const Line& l, std::size_t* after_equals) {
  std::size_t eq = l.text.find('=');
  if (eq == std::string_view::npos) return std::nullopt;
  constexpr int kCount = static_cast<int>(Quantity::kToleranceC) + 1;
  static const auto squeezed = [] {
    std::array<std::string, kCount> a;
    for (int i = 0; i < kCount; ++i) a[i] = Squeeze(Label(static_cast<Quantity>(i)));
    return a;
  }();
  std::string label = Squeeze(l.text.substr(0, eq));
  for (int i = 0; i < kCount; ++i)
    if (label == squeezed[i]) {
      *after_equals = eq + 1;
      return static_cast<Quantity>(i);
    }
  return std::nullopt;
}

Result ParseResult(const Line& l, Quantity q, std::size_t after_equals) {
  Cursor c(l);
  c.Seek(after_equals);
  Result r{q, c.Number(), {}, {}};
  if (IsTolerance(q)) {
    c.Expect("NOMINAL");
    c.Expect("=");
    r.nominal = c.Number();
    c.Expect("TOLERANCE");
    c.Expect("=");
    r.tolerance = c.Number();
  }
  if (!c.Done()) c.Fail(fmt::format("unexpected text after the {} value", Label(q)));
  return r;
}

bool IsNLine(std::string_view t) {
  return t.size() >= 2 && t[0] == 'N' && t.find_first_not_of("0123456789", 1) == std::string_view::npos;
}

// What may follow `q` in one cycle's block (App. E's FWR sequences), and the kind the first line starts.
struct Shape {
  CycleKind kind;
  std::vector<Quantity> then;
  bool optional_then;
};

std::optional<Shape> ShapeOf(Quantity q) {
  using Q = Quantity;
  switch (q) {
    case Q::kXSurface:
      return Shape{CycleKind::kSurface, {Q::kYSurface}, true};  // G26X, or G26XY/RA
    case Q::kYSurface:
    case Q::kZSurface:
      return Shape{CycleKind::kSurface, {}, false};
    case Q::kXSeparation:
      return Shape{CycleKind::kCentre, {Q::kXCenter}, false};
    case Q::kYSeparation:
      return Shape{CycleKind::kCentre, {Q::kYCenter}, false};
    case Q::kXYSeparation:
      return Shape{CycleKind::kCentre, {Q::kXCenter, Q::kYCenter}, false};
    case Q::kXCenter:
    case Q::kYCenter:
      return std::nullopt;  // a centre always follows its separation line
    case Q::kAAlignment:
    case Q::kBAlignment:
    case Q::kCAlignment:
      return Shape{CycleKind::kAlignment, {}, false};
    case Q::kProbeLength:
      return Shape{CycleKind::kProbeLength, {}, false};
    case Q::kToleranceX:
      return Shape{CycleKind::kTolerance, {Q::kToleranceY}, true};  // G24X, or G24XY
    default:
      return Shape{CycleKind::kTolerance, {}, false};
  }
}

CycleResult ParseCycle(Reader& r, std::optional<long> n) {
  const Line& first = r.Take();
  std::size_t after = 0;
  Quantity q = *LabelOf(first, &after);
  std::optional<Shape> shape = ShapeOf(q);
  if (!shape)
    throw ParseError(first.number, 1,
                     fmt::format("{} without the SURFACE SEPARATION line App. E writes before it", Label(q)));
  CycleResult c{shape->kind, n, {ParseResult(first, q, after)}};
  for (Quantity want : shape->then) {
    std::size_t at = 0;
    std::optional<Quantity> got = r.AtEnd() ? std::nullopt : LabelOf(r.Peek(), &at);
    if (got != want) {
      if (shape->optional_then) break;
      int line = r.AtEnd() ? r.EndLine() : r.Peek().number;
      throw ParseError(line, 1,
                       fmt::format("expected the {} line of this {} result", Label(want), KindName(c.kind)));
    }
    c.results.push_back(ParseResult(r.Take(), want, at));
  }
  if (r.AtEnd())
    throw ParseError(r.EndLine(), 1,
                     "the file ends inside a probe cycle's lines (App. E ends each with (FWR,))");
  const Line& end = r.Take();
  if (!end.text.empty())
    throw ParseError(
        end.number, 1,
        "expected the empty line that ends a probe cycle's lines (App. E ends each with (FWR,))");
  return c;
}

}  // namespace

InspectionFile Parse(std::string_view text) {
  Reader r(text);
  InspectionFile f;
  f.header = ParseHeader(r);
  while (!r.AtEnd()) {
    const Line& l = r.Peek();
    std::size_t after = 0;
    if (IsNLine(l.text)) {
      long n = 0;
      auto [end, ec] = std::from_chars(l.text.data() + 1, l.text.data() + l.text.size(), n);
      if (ec != std::errc()) throw ParseError(l.number, 2, "N number out of range");
      r.Take();
      if (r.AtEnd() || !LabelOf(r.Peek(), &after))
        throw ParseError(
            r.AtEnd() ? r.EndLine() : r.Peek().number, 1,
            fmt::format("N{} is not followed by a probe cycle's result (App. E writes N only before "
                        "one, ln 12273-12276)",
                        n));
      f.body.emplace_back(ParseCycle(r, n));
    } else if (LabelOf(l, &after)) {
      f.body.emplace_back(ParseCycle(r, std::nullopt));
    } else {
      f.body.emplace_back(TextLine{std::string(r.Take().text)});
    }
  }
  return f;
}

}  // namespace cell::inspection
