// Balt-System reference systems (manual §5.17.1, ln 5533-5794): absolute origins 0-99 from the origin file
// FILEOR (UAO), temporary (UOT) and incremental (UIO) origins, permanent requalification (RQO), the plane
// rotation URT (applied first) and mirroring MIR (second), scale factors SCF, and the tool length on its
// axis. Program coordinates map to machine coordinates as: scale, rotate, mirror, + origin, + tool length.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>

#include "cell/error/error.h"
#include "interp_internal.h"

namespace cell::interp::balt {

AxisArray BaltRun::ToMachine(const AxisArray& prog) const {
  AxisArray m = prog;
  if (!identity_) [[unlikely]] {
    for (int a = 0; a < kAxisCount; ++a) {
      if (!IsRotaryAxis(a)) m[a] *= scale_[a];
    }
    if (urt_ != 0) {
      double x = m[mode_.p1], y = m[mode_.p2];
      m[mode_.p1] = x * urt_cos_ - y * urt_sin_;
      m[mode_.p2] = x * urt_sin_ + y * urt_cos_;
    }
    for (int a = 0; a < kAxisCount; ++a) {
      if (mirror_[a]) m[a] = -m[a];
    }
  }
  // Pairs of axes, then the odd last one: a loop of a length divisible by two is one the compiler writes as
  // vector adds at -O2 (every move converts its end point).
  constexpr int kPaired = kAxisCount & ~1;
  for (int a = 0; a < kPaired; ++a) m[a] += origin_[a];
  for (int a = kPaired; a < kAxisCount; ++a) m[a] += origin_[a];
  m[len_axis_] += tool_len_;
  return m;
}

AxisArray BaltRun::ToProgram(const AxisArray& mach) const {
  AxisArray p = mach;
  p[len_axis_] -= tool_len_;
  for (int a = 0; a < kAxisCount; ++a) p[a] -= origin_[a];
  if (!identity_) [[unlikely]] {
    for (int a = 0; a < kAxisCount; ++a) {
      if (mirror_[a]) p[a] = -p[a];
    }
    if (urt_ != 0) {
      double x = p[mode_.p1], y = p[mode_.p2];
      p[mode_.p1] = x * urt_cos_ + y * urt_sin_;
      p[mode_.p2] = -x * urt_sin_ + y * urt_cos_;
    }
    for (int a = 0; a < kAxisCount; ++a) {
      if (!IsRotaryAxis(a) && scale_[a] != 0) p[a] /= scale_[a];
    }
  }
  return p;
}

const AxisArray& BaltRun::Prog() {
  if (!prog_valid_) {
    prog_ = ToProgram(pos_);
    prog_valid_ = true;
  }
  return prog_;
}

double BaltRun::PlaneScale() const {
  return scale_[mode_.p1];
}

bool BaltRun::MirrorFlipsPlane() const {
  return mirror_[mode_.p1] != mirror_[mode_.p2];
}

void BaltRun::UpdateIdentity() {
  identity_ = urt_ == 0;
  for (int a = 0; a < kAxisCount; ++a) {
    if (mirror_[a] || scale_[a] != 1.0) identity_ = false;
  }
  FrameChanged();
}

// The origin file: the library's FILEOR (offline --lib, on a station its MP3 file) and ORIGINn settings.
// Without either, every origin is the machine zero (DESIGN §4: machine state starts at zero).
void BaltRun::LoadOrigins() {
  // On memory MP3 (ln 8116-8170); offline (--lib) under its bare name.
  auto text = opt_.library ? opt_.library("FILEOR/MP3") : std::nullopt;
  if (!text && opt_.library) text = opt_.library("FILEOR");
  if (text) {
    try {
      origins_ = ParseOrigins(*text, basic_metric_);
    } catch (const FileError& e) {
      throw Error(Errc::kInvalidArgument, fmt::format("FILEOR:{}:{}: error: [FILMS4 {:02}] {}: {}", e.line,
                                                      e.col, e.code, FilmsText(e.code), e.text));
    }
    origin_file_ = true;
  }
  for (const auto& [k, v] : opt_.params) {
    if (k.rfind("ORIGIN", 0) != 0 || k.size() < 7) continue;
    std::string num = k.substr(6);
    if (!std::all_of(num.begin(), num.end(), IsDigit)) continue;
    int n = std::stoi(num);
    try {
      OriginFile one = ParseOrigins(num + " " + v, basic_metric_);
      origins_[n] = one[n];
    } catch (const FileError& e) {
      throw Error(Errc::kInvalidArgument, fmt::format("setting {}: {}", k, e.text));
    }
    origin_file_ = true;
  }
  // Origin 0 is active at power-on (ln 5572).
  if (auto it = origins_.find(0); it != origins_.end()) {
    for (int a = 0; a < kAxisCount; ++a) {
      if (it->second.axes & (1u << a)) origin_[a] = it->second.v[a];
    }
  }
}

void BaltRun::SaveOrigins() {
  origins_changed_ = false;
  SaveFile("FILEOR/MP3", FormatOrigins(origins_));
}

void BaltRun::SelectOrigin(int n, std::uint32_t axes, int col) {
  auto it = origins_.find(n);
  if (it == origins_.end()) {
    if (origin_file_ && n != 0) Fail(col, 27, fmt::format("origin {} is not in the origin file", n));
    // No file (or origin 0 not recorded): the machine zero.
    for (int a = 0; a < kAxisCount; ++a) {
      if (axes == 0 || (axes & (1u << a))) {
        origin_[a] = 0;
        origin_no_[a] = n;
      }
    }
    FrameChanged();
    return;
  }
  const OriginRecord& o = it->second;
  for (int a = 0; a < kAxisCount; ++a) {
    bool listed = axes & (1u << a);
    if (listed && !(o.axes & (1u << a)))
      Fail(col, 29, fmt::format("origin {} has no {} value", n, LetterOfAxis(a)));
    if (listed || (axes == 0 && (o.axes & (1u << a)))) {
      origin_[a] = o.v[a];
      origin_no_[a] = n;
    } else if (axes == 0 && n == 0) {
      origin_[a] = 0;
      origin_no_[a] = 0;
    }
  }
  FrameChanged();
}

// (UAO,n[,ax...]) (ln 5544-5575).
void BaltRun::CmdUao(const Command& c) {
  CheckOperands(c, 1, 4);
  int n = OperandInt(c.ops[0], 0, 99);
  std::uint32_t axes = 0;
  for (std::size_t k = 1; k < c.ops.size(); ++k) {
    AxisValue a = OperandAxis(c.ops[k].text, c.ops[k].col, false);
    if (c.ops[k].text.size() != 1) Fail(c.ops[k].col, 24, "UAO lists axis letters");
    if (axes & (1u << a.axis)) Fail(c.ops[k].col, 24, "an axis twice");
    axes |= 1u << a.axis;
  }
  SelectOrigin(n, axes, c.ops[0].col);
}

// (UOT,n,ax v...) (ln 5577-5623): absolute origin n shifted by the values (current unit, scaled by SCF).
void BaltRun::CmdUot(const Command& c) {
  CheckOperands(c, 2, 4);
  int n = OperandInt(c.ops[0], 0, 99);
  auto it = origins_.find(n);
  if (it == origins_.end() && origin_file_ && n != 0)
    Fail(c.ops[0].col, 27, fmt::format("origin {} is not in the origin file", n));
  std::uint32_t seen = 0;
  for (std::size_t k = 1; k < c.ops.size(); ++k) {
    AxisValue a = OperandAxis(c.ops[k].text, c.ops[k].col, true);
    if (seen & (1u << a.axis)) Fail(c.ops[k].col, 24, "an axis twice");
    seen |= 1u << a.axis;
    double base = 0;
    if (it != origins_.end()) {
      if (!(it->second.axes & (1u << a.axis)) && origin_file_ && n != 0) {
        Fail(c.ops[k].col, 29, fmt::format("origin {} has no {} value", n, LetterOfAxis(a.axis)));
      }
      base = it->second.v[a.axis];
    }
    double v = IsRotaryAxis(a.axis) ? a.v : a.v * UnitFactor() * scale_[a.axis];
    origin_[a.axis] = base + v;
    origin_no_[a.axis] = n;
  }
  FrameChanged();
}

// (UIO,ax v...) (ln 5625-5663): the current origin shifted, cumulatively.
void BaltRun::CmdUio(const Command& c) {
  CheckOperands(c, 1, 3);
  std::uint32_t seen = 0;
  for (const Operand& o : c.ops) {
    AxisValue a = OperandAxis(o.text, o.col, true);
    if (seen & (1u << a.axis)) Fail(o.col, 24, "an axis twice");
    seen |= 1u << a.axis;
    origin_[a.axis] += IsRotaryAxis(a.axis) ? a.v : a.v * UnitFactor() * scale_[a.axis];
  }
  FrameChanged();
}

// (MIR[,ax...]) (ln 5665-5697): listed axes mirrored (set, not toggled), others keep their state; (MIR)
// clears all.
void BaltRun::CmdMir(const Command& c) {
  CheckOperands(c, 0, 3);
  if (c.ops.empty()) {
    mirror_ = {};
  } else {
    for (const Operand& o : c.ops) {
      AxisValue a = OperandAxis(o.text, o.col, false);
      if (o.text.size() != 1) Fail(o.col, 24, "MIR lists axis letters");
      mirror_[a.axis] = true;
    }
  }
  UpdateIdentity();
}

// (URT,angle) (ln 5699-5728): the plane rotated about the current origin, degrees CCW; 0 cancels.
void BaltRun::CmdUrt(const Command& c) {
  CheckOperands(c, 1, 1);
  if (contour_.on()) Fail(c.col, 25, "URT with cutter compensation on");
  urt_ = OperandNumber(c.ops[0]);
  urt_cos_ = std::cos(urt_ * kDeg);
  urt_sin_ = std::sin(urt_ * kDeg);
  UpdateIdentity();
}

// (SCF[,n[,ax...]]) (ln 5730-5765): factor n on the listed axes (all when none), the others unscaled.
void BaltRun::CmdScf(const Command& c) {
  CheckOperands(c, 0, 4);
  if (contour_.on()) Fail(c.col, 25, "SCF with cutter compensation on");
  for (double& s : scale_) s = 1.0;
  if (!c.ops.empty()) {
    double n = OperandNumber(c.ops[0]);
    if (n <= 0) Fail(c.ops[0].col, 13, "a scale factor is positive");
    if (c.ops.size() == 1) {
      for (int a = 0; a < kAxisCount; ++a) {
        if (!IsRotaryAxis(a)) scale_[a] = n;
      }
    }
    for (std::size_t k = 1; k < c.ops.size(); ++k) {
      AxisValue a = OperandAxis(c.ops[k].text, c.ops[k].col, false);
      if (c.ops[k].text.size() != 1) Fail(c.ops[k].col, 24, "SCF lists axis letters");
      scale_[a.axis] = n;
    }
  }
  UpdateIdentity();
}

// (RQO,n,ax v...) (ln 5767-5794): the value added to absolute origin n in the file, permanently, in the
// characterized unit, unscaled; the active origin too when it is n.
void BaltRun::CmdRqo(const Command& c) {
  CheckOperands(c, 2, 4);
  int n = OperandInt(c.ops[0], 0, 99);
  auto it = origins_.find(n);
  if (it == origins_.end() && origin_file_)
    Fail(c.ops[0].col, 27, fmt::format("origin {} is not in the origin file", n));
  OriginRecord& rec = origins_[n];
  std::uint32_t seen = 0;
  for (std::size_t k = 1; k < c.ops.size(); ++k) {
    AxisValue a = OperandAxis(c.ops[k].text, c.ops[k].col, true);
    if (seen & (1u << a.axis)) Fail(c.ops[k].col, 24, "an axis twice");
    seen |= 1u << a.axis;
    double v = IsRotaryAxis(a.axis) ? a.v : a.v * (basic_metric_ ? 1.0 : kInch);
    if (!(rec.axes & (1u << a.axis)) && std::popcount(rec.axes) >= 3) {
      Fail(c.ops[k].col, 69, fmt::format("origin {} would have more than 3 axes", n));
    }
    rec.axes |= 1u << a.axis;
    rec.v[a.axis] += v;
    if (origin_no_[a.axis] == n) origin_[a.axis] += v;
  }
  FrameChanged();
  origins_changed_ = true;
  SaveOrigins();
}

}  // namespace cell::interp::balt
