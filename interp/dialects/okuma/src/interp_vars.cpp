// Okuma variables (manual SECTION 13, seed ln 7549-7918, 8236-8474): common variables V1-V200 (the station
// keeps them), local variables with their CALL/RTS registration rules, system variables (zero offsets and
// shifts, tool offsets, nose radius, positions, limits, user alarm comments), I/O variables with the user
// alarms VDOUT[991-993], and the RS232C channel of READ/WRITE/GET/PUT (the station's line, or a virtual one).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "cell/interp/serial.h"
#include "interp_internal.h"

namespace cell::interp::okuma {
namespace {

bool Indexed(const std::string& n) {
  static constexpr std::string_view kIndexed[] = {
      "VTOFZ", "VTOFX", "VTSOY", "VNSRZ", "VNSRX", "VNSRP", "VPFVZ", "VPFVX", "VPFVC", "VPFVY", "VPFVT",
      "VUACM", "VTLGN", "VTLSN", "VTLCN", "VTLST", "VTLCT", "VTLSA", "VTLCA", "VTLOA", "VTLOB", "VTLOC",
      "VTLUS", "VTLNG", "VTLLF", "VGRSL", "VGRLF", "VGRID", "VXMP0", "VXMCD", "VXMON", "VXMTG", "VXMOG",
      "VXMXZ", "VXMNC", "VXMCO", "VXMMC", "VXMMO", "VXMMD", "VXMDR", "VIMDZ", "VIMDX", "VTOAA", "VTOBA",
      "VTOCA", "VTOAB", "VTOBB", "VTOCB", "VLMON", "VTLIN", "VTLFN", "VTLA1", "VTLA2", "VTLL",  "VTLD",
      "VTLW",  "VTIZN", "VTIZP", "VTIXN", "VTIXP", "VTIPN", "VGRIN", "VGRFN", "VGRA1", "VGRA2", "VGRL",
      "VGRD",  "VGRW",  "VEXPO", "VEXTR", "VEXAX", "VEXGF", "VEXTO", "VEXOG", "VEXOK", "VEXFB", "VEXDR",
      "VCEJM", "VMCN",  "VMDT",  "VWKCS", "VWKCC", "VRZV",  "VRCV",  "VRRG",  "VRVY",  "VRBV",  "VRVW",
      "VRVX",  "VLZV",  "VLYV",  "VLRG",  "VDIN",  "VDOUT", "VIRD",  "VORD",
  };
  return std::find(std::begin(kIndexed), std::end(kIndexed), n) != std::end(kIndexed);
}

bool ReadOnly(const std::string& n) {
  static constexpr std::string_view kReadOnly[] = {
      "VSIOZ", "VSIOY", "VSIOX", "VSIOC", "VAPAZ", "VAPAX", "VSKPZ", "VSKPY", "VSKPX", "VSKPC",
      "VETFZ", "VETFY", "VETFX", "VDIFZ", "VDIFX", "VETON", "VETLN", "VAPPZ", "VAPPX", "VMIRZ",
      "VRSTT", "VPAI",  "VTOPC", "VSNWD", "VSNTU", "VDIN",  "VIRD",  "VORD",  "VRUND", "VUNIT"};
  return std::find(std::begin(kReadOnly), std::end(kReadOnly), n) != std::end(kReadOnly);
}

// System variables that set the servo (droop amount ln 7779-7784, pitch-error compensation ln 7786-7796, the
// T axis' rapid ln 9911).
const char* ServoParameter(const std::string& stem) {
  if (stem == "VINP") return "droop amount, ln 7779-7784";
  if (stem == "VPFV" || stem == "VPCH") return "pitch-error compensation, ln 7786-7796";
  if (stem == "VTRT") return "T-axis rapid feedrate, ln 9911";
  return nullptr;
}

int IndexOf(const std::string& name, const Value* index, int col, int lo, int hi) {
  if (!index) Fail(col, fmt::format("{} needs a suffix [n]", name));
  double v = index->v;
  if (v != std::floor(v) || v < lo || v > hi)
    Fail(col, fmt::format("{}[{}]: the suffix is {}-{}", name, v, lo, hi));
  return static_cast<int>(v);
}

int AxisOfSuffix(char c) {
  switch (c) {
    case 'X':
      return kX;
    case 'Z':
      return kZ;
    case 'C':
      return kC;
    case 'Y':
      return kY;
    case 'W':
      return kW;
    default:
      return -1;
  }
}

// A number in c characters, right-justified (PUT; ln 8137-8153, 8204-8229).
std::string Justify(std::string s, size_t c) {
  if (s.size() < c) s.insert(0, c - s.size(), ' ');
  return s;
}

std::string ShortNumber(double v) {
  std::string s = fmt::format("{:.8g}", v);
  if (s.find('e') != std::string::npos) s = fmt::format("{:.3f}", v);
  return s;
}

}  // namespace

double OkRun::Common(int n, int col) {
  if (n < 1 || n > 200) Fail(col, "common variables are V1-V200");
  return common_[static_cast<size_t>(n)];
}

double OkRun::Local(uint64_t name, int col) {
  for (auto it = locals_.rbegin(); it != locals_.rend(); ++it) {
    if (it->name == name) return it->v;
  }
  Fail(col, fmt::format("local variable {} is not defined", UnpackName(name)));
}

std::optional<double> OkRun::EnvValue(const std::string& name) {
  return env_->SystemVariable(name);
}

Value OkRun::System(uint64_t packed, const Value* index, int col) {
  const std::string name = UnpackName(packed);
  const bool indexed = Indexed(name);
  if (!indexed && index) Fail(col, fmt::format("{} takes no suffix", name));
  auto real = [](double v) { return Value{v, false}; };
  auto integer = [](double v) { return Value{v, true}; };
  if (name == "VPAI") return real(kPi);
  if (name == "VRUND") return real(360);
  if (name == "VUNIT") return integer(static_cast<double>(units_));
  if (name == "VRSTT") return integer(0);
  const char axis_char = name.back();
  const int axis = AxisOfSuffix(axis_char);
  const std::string stem = name.substr(0, 4);
  if ((stem == "VZOF" || stem == "VZSH") && axis >= 0) {
    return real(stem == "VZOF" ? zero_offset_[static_cast<size_t>(axis)]
                               : zero_shift_[static_cast<size_t>(axis)]);
  }
  if (name == "VTOFX" || name == "VTOFZ") {
    int n = IndexOf(name, index, col, 0, 96);
    return real(name == "VTOFX" ? tools_.OffsetX(n) : tools_.OffsetZ(n));
  }
  if (name == "VNSRX" || name == "VNSRZ" || name == "VNSRP") {
    int n = IndexOf(name, index, col, 0, 96);
    if (name == "VNSRP") return integer(tools_.Tip(n));
    return real(name == "VNSRX" ? tools_.NoseX(n) : tools_.NoseZ(n));
  }
  if (stem == "VSIO" && axis >= 0) {
    if (auto v = EnvValue(name)) return real(*v);
    return real(ToProgram(axis, pos_[static_cast<size_t>(axis)]));
  }
  if ((stem == "VAPA" || stem == "VSKP" || stem == "VDIF" || stem == "VAPP") && axis >= 0) {
    if (auto v = EnvValue(name)) return real(*v);
    return real(stem == "VAPA" ? pos_[static_cast<size_t>(axis)] : 0.0);
  }
  if (name == "VETFX") return real(tools_.OffsetX(offset_no_));
  if (name == "VETFZ") return real(tools_.OffsetZ(offset_no_));
  if (name == "VETON") return integer(offset_no_);
  if (name == "VETLN") return integer(tool_);
  if ((stem == "VPVL" || stem == "VNVL") && axis >= 0) {
    const auto& lim = stem == "VPVL" ? pos_limit_ : neg_limit_;
    return real(lim[static_cast<size_t>(axis)]);
  }
  if (name == "VUACM") {
    int i = IndexOf(name, index, col, 1, 16);
    return integer(static_cast<unsigned char>(vuacm_[static_cast<size_t>(i)]));
  }
  if (name == "VDIN" || name == "VIRD" || name == "VORD") {
    int i = IndexOf(name, index, col, 0, 99999);
    if (auto v = EnvValue(fmt::format("{}[{}]", name, i))) return integer(std::round(*v));
    if (name == "VDIN" && i >= 1000 && i <= 1004)
      return integer(0);  // timers: the run's own clock is not kept
    return integer(0);
  }
  if (name == "VDOUT") {
    int i = IndexOf(name, index, col, 0, 99999);
    auto it = vdout_.find(i);
    return integer(it == vdout_.end() ? 0 : it->second);
  }
  int i = 0;
  if (indexed) i = IndexOf(name, index, col, 0, 9999);
  if (auto v = EnvValue(indexed ? fmt::format("{}[{}]", name, i) : name)) return real(*v);
  auto it = system_.find({packed, i});
  return real(it == system_.end() ? 0 : it->second);
}

double OkRun::ScaleSystemInput(const Value& v) const {
  // ln 8365-8406: in the 1 um (1/10000 in) systems a system variable takes least units; real values are
  // rounded to them. In the mm and inch systems the value is the number of mm (inch).
  switch (units_) {
    case UnitSystem::k1um:
      return std::round(v.v) * 0.001;
    case UnitSystem::k10um:
      return std::round(v.v) * 0.01;
    case UnitSystem::k10000thInch:
      return std::round(v.v) * 0.00254;
    case UnitSystem::kInch:
      return v.v * 25.4;
    default:
      return v.v;
  }
}

void OkRun::SetSystem(uint64_t packed, const Value* index, double v, int col) {
  const std::string name = UnpackName(packed);
  const bool indexed = Indexed(name);
  if (!indexed && index) Fail(col, fmt::format("{} takes no suffix", name));
  if (ReadOnly(name)) Fail(col, fmt::format("{} is read-only", name));
  const std::string stem = name.substr(0, 4);
  if (const char* what = ServoParameter(stem)) {
    // The servo keeps its own in-position band, pitch-error table and rapid rates: a write would be accepted
    // and change nothing (judgement 49); reading gives the value stored, 0 at the start.
    Fail(col,
         fmt::format("{} ({}) is the servo's: writing it is not supported by the cell's OSP-E100L dialect",
                     name, what));
  }
  const int axis = AxisOfSuffix(name.back());
  if ((stem == "VZOF" || stem == "VZSH") && axis >= 0) {
    if (axis != kX && axis != kZ && axis != kC)
      Fail(col, fmt::format("{}: no such axis on this lathe", name));
    (stem == "VZOF" ? zero_offset_ : zero_shift_)[static_cast<size_t>(axis)] = v;
    return;
  }
  if (name == "VTOFX" || name == "VTOFZ" || name == "VNSRX" || name == "VNSRZ" || name == "VNSRP") {
    int n = IndexOf(name, index, col, 1, 96);
    if (name == "VNSRP" && (v < 0 || v > 9 || v != std::floor(v))) Fail(col, "VNSRP (nose R pattern) is 0-9");
    if (name != "VNSRP" && std::fabs(v) > 999.999) Fail(col, fmt::format("{} outside 0 to +-999.999", name));
    char what = name == "VTOFX"   ? 'x'
                : name == "VTOFZ" ? 'z'
                : name == "VNSRX" ? 'X'
                : name == "VNSRZ" ? 'Z'
                                  : 'P';
    const tooltable::ToolEntry& e = tools_.Set(n, what, v);
    Out<ToolDataOp>().entry = e;
    if (n == nose_no_) {
      nose_r_ = tools_.NoseRadius(n);
      tip_ = tools_.Tip(n);
    }
    return;
  }
  if ((stem == "VPVL" || stem == "VNVL") && axis >= 0) {
    const uint32_t bit = 1u << axis;
    if (stem == "VPVL") {
      pos_limit_[static_cast<size_t>(axis)] = v;
      pos_limit_set_ |= bit;
    } else {
      neg_limit_[static_cast<size_t>(axis)] = v;
      neg_limit_set_ |= bit;
    }
    return;
  }
  if (name == "VUACM") Fail(col, "VUACM takes a character string ('TEXT')");
  if (name == "VDOUT") {
    int i = IndexOf(name, index, col, 0, 99999);
    double iv = std::round(v);  // I/O variables are integers (ln 8399)
    if (i >= 991 && i <= 993) RaiseUserAlarm(i, iv, col);
    vdout_[i] = iv;
    Out<OutputOp>().spec = fmt::format("VDOUT[{}]={}", i, static_cast<long long>(iv));
    return;
  }
  int i = indexed ? IndexOf(name, index, col, 0, 9999) : 0;
  system_[{packed, i}] = v;
}

void OkRun::RaiseUserAlarm(int which, double code, int col) {
  // ln 7807-7882: VDOUT[991] = Alarm C 3202, [992] = Alarm B 2288, [993] = Alarm A 1213; the comment is the
  // VUACM text from slot 1 up to the first empty slot.
  if (code < 1 || code > 9999) Fail(col, "user reserve code must be 1-9999");
  std::string comment;
  for (size_t i = 1; i <= 16 && vuacm_[i] != 0; ++i) comment.push_back(vuacm_[i]);
  const char* alarm = which == 991 ? "3202" : which == 992 ? "2288" : "1213";
  const char* cls = which == 991 ? "C" : which == 992 ? "B" : "A";
  std::string text = fmt::format("Alarm {} User reserve code {}", cls, static_cast<long>(code));
  if (!comment.empty()) text += " " + comment;
  Fail(col, text, alarm);
}

void OkRun::SetLocal(uint64_t name, double v, bool new_entry, int col) {
  const int level = static_cast<int>(frames_->depth());
  if (!new_entry) {
    for (auto it = locals_.rbegin(); it != locals_.rend(); ++it) {
      if (it->name == name) {
        it->v = v;  // the most recently registered entry of that name (ln 7659-7666)
        return;
      }
    }
  }
  if (locals_.size() >= 127) Fail(col, "more than 127 local variables");
  locals_.push_back({name, v, level});
}

void OkRun::Assignment(const Assign& a, const Block& b, bool call_arg) {
  if (a.is_string) {
    int i = static_cast<int>(Evaluate(b.pool, a.index, *this).v);
    if (i < 1 || i > 16) Fail(a.col, "VUACM[n]: n is 1-16");
    if (static_cast<int>(a.text.size()) > 17 - i) Fail(a.col, "VUACM holds at most 16 characters");
    for (size_t k = 0; k < a.text.size(); ++k) vuacm_[static_cast<size_t>(i) + k] = a.text[k];
    return;
  }
  Value v = Evaluate(b.pool, a.value, *this);
  switch (a.kind) {
    case VarKind::kCommon:
      common_[static_cast<size_t>(a.common)] = v.v;
      common_set_.set(static_cast<size_t>(a.common));
      return;
    case VarKind::kLocal:
      SetLocal(a.name, v.v, call_arg, a.col);
      return;
    case VarKind::kSystem: {
      if (a.index >= 0) {
        Value idx = Evaluate(b.pool, a.index, *this);
        SetSystem(a.name, &idx, ScaleSystemInput(v), a.col);
      } else {
        SetSystem(a.name, nullptr, ScaleSystemInput(v), a.col);
      }
      return;
    }
  }
}

// READ / WRITE / GET / PUT on the RS232C channel (ln 8075-8229): the station's serial line when the
// environment is a SerialChannel (docs/dnc.md "Okuma READ/WRITE"); where there is none (offline), a virtual
// channel whose READ data is the run's RS232C parameter and whose WRITE is one file_write command.
void OkRun::ExecIo(const Block& b) {
  switch (b.stmt) {
    case Stmt::kRead: {
      if (auto* line = dynamic_cast<SerialChannel*>(env_)) {
        SerialChannel::Result got = line->SerialRead();
        if (!got.error.empty()) Fail(b.stmt_col, "Alarm B RS232C: " + got.error);
        read_area_ = std::move(got.record);
      }
      if (read_area_.size() > 160) Fail(b.stmt_col, "Alarm B RS232C: more than 160 characters received");
      rrp_ = 0;
      return;
    }
    case Stmt::kWrite: {
      if (auto* line = dynamic_cast<SerialChannel*>(env_)) {
        SerialChannel::Result sent = line->SerialWrite(write_area_);
        if (!sent.error.empty()) Fail(b.stmt_col, "Alarm B RS232C: " + sent.error);
      } else {
        Out<FileWriteOp>().text = write_area_;
      }
      write_area_.clear();  // WWP to the start (ln 8141)
      return;
    }
    case Stmt::kGet: {
      double c = Evaluate(b.pool, b.count, *this).v;
      if (c < 1 || c != std::floor(c))
        Fail(b.stmt_col, "GET: the count must be a whole number of characters");
      size_t n = static_cast<size_t>(c);
      if (rrp_ + n > read_area_.size()) Fail(b.stmt_col, "Alarm B GET past the characters read");
      std::string field = read_area_.substr(rrp_, n);
      rrp_ += n;
      if (!b.has_var) return;
      std::string t;
      for (char ch : field) {
        if (ch != ' ') t.push_back(ch);
      }
      char* end = nullptr;
      double v = std::strtod(t.c_str(), &end);
      bool ok = !t.empty() && end && *end == 0 && std::count(t.begin(), t.end(), '.') <= 1 &&
                t.find_first_not_of("+-.0123456789") == std::string::npos;
      if (!ok) Fail(b.stmt_col, fmt::format("Alarm B GET: '{}' is not a number", field));
      const Assign& a = b.assigns[0];
      if (a.kind == VarKind::kCommon) {
        common_[static_cast<size_t>(a.common)] = v;
        common_set_.set(static_cast<size_t>(a.common));
      } else if (a.kind == VarKind::kLocal) {
        SetLocal(a.name, v, false, a.col);
      } else if (a.index >= 0) {
        Value idx = Evaluate(b.pool, a.index, *this);
        SetSystem(a.name, &idx, v, a.col);
      } else {
        SetSystem(a.name, nullptr, v, a.col);
      }
      return;
    }
    case Stmt::kPut: {
      std::string piece;
      if (b.put_text) {
        piece = b.put;
      } else {
        double c = Evaluate(b.pool, b.count, *this).v;
        if (c < 1 || c > 160 || c != std::floor(c)) Fail(b.stmt_col, "PUT: the count is 1-160 characters");
        size_t n = static_cast<size_t>(c);
        if (!b.has_var) {
          piece.assign(n, ' ');
        } else {
          const Assign& a = b.assigns[0];
          std::string s;
          if (a.kind == VarKind::kCommon) {
            s = ShortNumber(common_[static_cast<size_t>(a.common)]);
          } else if (a.kind == VarKind::kLocal) {
            s = ShortNumber(Local(a.name, a.col));
          } else {
            Value idx{};
            if (a.index >= 0) idx = Evaluate(b.pool, a.index, *this);
            Value v = System(a.name, a.index >= 0 ? &idx : nullptr, a.col);
            s = v.integer ? fmt::format("{}", static_cast<long long>(v.v)) : fmt::format("{:.3f}", v.v);
          }
          if (s.size() > n) Fail(b.stmt_col, fmt::format("PUT: {} does not fit in {} characters", s, n));
          piece = Justify(s, n);
        }
      }
      if (write_area_.size() + piece.size() > 160) Fail(b.stmt_col, "Alarm B PUT past 160 characters");
      write_area_ += piece;
      return;
    }
    default:
      return;
  }
}

}  // namespace cell::interp::okuma
