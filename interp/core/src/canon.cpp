#include "cell/interp/canon.h"

#include <fmt/format.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace cell::interp {

const char* OpName(Op op) {
  switch (op) {
    case Op::kUnits:
      return "units";
    case Op::kRapid:
      return "rapid";
    case Op::kLinear:
      return "linear";
    case Op::kArc:
      return "arc";
    case Op::kThread:
      return "thread";
    case Op::kDwell:
      return "dwell";
    case Op::kSpindle:
      return "spindle";
    case Op::kCoolant:
      return "coolant";
    case Op::kToolSelect:
      return "tool_select";
    case Op::kToolChange:
      return "tool_change";
    case Op::kStop:
      return "stop";
    case Op::kEnd:
      return "end";
    case Op::kPallet:
      return "pallet";
    case Op::kMessage:
      return "message";
    case Op::kAlarm:
      return "alarm";
    case Op::kAux:
      return "aux";
    case Op::kRegrid:
      return "regrid";
    case Op::kProbe:
      return "probe";
    case Op::kOutput:
      return "output";
    case Op::kWaitInput:
      return "wait_input";
    case Op::kFileOpen:
      return "file_open";
    case Op::kFileWrite:
      return "file_write";
    case Op::kFileClose:
      return "file_close";
    case Op::kFileOp:
      return "file_op";
    case Op::kEvent:
      return "event";
    case Op::kToolData:
      return "tool_data";
    case Op::kOverrides:
      return "overrides";
  }
  return "unknown";
}

namespace {

// The writer's staging buffer: pieces are copied into a fixed local array and appended to the caller's
// string in one go (per-piece std::string appends dominated the cost of a line). Anything larger than the
// array goes straight through. Literals are copied with their length known at compile time, and short
// pieces of a bounded length (Room) as a fixed-size block the cursor then moves only part of the way
// over: both copies are inlined moves, not calls of memcpy.
class Buf {
 public:
  explicit Buf(std::string& out) : out_(out) {}
  Buf(const Buf&) = delete;
  Buf& operator=(const Buf&) = delete;
  ~Buf() { Flush(); }
  Buf& operator+=(char c) {
    if (p_ == end_) Flush();
    *p_++ = c;
    return *this;
  }
  template <size_t N>
  Buf& operator+=(const char (&s)[N]) {
    static_assert(N - 1 <= kCap);
    if (N - 1 > static_cast<size_t>(end_ - p_)) Flush();
    std::memcpy(p_, s, N - 1);
    p_ += N - 1;
    return *this;
  }
  Buf& operator+=(std::string_view s) {
    if (s.size() > static_cast<size_t>(end_ - p_)) {
      Flush();
      if (s.size() > kCap) {
        out_.append(s);
        return *this;
      }
    }
    std::memcpy(p_, s.data(), s.size());
    p_ += s.size();
    return *this;
  }
  void append(const char* p, size_t n) { *this += std::string_view(p, n); }
  // At least n bytes free at the cursor (n <= kCap).
  char* Room(size_t n) {
    if (n > static_cast<size_t>(end_ - p_)) Flush();
    return p_;
  }
  void Advance(size_t n) { p_ += n; }
  void Flush() {
    out_.append(buf_, static_cast<size_t>(p_ - buf_));
    p_ = buf_;
  }

