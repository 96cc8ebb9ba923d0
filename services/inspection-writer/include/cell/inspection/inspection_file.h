// The KT-APL process inspection file (manual PUB 929A, Ch. 7 "Type II commands related to spindle probe
// inspection", ln 7886-8254, and the lines App. E's probe cycles write, ln 11745-13068): its text as the
// control writes it, the text read back into records, and the records as CSV and QIF 3.0.
// docs/dialects/ktapl.md "Inspection files" is the format's reference and its judgement calls.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "cell/error/error.h"

namespace cell::inspection {

// Every line of a file holds at most this many characters (ln 8075, 8101); the control cuts longer ones.
inline constexpr std::size_t kMaxLineChars = 80;

// The control's 8-significant-digit number (FWR `Ln`, ln 8168-8171): 9.8000000, -45.670000, .25000000.
// The interpreter's own format (cell::interp::FormatKtNumber), so a file reads the same from both.
std::string FormatNumber(double v);
// FWR `LnI` (ln 8181: the integer part, no point) and `LnR` (ln 7947-7952: rounded to a whole number).
std::string FormatTruncated(double v);
std::string FormatRounded(double v);

// YY:MM:DD HH:MM (ln 7904-7908). `year` is the full year; the file keeps two digits, read back as
// 1970-2069.
struct Stamp {
  int year = 1970, month = 1, day = 1, hour = 0, minute = 0;
  bool operator==(const Stamp&) const = default;
};

// The canned lines OIF (or MSG,NAM) writes when it creates the file (ln 7898-7908).
struct Header {
  std::string serial;  // CONTROL SERIAL NUMBER (L3060)
  std::string part;    // PALLET CODE/PART NUMBER
  // Part 1's G36 list (ln 1553-1557) also names the number of part cycles completed; Ch. 7's examples
  // print no such line, so it is written only when known (docs/dialects/ktapl.md).
  std::optional<long> parts_completed;
  Stamp created;
  bool operator==(const Header&) const = default;
};

// What a probe cycle measured, as App. E names it in its FWR lines.
enum class Quantity {
  kXSurface,      // G26X, G26XY/RA: X SURFACE
  kYSurface,      // G26Y, G26XY/RA: Y SURFACE
  kZSurface,      // G26Z: Z SURFACE
  kXSeparation,   // G27X, G27XZE: X SURFACE SEPARATION (L1005)
  kYSeparation,   // G27Y, G27YZE: Y SURFACE SEPARATION
  kXYSeparation,  // G27XY/RA(ZE): X,Y SURFACE SEPARATION
  kXCenter,       // G27: X CENTER
  kYCenter,       // G27: Y CENTER
  kAAlignment,    // G26YZA: A ALIGNMENT
  kBAlignment,    // G26XZB, G27B: B ALIGNMENT
  kCAlignment,    // G26YZC, G27C: C ALIGNMENT
  kProbeLength,   // G26T0Z: SPINDLE PROBE LENGTH
  kToleranceR,    // G24R: separation L1005 against R (the cell's G24 line)
  kToleranceX,    // G24X, G24XY
  kToleranceY,    // G24Y, G24XY
  kToleranceZ,    // G24Z: Z - (L3029 - L3033) against Z
  kToleranceA,    // G24A
  kToleranceB,    // G24B
  kToleranceC,    // G24C
};

// The label the line carries ("X SURFACE", "G24 X", ...).
std::string_view Label(Quantity q);
// Linear (inch or mm as the program ran) or angular (degrees).
bool IsAngular(Quantity q);
bool IsTolerance(Quantity q);

struct Result {
  Quantity quantity = Quantity::kXSurface;
  double value = 0;
  // G24 only: the programmed position (its letter) and E, the half-width of the band (ln 1043, 11792).
  std::optional<double> nominal, tolerance;
  bool operator==(const Result&) const = default;
};

enum class CycleKind {
  kSurface,      // G26 X, Y, Z, XY, RA: surface positions
  kCentre,       // G27 X, Y, XY, RA and the E (hub, groove) forms: bore or boss centre and separation
  kAlignment,    // G26 XZB/YZA/YZC, G27 B/C: the rotary position that squares the face or centres the feature
  kProbeLength,  // G26T0Z
  kTolerance,    // G24 (a cell addition: App. E's G24 writes no line)
};
std::string_view KindName(CycleKind k);  // "surface", "centre", ...
// The cycles that write this kind of result: "G26", "G27", "G26/G27" (B and C alignment), "G24".
std::string_view CycleName(CycleKind k, const std::vector<Result>& results);

// One probe cycle's block of lines: `N<n>` when the block had an N word (ln 12273-12275), its result
// lines, and the empty line of its closing (FWR,).
struct CycleResult {
  CycleKind kind = CycleKind::kSurface;
  std::optional<long> n;
  std::vector<Result> results;
  bool operator==(const CycleResult&) const = default;
};

// The results a cycle writes, in App. E's order.
CycleResult Surface(std::optional<long> n, Quantity axis_surface, double value);  // kX/kY/kZSurface
CycleResult SurfaceXY(std::optional<long> n, double x, double y);
CycleResult Centre(std::optional<long> n, char axis, double separation, double centre);  // 'X' or 'Y'
CycleResult CentreXY(std::optional<long> n, double separation, double x, double y);
CycleResult Alignment(std::optional<long> n, char axis, double angle);  // 'A', 'B' or 'C'
CycleResult ProbeLength(std::optional<long> n, double length);
// letter R X Y Z A B C; `measured` is what G24 compares (L1005 for R, Z - (L3029 - L3033) for Z, else the
// axis position).
CycleResult Tolerance(std::optional<long> n, char letter, double measured, double nominal, double tolerance);
CycleResult ToleranceXY(std::optional<long> n, double x, double x_nominal, double y, double y_nominal,
                        double tolerance);

// Any other line: FWR text, MSG text and the empty line after it, a blank (FWR,).
struct TextLine {
  std::string text;
  bool operator==(const TextLine&) const = default;
};

using Entry = std::variant<CycleResult, TextLine>;

struct InspectionFile {
  Header header;
  std::vector<Entry> body;
  bool operator==(const InspectionFile&) const = default;
};

// Text as the control writes it, every line ending in '\n'. Throws Error(kInvalidArgument) for what the
// control could not write: a header field that is empty, holds a control character or makes its line
// longer than 80 characters; a cycle whose results are not a shape App. E writes.
std::string FormatHeader(const Header& h);
std::string FormatCycle(const CycleResult& c);
std::string FormatLine(std::string_view text);     // FWR: one line, cut to 80 characters
std::string FormatMessage(std::string_view text);  // MSG: the text cut to 80, then one empty line (ln 8045)
std::string Format(const InspectionFile& f);

// A file's text as the writer builds it, statement by statement: OIF's header, FWR lines (a piece ending in
// ';' continues on the same line, ln 8187-8189), MSG lines and the probe cycles' blocks.
class FileText {
 public:
  void Open(const Header& h);  // OIF / (MSG,NAM,..): the canned header (OPF writes none)
  // One FWR's resolved text; `continued` when the statement ended in ';' (the next FWR joins this line).
  void Fwr(std::string_view piece, bool continued = false);
  void Msg(std::string_view text);
  void Cycle(const CycleResult& c);
  const std::string& str() const { return text_; }

