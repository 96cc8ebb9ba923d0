// The inspection file's text: writing it as the control does, reading it back.
#include "cell/inspection/inspection_file.h"

#include <fmt/format.h>

#include <array>
#include <charconv>
#include <cmath>

#include "cell/interp/ktapl.h"

namespace cell::inspection {

namespace {

struct QuantityInfo {
  Quantity q;
  std::string_view label;
  bool angular;
};

// App. E's labels (ln 12276, 12298-12300, 12375-12376, 12432, 12447, 12611-12612, 12712-12714, 13004,
// 13068) and the cell's G24 lines.
constexpr std::array<QuantityInfo, 19> kQuantities{{
    {Quantity::kXSurface, "X SURFACE", false},
    {Quantity::kYSurface, "Y SURFACE", false},
    {Quantity::kZSurface, "Z SURFACE", false},
    {Quantity::kXSeparation, "X SURFACE SEPARATION", false},
    {Quantity::kYSeparation, "Y SURFACE SEPARATION", false},
    {Quantity::kXYSeparation, "X,Y SURFACE SEPARATION", false},
    {Quantity::kXCenter, "X CENTER", false},
    {Quantity::kYCenter, "Y CENTER", false},
    {Quantity::kAAlignment, "A ALIGNMENT", true},
    {Quantity::kBAlignment, "B ALIGNMENT", true},
    {Quantity::kCAlignment, "C ALIGNMENT", true},
    {Quantity::kProbeLength, "SPINDLE PROBE LENGTH", false},
    {Quantity::kToleranceR, "G24 R", false},
    {Quantity::kToleranceX, "G24 X", false},
    {Quantity::kToleranceY, "G24 Y", false},
    {Quantity::kToleranceZ, "G24 Z", false},
    {Quantity::kToleranceA, "G24 A", true},
    {Quantity::kToleranceB, "G24 B", true},
    {Quantity::kToleranceC, "G24 C", true},
}};

const QuantityInfo& Info(Quantity q) {
  return kQuantities[static_cast<std::size_t>(q)];
}

constexpr std::string_view kSerial = "CONTROL SERIAL NUMBER";
constexpr std::string_view kPart = "PALLET CODE/PART NUMBER";
constexpr std::string_view kCompleted = "NUMBER OF PART CYCLES COMPLETED";
constexpr std::string_view kNominal = "NOMINAL";
constexpr std::string_view kTolerance = "TOLERANCE";
// The manual names a dashed delimiter line but the scan lost it (ln 7908): 30 dashes, the width of the
// example header's longest line.
constexpr std::string_view kDelimiter = "------------------------------";

[[noreturn]] void Invalid(const std::string& what) {
  throw Error(Errc::kInvalidArgument, what);
}

bool Printable(std::string_view s) {
  for (char c : s)
    if (c < 0x20 || c > 0x7e) return false;
  return true;
}

void AppendLine(std::string& out, std::string_view text) {
  out.append(text.substr(0, kMaxLineChars));
  out += '\n';
}

std::string HeaderField(std::string_view name, std::string_view value) {
  if (value.empty() || !Printable(value) || value.front() == ' ' || value.back() == ' ')
    Invalid(fmt::format("{}: '{}' is not a value the header can hold", name, value));
  std::string line = fmt::format("{} = {}", name, value);
  if (line.size() > kMaxLineChars)
    Invalid(fmt::format("{}: '{}' makes the line longer than {} characters", name, value, kMaxLineChars));
  return line;
}

// The shapes App. E writes, by kind: every cycle's lines in order.
bool ValidShape(const CycleResult& c) {
  const auto& r = c.results;
  auto is = [&](std::initializer_list<Quantity> qs) {
    if (r.size() != qs.size()) return false;
    std::size_t i = 0;
    for (Quantity q : qs)
      if (r[i++].quantity != q) return false;
    return true;
  };
  for (const Result& x : r) {
    if (IsTolerance(x.quantity) != (x.nominal.has_value() && x.tolerance.has_value())) return false;
    if (!std::isfinite(x.value) || (x.nominal && !std::isfinite(*x.nominal)) ||
        (x.tolerance && !(std::isfinite(*x.tolerance) && *x.tolerance >= 0)))
      return false;
  }
  switch (c.kind) {
    case CycleKind::kSurface:
      return is({Quantity::kXSurface}) || is({Quantity::kYSurface}) || is({Quantity::kZSurface}) ||
             is({Quantity::kXSurface, Quantity::kYSurface});
    case CycleKind::kCentre:
      return is({Quantity::kXSeparation, Quantity::kXCenter}) ||
             is({Quantity::kYSeparation, Quantity::kYCenter}) ||
             is({Quantity::kXYSeparation, Quantity::kXCenter, Quantity::kYCenter});
    case CycleKind::kAlignment:
      return is({Quantity::kAAlignment}) || is({Quantity::kBAlignment}) || is({Quantity::kCAlignment});
    case CycleKind::kProbeLength:
      return is({Quantity::kProbeLength});
    case CycleKind::kTolerance:
      if (is({Quantity::kToleranceX, Quantity::kToleranceY})) return true;
      return r.size() == 1 && IsTolerance(r[0].quantity);
  }
  return false;
}

std::string ResultLine(const Result& r) {
  std::string line = fmt::format("{} = {}", Label(r.quantity), FormatNumber(r.value));
  if (r.nominal && r.tolerance)
    line += fmt::format(" {} = {} {} = {}", kNominal, FormatNumber(*r.nominal), kTolerance,
                        FormatNumber(*r.tolerance));
  return line;
}

}  // namespace

std::string FormatNumber(double v) {
  return cell::interp::FormatKtNumber(v);
}

std::string FormatTruncated(double v) {
  return fmt::format("{}", static_cast<long long>(std::trunc(v)));
}

std::string FormatRounded(double v) {
  return fmt::format("{}", static_cast<long long>(std::floor(v + 0.5)));
}

std::string_view Label(Quantity q) {
  return Info(q).label;
}

bool IsAngular(Quantity q) {
  return Info(q).angular;
}

bool IsTolerance(Quantity q) {
  return q >= Quantity::kToleranceR;
}

std::string_view KindName(CycleKind k) {
  switch (k) {
    case CycleKind::kSurface:
      return "surface";
    case CycleKind::kCentre:
      return "centre";
    case CycleKind::kAlignment:
      return "alignment";
    case CycleKind::kProbeLength:
      return "probe_length";
    case CycleKind::kTolerance:
      return "tolerance";
  }
  return "";
}

std::string_view CycleName(CycleKind k, const std::vector<Result>& results) {
  switch (k) {
    case CycleKind::kSurface:
    case CycleKind::kProbeLength:
      return "G26";
    case CycleKind::kCentre:
      return "G27";
    case CycleKind::kAlignment:
      // A is G26YZA only; G26 and G27 both write B and C ALIGNMENT and the file does not say which ran.
      return !results.empty() && results[0].quantity == Quantity::kAAlignment ? "G26" : "G26/G27";
    case CycleKind::kTolerance:
      return "G24";
  }
  return "";
}

CycleResult Surface(std::optional<long> n, Quantity q, double value) {
  if (q != Quantity::kXSurface && q != Quantity::kYSurface && q != Quantity::kZSurface)
    Invalid("a G26 surface is X, Y or Z SURFACE");
  return {CycleKind::kSurface, n, {{q, value, {}, {}}}};
}

CycleResult SurfaceXY(std::optional<long> n, double x, double y) {
  return {CycleKind::kSurface, n, {{Quantity::kXSurface, x, {}, {}}, {Quantity::kYSurface, y, {}, {}}}};
}

CycleResult Centre(std::optional<long> n, char axis, double separation, double centre) {
  if (axis != 'X' && axis != 'Y') Invalid("a G27 single-axis centre is X or Y");
  bool x = axis == 'X';
  return {CycleKind::kCentre,
          n,
          {{x ? Quantity::kXSeparation : Quantity::kYSeparation, separation, {}, {}},
           {x ? Quantity::kXCenter : Quantity::kYCenter, centre, {}, {}}}};
}

CycleResult CentreXY(std::optional<long> n, double separation, double x, double y) {
  return {CycleKind::kCentre,
          n,
          {{Quantity::kXYSeparation, separation, {}, {}},
           {Quantity::kXCenter, x, {}, {}},
           {Quantity::kYCenter, y, {}, {}}}};
}

CycleResult Alignment(std::optional<long> n, char axis, double angle) {
  Quantity q = axis == 'A'   ? Quantity::kAAlignment
               : axis == 'B' ? Quantity::kBAlignment
               : axis == 'C' ? Quantity::kCAlignment
                             : (Invalid("an alignment is A, B or C"), Quantity::kAAlignment);
  return {CycleKind::kAlignment, n, {{q, angle, {}, {}}}};
}

CycleResult ProbeLength(std::optional<long> n, double length) {
  return {CycleKind::kProbeLength, n, {{Quantity::kProbeLength, length, {}, {}}}};
}

CycleResult Tolerance(std::optional<long> n, char letter, double measured, double nominal, double tolerance) {
  static constexpr std::string_view kLetters = "RXYZABC";
  auto at = kLetters.find(letter);
  if (at == std::string_view::npos) Invalid("a G24 check is R, X, Y, Z, A, B or C");
  auto q = static_cast<Quantity>(static_cast<int>(Quantity::kToleranceR) + static_cast<int>(at));
  return {CycleKind::kTolerance, n, {{q, measured, nominal, tolerance}}};
}

CycleResult ToleranceXY(std::optional<long> n, double x, double x_nominal, double y, double y_nominal,
                        double tolerance) {
  return {
      CycleKind::kTolerance,
      n,
      {{Quantity::kToleranceX, x, x_nominal, tolerance}, {Quantity::kToleranceY, y, y_nominal, tolerance}}};
}

std::string FormatHeader(const Header& h) {
  const Stamp& s = h.created;
  if (s.month < 1 || s.month > 12 || s.day < 1 || s.day > 31 || s.hour < 0 || s.hour > 23 || s.minute < 0 ||
      s.minute > 59 || s.year < 1970 || s.year > 2069)
    Invalid("the header's date and time are out of range (years 1970-2069: the file keeps two digits)");
  std::string out;
  AppendLine(out, HeaderField(kSerial, h.serial));
  AppendLine(out, HeaderField(kPart, h.part));
  if (h.parts_completed) {
    if (*h.parts_completed < 0) Invalid("a negative number of part cycles completed");
    AppendLine(out, HeaderField(kCompleted, std::to_string(*h.parts_completed)));
  }
  AppendLine(out,
             fmt::format("{:02}:{:02}:{:02} {:02}:{:02}", s.year % 100, s.month, s.day, s.hour, s.minute));
  AppendLine(out, kDelimiter);
  return out;
}

std::string FormatCycle(const CycleResult& c) {
  if (!ValidShape(c)) Invalid(fmt::format("not a {} result App. E writes", KindName(c.kind)));
  if (c.n && *c.n < 0) Invalid("a negative N number");
  std::string out;
  if (c.n) AppendLine(out, fmt::format("N{}", *c.n));
  for (const Result& r : c.results) {
    std::string line = ResultLine(r);
    if (line.size() > kMaxLineChars)
      Invalid(fmt::format("'{}' is longer than {} characters", line, kMaxLineChars));
    AppendLine(out, line);
  }
  out += '\n';  // the cycle's closing (FWR,)
  return out;
}

std::string FormatLine(std::string_view text) {
  if (!Printable(text)) Invalid("a file line holds printable ASCII only (no control characters)");
  std::string out;
  AppendLine(out, text);
  return out;
}

std::string FormatMessage(std::string_view text) {
  return FormatLine(text) + "\n";
}

std::string Format(const InspectionFile& f) {
  std::string out = FormatHeader(f.header);
  for (const Entry& e : f.body) {
    if (const auto* c = std::get_if<CycleResult>(&e))
      out += FormatCycle(*c);
    else
      out += FormatLine(std::get<TextLine>(e).text);
  }
  return out;
}

void FileText::Flush() {
  if (!has_pending_) return;
  text_ += FormatLine(pending_);
  pending_.clear();
  has_pending_ = false;
}

void FileText::Open(const Header& h) {
  text_ = FormatHeader(h);
  pending_.clear();
  has_pending_ = false;
}

void FileText::Fwr(std::string_view piece, bool continued) {
  pending_ += piece;
  has_pending_ = true;
  if (!continued) Flush();
}

void FileText::Msg(std::string_view text) {
  Flush();
  text_ += FormatMessage(text);
}

void FileText::Cycle(const CycleResult& c) {
  Flush();
  text_ += FormatCycle(c);
}

}  // namespace cell::inspection