 private:
  static constexpr size_t kCap = 512;
  char buf_[kCap];
  char* p_ = buf_;
  char* const end_ = buf_ + kCap;
  std::string& out_;
};

// Appends v with six decimals, trailing zeros trimmed down to four ("1.5000", "0.000125"), exactly as
// fmt's correctly rounded "{:.6f}" would. The fast path scales to integer micro-units; it is taken only
// when the scaled value is clear of a rounding tie by far more than the product's rounding error, so the
// digits never differ from the slow path (which handles ties, huge values and non-finite input).
// Recently written numbers, by bit pattern: a toolpath repeats most values from line to line (the feed, an
// axis that does not move, arc centres), and copying the text is cheaper than formatting it again.
struct NumCacheEntry {
  uint64_t bits = 0;
  uint8_t len = 0;  // 0: empty
  char text[23];
};
thread_local NumCacheEntry num_cache[64];

// "00" .. "99": numbers are written two digits at a time.
constexpr char kPairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

// A number the cache does not hold: formatted, and kept in `hit` when the fast path wrote it. Out of line, so
// that the cache hit (most numbers) is a short function that saves no registers.
[[gnu::noinline]] void NumMiss(Buf& out, double v, uint64_t bits, NumCacheEntry& hit) {
  if (!std::isfinite(v)) {
    out += '0';
    return;
  }
  if (std::fabs(v) < 5e-7) v = 0;  // no "-0.000000"
  double a = std::fabs(v) * 1e6;
  if (a < 1e12) {
    auto whole = static_cast<uint64_t>(a);
    double frac = a - static_cast<double>(whole);
    if (std::fabs(frac - 0.5) > 1e-3) {
      uint64_t r = whole + (frac > 0.5 ? 1 : 0);
      char buf[48];  // the digits end at e; at most 14 characters, copied as a fixed 16 (room behind e)
      char* e = buf + 32;
      char* p = e;
      auto ip = static_cast<uint32_t>(r / 1000000);  // < 10^6: 32-bit division is cheaper
      auto fp = static_cast<uint32_t>(r % 1000000);
      for (int k = 0; k < 3; ++k) {  // six fraction digits, two at a time
        uint32_t d = fp % 100;
        fp /= 100;
        p -= 2;
        p[0] = kPairs[2 * d];
        p[1] = kPairs[2 * d + 1];
      }
      char* end = e;
      if (end[-1] == '0') --end;  // at most two trailing zeros dropped: four decimals stay
      if (end[-1] == '0') --end;
      *--p = '.';
      do {
        *--p = static_cast<char>('0' + ip % 10);
        ip /= 10;
      } while (ip);
      if (v < 0) *--p = '-';
      auto n = static_cast<size_t>(end - p);
      static_assert(sizeof hit.text >= 16);
      hit.bits = bits;
      hit.len = static_cast<uint8_t>(n);
      std::memcpy(hit.text, p, 16);
      std::memcpy(out.Room(16), p, 16);
      out.Advance(n);
      return;
    }
  }
  std::string s = fmt::format("{:.6f}", v);
  auto dot = s.find('.');
  while (s.size() > dot + 5 && s.back() == '0') s.pop_back();
  out += std::string_view(s);
}

void Num(Buf& out, double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  NumCacheEntry& hit = num_cache[(bits * 0x9E3779B97F4A7C15ull) >> 58];
  // A non-finite value is never cached (the miss path writes it without filling the entry).
  if (hit.len != 0 && hit.bits == bits) [[likely]] {
    std::memcpy(out.Room(sizeof hit.text), hit.text, sizeof hit.text);  // all of it: a fixed-size move
    out.Advance(hit.len);
    return;
  }
  NumMiss(out, v, bits, hit);
}

void Int(Buf& out, long v) {
  char buf[48];  // at most 20 digits and a sign, ending at e; copied as a fixed 24 (room behind e)
  char* e = buf + 24;
  char* p = e;
  unsigned long u = v < 0 ? 0ul - static_cast<unsigned long>(v) : static_cast<unsigned long>(v);
  while (u >= 100) {  // every line's number: two digits per division
    const unsigned long d = u % 100;
    u /= 100;
    p -= 2;
    std::memcpy(p, kPairs + 2 * d, 2);
  }
  if (u >= 10) {
    p -= 2;
    std::memcpy(p, kPairs + 2 * u, 2);
  } else {
    *--p = static_cast<char>('0' + u);
  }
  if (v < 0) *--p = '-';
  std::memcpy(out.Room(24), p, 24);
  out.Advance(static_cast<size_t>(e - p));
}

void Str(Buf& out, std::string_view s) {
  out += '"';
  for (unsigned char ch : s) {
    switch (ch) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (ch < 0x20 || ch >= 0x7f) {
          out += std::string_view(fmt::format("\\u{:04x}", ch));
        } else {
          out += static_cast<char>(ch);
        }
    }
  }
  out += '"';
}

