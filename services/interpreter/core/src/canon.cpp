#include "cell/interp/canon.h"

#include <fmt/format.h>

#include <cmath>
#include <cstring>
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
  }
  return "unknown";
}

namespace {

// The writer's staging buffer: pieces are copied into a fixed local array and appended to the caller's
// string in one go (per-piece std::string appends dominated the cost of a line). Anything larger than the
// array goes straight through.
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

void Num(Buf& out, double v) {
  if (!std::isfinite(v)) {
    out += '0';
    return;
  }
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  NumCacheEntry& hit = num_cache[(bits * 0x9E3779B97F4A7C15ull) >> 58];
  if (hit.len != 0 && hit.bits == bits) {
    out += std::string_view(hit.text, hit.len);
    return;
  }
  if (std::fabs(v) < 5e-7) v = 0;  // no "-0.000000"
  double a = std::fabs(v) * 1e6;
  if (a < 1e12) {
    auto whole = static_cast<uint64_t>(a);
    double frac = a - static_cast<double>(whole);
    if (std::fabs(frac - 0.5) > 1e-3) {
      uint64_t r = whole + (frac > 0.5 ? 1 : 0);
      char buf[32];
      char* e = buf + sizeof buf;
      char* p = e;
      auto ip = static_cast<uint32_t>(r / 1000000);  // < 10^6: 32-bit division is cheaper
      auto fp = static_cast<uint32_t>(r % 1000000);
      static constexpr char kPairs[] =
          "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
          "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
          "8081828384858687888990919293949596979899";
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
      if (n <= sizeof hit.text) {
        hit.bits = bits;
        hit.len = static_cast<uint8_t>(n);
        std::memcpy(hit.text, p, n);
      }
      out.append(p, n);
      return;
    }
  }
  std::string s = fmt::format("{:.6f}", v);
  auto dot = s.find('.');
  while (s.size() > dot + 5 && s.back() == '0') s.pop_back();
  out += std::string_view(s);
}

void Int(Buf& out, long v) {
  char buf[24];
  char* e = buf + sizeof buf;
  char* p = e;
  unsigned long u = v < 0 ? 0ul - static_cast<unsigned long>(v) : static_cast<unsigned long>(v);
  do {
    *--p = static_cast<char>('0' + u % 10);
    u /= 10;
  } while (u);
  if (v < 0) *--p = '-';
  out.append(p, static_cast<size_t>(e - p));
}

void Str(Buf& out, const std::string& s) {
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

void Key(Buf& out, const char* k) {
  out += ",\"";
  out += k;
  out += "\":";
}

void Axes(Buf& out, const Canon& c) {
  static constexpr std::string_view kKeys[kAxisCount] = {
      ",\"x\":", ",\"y\":", ",\"z\":", ",\"a\":", ",\"b\":", ",\"c\":", ",\"u\":", ",\"v\":", ",\"w\":"};
  for (int i = 0; i < kAxisCount; ++i) {
    if (c.used & (1u << i)) {
      out += kKeys[i];
      Num(out, c.pos[i]);
    }
  }
  for (int i = 0; i < kAxisCount; ++i) {
    if (c.travel_mask & (1u << i)) {
      out += ",\"";
      out += AxisName(i);
      out += "_travel\":";
      Num(out, c.travel[i]);
    }
  }
}

void Feed(Buf& out, const Canon& c) {
  out += std::string_view(",\"f\":");
  Num(out, c.feed);
  switch (c.f_mode) {
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
}

}  // namespace

std::string ToJsonLine(const Canon& c) {
  std::string out;
  AppendJsonLine(out, c);
  return out;
}

void AppendJsonLine(std::string& str, const Canon& c) {
  Buf out(str);
  out += std::string_view("{\"op\":\"");
  out += OpName(c.op);
  out += std::string_view("\",\"line\":");
  Int(out, c.line);
  switch (c.op) {
    case Op::kUnits:
      out += c.metric ? ",\"length\":\"mm\"" : ",\"length\":\"inch\"";
      out += ",\"x_mode\":\"radius\"";
      break;
    case Op::kRapid:
      Axes(out, c);
      break;
    case Op::kLinear:
      Axes(out, c);
      Feed(out, c);
      if (c.exact_stop) out += ",\"exact_stop\":true";
      break;
    case Op::kArc:
      Axes(out, c);
      Feed(out, c);
      if (c.exact_stop) out += ",\"exact_stop\":true";
      out += ",\"center\":[";
      Num(out, c.center[0]);
      out += ',';
      Num(out, c.center[1]);
      out += ',';
      Num(out, c.center[2]);
      out += ']';
      out += c.cw ? ",\"dir\":\"cw\"" : ",\"dir\":\"ccw\"";
      Key(out, "plane");
      Str(out, c.plane);
      Key(out, "angle");
      Num(out, c.turns);
      break;
    case Op::kDwell:
      Key(out, "seconds");
      Num(out, c.value);
      break;
    case Op::kSpindle:
      Key(out, "dir");
      Str(out, c.text);
      Key(out, "s");
      Num(out, c.value);
      if (c.text == "orient") {
        Key(out, "angle");
        Num(out, c.value2);
      }
      break;
    case Op::kCoolant:
      Key(out, "m");
      Int(out, c.code);
      Key(out, "mode");
      Str(out, c.text);
      break;
    case Op::kToolSelect:
    case Op::kToolChange:
      Key(out, "tool");
      Str(out, c.text);
      break;
    case Op::kStop:
      Key(out, "m");
      Int(out, c.code);
      out += c.flag ? ",\"optional\":true" : ",\"optional\":false";
      break;
    case Op::kEnd:
      Key(out, "m");
      Int(out, c.code);
      out += c.flag ? ",\"shuttle\":true" : ",\"shuttle\":false";
      break;
    case Op::kPallet:
      Key(out, "m");
      Int(out, c.code);
      break;
    case Op::kMessage:
    case Op::kAlarm:
    case Op::kEvent:
      Key(out, "text");
      Str(out, c.text);
      break;
    case Op::kAux:
      Key(out, "m");
      Int(out, c.code);
      break;
    case Op::kRegrid:
      Axes(out, c);
      break;
    case Op::kProbe:
      Key(out, "g");
      Int(out, c.code);
      Axes(out, c);
      Feed(out, c);
      Key(out, "result");
      Str(out, c.text);
      break;
    case Op::kOutput:
    case Op::kWaitInput:
      Key(out, "spec");
      Str(out, c.text);
      break;
    case Op::kFileOpen:
      Key(out, "name");
      Str(out, c.text);
      Key(out, "type");
      Str(out, c.text2);
      out += c.flag ? ",\"append\":true" : ",\"append\":false";
      if (c.code) out += ",\"inspection\":true";
      break;
    case Op::kFileWrite:
      Key(out, "text");
      Str(out, c.text);
      break;
    case Op::kFileClose:
      break;
    case Op::kFileOp:
      Key(out, "what");
      Str(out, c.text2);
      Key(out, "args");
      Str(out, c.text);
      break;
    case Op::kToolData:
      Key(out, "tool");
      Str(out, c.text);
      Key(out, "length");
      Num(out, c.value);
      Key(out, "diameter");
      Num(out, c.value2);
      break;
  }
  out += '}';
}

}  // namespace cell::interp