 private:
  void Flush();
  std::string text_, pending_;
  bool has_pending_ = false;
};

// A file that is not what Format writes: the 1-based line and column of the first problem.
class ParseError : public Error {
 public:
  ParseError(int line, int column, const std::string& reason);
  int line() const { return line_; }
  int column() const { return column_; }
  const std::string& reason() const { return reason_; }

 private:
  int line_, column_;
  std::string reason_;
};

// Reads a closed inspection file. Accepts what the manual's listings print besides the canonical form:
// any spacing around '=' and inside labels ("XSURFACE=", "BALIGNMENT ="), CR LF line ends, any dashed
// delimiter of three dashes or more.
InspectionFile Parse(std::string_view text);

// A measured quantity with what the exports need.
enum class LinearUnit { kInch, kMillimetre };
struct Characteristic {
  int feature = 0;  // 1-based: the cycle result in the file
  CycleKind kind = CycleKind::kSurface;
  std::string_view cycle;
  std::optional<long> n;
  Result result;
  std::string_view unit;  // "inch", "mm" or "degree"
  // PASS, FAIL (|value - nominal| > tolerance, as G24 tests it, ln 11807) or nullopt without a tolerance.
  std::optional<bool> pass;
};
std::vector<Characteristic> Characteristics(const InspectionFile& f, LinearUnit unit);

// One row per measured quantity after a header row; RFC 4180 (CRLF, fields with , " CR LF quoted).
std::string ToCsv(const InspectionFile& f, LinearUnit unit);

// A QIF 3.0 QIFDocument: Product (the part number), Characteristics (definition, nominal, item per
// measured quantity; G24's nominal and tolerance where given) and MeasurementResults (an actual each).
// `name` (the file's name) goes into the header's scope. The document's id is derived from the content, so
// the same file always exports to the same document.
std::string ToQif(const InspectionFile& f, LinearUnit unit, std::string_view name);

}  // namespace cell::inspection