template <size_t N>
void Key(Buf& out, const char (&k)[N]) {
  out += ",\"";
  out += k;
  out += "\":";
}

void Axes(Buf& out, const Target& t) {
  // `,"x":` is five characters for every axis: a fixed-size copy (padded to eight), not a call of memcpy.
  static constexpr char kKeys[kAxisCount][8] = {
      ",\"x\":", ",\"y\":", ",\"z\":", ",\"a\":", ",\"b\":", ",\"c\":", ",\"u\":", ",\"v\":", ",\"w\":"};
  // Only the set bits, lowest axis first (the order of kKeys): most moves name two or three of nine axes.
  for (uint32_t m = t.used & ((1u << kAxisCount) - 1); m != 0; m &= m - 1) {
    const int i = std::countr_zero(m);
    std::memcpy(out.Room(8), kKeys[i], 8);
    out.Advance(5);
    Num(out, t.pos[i]);
  }
  for (uint32_t m = t.travel_mask & ((1u << kAxisCount) - 1); m != 0; m &= m - 1) {
    const int i = std::countr_zero(m);
    out += ",\"";
    out += AxisName(i);
    out += "_travel\":";
    Num(out, t.travel[i]);
  }
}

void FeedOf(Buf& out, const Feed& f, bool with_exact_stop) {
  out += std::string_view(",\"f\":");
  Num(out, f.rate);
  switch (f.mode) {
    case FeedMode::kPerMinute:
      break;
    case FeedMode::kInverseTime:
      out += ",\"f_mode\":\"inverse_time\"";
      break;
    case FeedMode::kPerRev:
      out += ",\"f_mode\":\"per_rev\"";
      break;
    case FeedMode::kDegPerMinute:
      out += ",\"f_mode\":\"deg_per_min\"";
      break;
  }
  if (with_exact_stop && f.exact_stop) out += ",\"exact_stop\":true";
}

template <size_t N>
void Bool(Buf& out, const char (&key)[N], bool v) {
  Key(out, key);
  out += v ? std::string_view("true") : std::string_view("false");
}

// One writer per payload type (overload set for std::visit).
struct Writer {
  Buf& out;
  void operator()(const UnitsOp& u) const {
    out += u.metric ? std::string_view(",\"length\":\"mm\"") : std::string_view(",\"length\":\"inch\"");
    out += u.x_mode == XMode::kDiameter ? std::string_view(",\"x_mode\":\"diameter\"")
                                        : std::string_view(",\"x_mode\":\"radius\"");
  }
  void operator()(const RapidOp& r) const { Axes(out, r.to); }
  void operator()(const LinearOp& l) const {
    Axes(out, l.to);
    FeedOf(out, l.feed, true);
  }
  void operator()(const ArcOp& a) const {
    Axes(out, a.to);
    FeedOf(out, a.feed, true);
    out += ",\"center\":[";
    Num(out, a.center[0]);
    out += ',';
    Num(out, a.center[1]);
    out += ',';
    Num(out, a.center[2]);
    out += ']';
    out += a.cw ? std::string_view(",\"dir\":\"cw\"") : std::string_view(",\"dir\":\"ccw\"");
    const char plane[2] = {AxisName(a.plane.first)[0], AxisName(a.plane.second)[0]};
    out += std::string_view(",\"plane\":\"");
    out += std::string_view(plane, 2);
    out += '"';
    Key(out, "angle");
    Num(out, a.angle);
  }
  void operator()(const ThreadOp& t) const {
    Axes(out, t.to);
    Key(out, "lead");
    Num(out, t.lead);
    if (t.lead_change != 0) {
      Key(out, "lead_change");
      Num(out, t.lead_change);
    }
    Key(out, "start_angle");
    Num(out, t.start_angle);
    if (t.exact_stop) out += ",\"exact_stop\":true";
  }
  void operator()(const DwellOp& d) const {
    Key(out, "seconds");
    Num(out, d.seconds);
  }
  void operator()(const SpindleOp& s) const {
    if (s.spindle != SpindleId::kMain) {  // the main spindle's ops keep their form
      Key(out, "spindle");
      Str(out, SpindleIdName(s.spindle));
    }
    Key(out, "dir");
    Str(out, SpindleDirName(s.dir));
    Key(out, "s");
    Num(out, s.rpm);
    if (s.dir == SpindleDir::kOrient) {
      Key(out, "angle");
      Num(out, s.angle);
    }
    if (s.css > 0) {
      Key(out, "css");
      Num(out, s.css);
    }
    if (s.max_rpm > 0) {
      Key(out, "max_rpm");
      Num(out, s.max_rpm);
    }
  }
  void operator()(const CoolantOp& c) const {
    Key(out, "m");
    Int(out, c.m);
    Key(out, "mode");
    Str(out, CoolantModeName(c.mode));
  }
  void operator()(const ToolSelectOp& t) const {
    Key(out, "tool");
    Str(out, t.tool);
  }
  void operator()(const ToolChangeOp& t) const {
    Key(out, "tool");
    Str(out, t.tool);
    if (t.offset != 0) {
      Key(out, "offset");
      Int(out, t.offset);
    }
    if (t.tip >= 0) {
      Key(out, "tip");
      Int(out, t.tip);
    }
    if (t.socket != 0) {
      Key(out, "socket");
      Int(out, t.socket);
    }
  }
  void operator()(const StopOp& s) const {
    Key(out, "m");
    Int(out, s.m);
    Bool(out, "optional", s.optional);
    if (!s.why.empty()) {
      Key(out, "why");
      Str(out, s.why);
    }
  }
  void operator()(const EndOp& e) const {
    Key(out, "m");
    Int(out, e.m);
    Bool(out, "shuttle", e.shuttle);
  }
  void operator()(const PalletOp& p) const {
    Key(out, "m");
    Int(out, p.m);
  }
  void operator()(const MessageOp& m) const {
    Key(out, "text");
    Str(out, m.text);
  }
  void operator()(const AlarmOp& a) const {
    Key(out, "text");
    Str(out, a.text);
  }
  void operator()(const AuxOp& a) const {
    Key(out, "m");
    Int(out, a.m);
  }
  void operator()(const RegridOp& r) const { Axes(out, r.to); }
  void operator()(const ProbeOp& p) const {
    Key(out, "g");
    Int(out, p.g);
    Axes(out, p.to);
    FeedOf(out, p.feed, false);
    Key(out, "result");
    Str(out, ProbeOutcomeName(p.result));
  }
  void operator()(const OutputOp& o) const {
    Key(out, "spec");
    Str(out, o.spec);
  }
  void operator()(const WaitInputOp& w) const {
    Key(out, "spec");
    Str(out, w.spec);
  }
  void operator()(const FileOpenOp& f) const {
    Key(out, "name");
    Str(out, f.name);
    Key(out, "type");
    Str(out, f.type);
    Bool(out, "append", f.append);
    if (f.inspection) out += std::string_view(",\"inspection\":true");
  }
  void operator()(const FileWriteOp& f) const {
    Key(out, "text");
    Str(out, f.text);
  }
  void operator()(const FileCloseOp&) const {}
  void operator()(const FileOpOp& f) const {
    Key(out, "what");
    Str(out, f.what);
    Key(out, "args");
    Str(out, f.args);
  }
  void operator()(const EventOp& e) const {
    Key(out, "text");
    Str(out, e.text);
  }
  void operator()(const OverridesOp& o) const { Bool(out, "fixed", o.fixed); }
  void operator()(const ToolDataOp& t) const {
    Key(out, "tool");
    Str(out, t.cleared ? std::string_view("*") : std::string_view(t.entry.tool));
    Key(out, "length");
    Num(out, t.entry.length);
    Key(out, "diameter");
    Num(out, t.entry.diameter);
    if (t.pallet != 0) {
      Key(out, "pallet");
      Int(out, t.pallet);
    }
    // Lathe data only where a dialect sets it (KT-APL lines stay as they were).
    if (t.entry.x_offset != 0 || t.entry.z_offset != 0 || t.entry.nose_radius != 0 || t.entry.tip != 0) {
      Key(out, "x_offset");
      Num(out, t.entry.x_offset);
      Key(out, "z_offset");
      Num(out, t.entry.z_offset);
      Key(out, "nose_radius");
      Num(out, t.entry.nose_radius);
      Key(out, "tip");
      Int(out, t.entry.tip);
    }
  }
};

}  // namespace

const char* SpindleDirName(SpindleDir d) {
  switch (d) {
    case SpindleDir::kStop:
      return "stop";
    case SpindleDir::kCw:
      return "cw";
    case SpindleDir::kCcw:
      return "ccw";
    case SpindleDir::kOrient:
      return "orient";
    case SpindleDir::kAxis:
      return "axis";
  }
  return "stop";
}

const char* SpindleIdName(SpindleId s) {
  return s == SpindleId::kLiveTool ? "live_tool" : "main";
}

const char* CoolantModeName(CoolantMode m) {
  switch (m) {
    case CoolantMode::kOff:
      return "off";
    case CoolantMode::kMist:
      return "mist";
    case CoolantMode::kFlood:
      return "flood";
    case CoolantMode::kWashFlood:
      return "wash_flood";
    case CoolantMode::kWashAir:
      return "wash_air";
    case CoolantMode::kAuxMist:
      return "aux_mist";
    case CoolantMode::kAuxFlood:
      return "aux_flood";
    case CoolantMode::kAuxPulse:
      return "aux_pulse";
  }
  return "off";
}

const char* ProbeOutcomeName(ProbeOutcome r) {
  switch (r) {
    case ProbeOutcome::kContact:
      return "contact";
    case ProbeOutcome::kBreak:
      return "break";
    case ProbeOutcome::kNone:
      return "none";
    case ProbeOutcome::kAlready:
      return "already";
    case ProbeOutcome::kToolOk:
      return "tool_ok";
    case ProbeOutcome::kToolBroken:
      return "tool_broken";
  }
  return "none";
}

Target* Canon::target() {
  switch (op()) {
    case Op::kRapid:
      return &std::get<RapidOp>(p).to;
    case Op::kLinear:
      return &std::get<LinearOp>(p).to;
    case Op::kArc:
      return &std::get<ArcOp>(p).to;
    case Op::kThread:
      return &std::get<ThreadOp>(p).to;
    case Op::kRegrid:
      return &std::get<RegridOp>(p).to;
    case Op::kProbe:
      return &std::get<ProbeOp>(p).to;
    default:
      return nullptr;
  }
}

Feed* Canon::feed() {
  switch (op()) {
    case Op::kLinear:
      return &std::get<LinearOp>(p).feed;
    case Op::kArc:
      return &std::get<ArcOp>(p).feed;
    case Op::kProbe:
      return &std::get<ProbeOp>(p).feed;
    default:
      return nullptr;
  }
}

std::string ToJsonLine(const Canon& c) {
  std::string out;
  AppendJsonLine(out, c);
  return out;
}

namespace {

// Every op's `{"op":"<name>","line":`, padded to a fixed size: copied whole, as a cached number.
struct OpPrefix {
  char text[32];
  uint8_t len;
};

const std::array<OpPrefix, kOpCount>& OpPrefixes() {
  static const std::array<OpPrefix, kOpCount> table = [] {
    std::array<OpPrefix, kOpCount> t{};
    for (int i = 0; i < kOpCount; ++i) {
      std::string s = std::string("{\"op\":\"") + OpName(static_cast<Op>(i)) + "\",\"line\":";
      std::memcpy(t[i].text, s.data(), s.size());  // at most 27 characters (tool_select)
      t[i].len = static_cast<uint8_t>(s.size());
    }
    return t;
  }();
  return table;
}

}  // namespace

void AppendJsonLine(std::string& str, const Canon& c) {
  Buf out(str);
  const OpPrefix& prefix = OpPrefixes()[static_cast<size_t>(c.op())];
  std::memcpy(out.Room(sizeof prefix.text), prefix.text, sizeof prefix.text);
  out.Advance(prefix.len);
  Int(out, c.line);
  std::visit(Writer{out}, c.p);
  out += '}';
}

}  // namespace cell::interp
