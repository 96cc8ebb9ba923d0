// KT-APL parameters (manual ch. 4 PAR, ch. 8): locals L0-L99 per call level, program parameters
// L100-L999, persistent machine parameters L1000-L2999, read-only system parameters L3000-L3999; letter
// values and the G/M state IFT tests; expressions with the failing token's column.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::ktapl {

double KtRun::Param(int n) {
  if (n >= 0 && n <= 99) {
    auto& loc = frames_->top().data.locals;
    auto it = loc.find(n);
    if (it == loc.end()) throw ExprError{fmt::format("Error L number NOT in table (L{})", n), 0};
    return it->second;
  }
  if (n >= 100 && n <= 999) {
    auto it = program_.find(n);
    if (it == program_.end()) throw ExprError{fmt::format("Error L number NOT in table (L{})", n), 0};
    return it->second;
  }
  if (n >= 1000 && n <= 2999) {
    auto it = machine_.find(n);
    if (it == machine_.end()) throw ExprError{fmt::format("Error L number NOT in table (L{})", n), 0};
    return it->second;
  }
  if (n >= 3000 && n <= 3999) {
    static const int kAxisOrder[8] = {kX, kY, kZ, kB, kA, kC, kU, kV};
    if (n <= 3007) {
      int a = kAxisOrder[n - 3000];
      return IsRotaryAxis(a) ? pos_[a] : FromMm(pos_[a]);
    }
    if (n >= 3008 && n <= 3012) {
      int a = kAxisOrder[n - 3008];
      // The offset in force (G47: as calculated for the table's position, ln 6296).
      double v = FixtureOffset(a);
      return IsRotaryAxis(a) ? v : FromMm(v);
    }
    if (n == 3016) return FromMm(u88_x_);
    if (n == 3017) return FromMm(u88_y_);
    if (n == 3018) return FromMm(tool_dia_);
    if (n == 3020) return pallet_;
    if (n == 3030) return active_tool_.empty() ? 0 : std::atof(active_tool_.c_str());
    if (n == 3033) return FromMm(tool_len_);
    if (n >= 3042 && n <= 3049) {
      int a = kAxisOrder[n - 3042];
      double v = probe_latch_[n - 3042];
      return IsRotaryAxis(a) ? v : FromMm(v);
    }
    if (n >= 3061 && n <= 3066) return dat_[n - 3061];
    // Lengths the machine knows (App. C): answered by the environment in mm, read in the program's units.
    // L3029: the spindle's G26 pull-back position above a touched surface (the probe tip then stands
    // L3029 - L3033 above it); without one from the machine, one inch above the tip.
    if (n == 3029 || (n >= 3080 && n <= 3085) || n == 3090) {
      std::optional<double> mm = env_->SystemVariable(fmt::format("L{}", n));
      if (!mm && n == 3029) mm = tool_len_ + kInch;
      return FromMm(mm.value_or(0));
    }
    if (n == 3070) return kPi;
    if (n == 3071) return std::exp(1.0);
    if (auto v = env_->SystemVariable(fmt::format("L{}", n))) return *v;
    return 0;
  }
  throw ExprError{"Error L numbers range from 0..3999", 0};
}

bool KtRun::ParamDefined(int n) {
  if (n >= 0 && n <= 99) return frames_->top().data.locals.count(n) > 0;
  if (n >= 100 && n <= 999) return program_.count(n) > 0;
  if (n >= 1000 && n <= 2999) return machine_.count(n) > 0;
  return n >= 3000 && n <= 3999;
}

void KtRun::SetParam(int n, double v, int col) {
  if (n < 0 || n > 2999) Fail(col, "Error L numbers range from 0..2999");
  if (!std::isfinite(v) || v < -99999999.0 - 1e-6 || v > 999999999.0 + 1e-6) {
    Fail(col, fmt::format("PARAMETER VALUE OUT OF RANGE (L{})", n));
  }
  if (n <= 99) {
    frames_->top().data.locals[n] = v;
  } else if (n <= 999) {
    program_[n] = v;
  } else {
    machine_[n] = v;
  }
}

void KtRun::DeleteParam(int n) {
  if (n <= 99) {
    frames_->top().data.locals.erase(n);
  } else if (n <= 999) {
    program_.erase(n);
  } else if (n <= 2999) {
    machine_.erase(n);
  }
}

double KtRun::Letter(char c) {
  int a = AxisOfLetter(c);
  if (a >= 0) {
    double v = pos_[a] - (IsRotaryAxis(a) ? 0 : Offset(a));
    return IsRotaryAxis(a) ? v : FromMm(v);
  }
  switch (c) {
    case 'F':
      return feed_.value_or(0);
    case 'S':
      return speed_;
    case 'T':
      return selected_tool_.empty() ? 0 : std::atof(selected_tool_.c_str());
    default:
      return letters_[c - 'A'];
  }
}

bool KtRun::ActiveCode(char gm, int code) {
  const Modal& m = mode_;
  if (gm == 'G') {
    switch (code) {
      case 0:
        return !m.contouring;
      case 1:
        return m.contouring;
      case 17:
        return m.plane == geom::Plane::kXY;
      case 18:
        return m.plane == geom::Plane::kZX;
      case 19:
        return m.plane == geom::Plane::kYZ;
      case 20:
        return m.coaxis_first;
      case 21:
        return m.coaxis_second;
      case 28:
        return m.obstruction_detection;
      case 29:
        return !m.obstruction_detection;
      case 36:
        return m.inspection_recording;
      case 37:
        return !m.inspection_recording;
      case 39:
        return !m.calculated_offsets;
      case 47:
        return m.calculated_offsets;
      case 40:
        return m.cutter_comp == CutterComp::kOff;
      case 41:
        return m.cutter_comp == CutterComp::kLeft;
      case 42:
        return m.cutter_comp == CutterComp::kRight;
      case 46:
        return m.fill_in_bypass;
      case 48:
        return m.explicit_fixtures;
      case 49:
        return !m.explicit_fixtures;
      case 50:
        return m.adaptive == Adaptive::kOff;
      case 51:
        return m.adaptive == Adaptive::kOn;
      case 53:
        return m.adaptive == Adaptive::kWithoutAirGap;
      case 60:
        return m.probe_count == ProbeCount::kOff;
      case 61:
        return m.probe_count == ProbeCount::kContacts;
      case 62:
        return m.probe_count == ProbeCount::kBreaks;
      case 70:
        return !metric_;
      case 71:
        return metric_;
      case 80:
        return m.cycle == 0;
      case 90:
        return !m.incremental;
      case 91:
        return m.incremental;
      case 93:
        return m.inverse_time;
      case 94:
        return !m.inverse_time;
      case 98:
        return std::any_of(g98_.begin(), g98_.end(), [](double v) { return v != 0; });
      case 99:
        return std::all_of(g98_.begin(), g98_.end(), [](double v) { return v == 0; });
      default:
        return m.cycle != 0 && m.cycle == code;
    }
  }
  switch (code) {
    case 3:
      return m.spindle == SpindleDir::kCw;
    case 4:
      return m.spindle == SpindleDir::kCcw;
    case 5:
      return m.spindle == SpindleDir::kStop;
    case 19:
      return m.spindle == SpindleDir::kOrient;
    case 7:
      return m.coolant == CoolantMode::kMist;
    case 8:
      return m.coolant == CoolantMode::kFlood;
    case 9:
      return m.coolant == CoolantMode::kOff;
    case 57:
      return m.aux_coolant == CoolantMode::kAuxMist;
    case 58:
      return m.aux_coolant == CoolantMode::kAuxFlood;
    case 59:
      return m.aux_coolant == CoolantMode::kAuxPulse;
    case 20:
      return !m.secondary_probe;
    case 21:
      return m.secondary_probe;
    case 23:
      return !m.z_prime_retracted;
    case 24:
      return m.z_prime_retracted;
    case 26:
      return !m.b_clamp_off;
    case 27:
      return m.b_clamp_off;
    case 28:
      return !m.c_clamp_off;
    case 29:
      return m.c_clamp_off;
    case 40:
      return m.tapping_range;
    case 48:
      return !m.overrides_locked;
    case 49:
      return m.overrides_locked;
    case 51:
      return m.wash_flood;
    case 52:
      return m.wash_air;
    default:
      return false;
  }
}

int KtRun::ExprCol(std::string_view text, size_t offset, int col) const {
  // Expression texts are views into the block or verbatim copies of part of it (statement bodies, PAR
  // fields): find them to point the diagnostic at the failing token rather than at the statement.
  if (block_.empty() || text.empty()) return col;
  const char* b = block_.data();
  size_t at = std::string_view::npos;
  if (text.data() >= b && text.data() + text.size() <= b + block_.size()) {
    at = static_cast<size_t>(text.data() - b);
  } else {
    at = block_.find(text, col > 0 ? static_cast<size_t>(col - 1) : 0);
  }
  if (at == std::string_view::npos) return col;
  return static_cast<int>(at + std::min(offset, text.size())) + 1;
}

double KtRun::Eval(std::string_view text, int col) {
  try {
    return EvalValue(text, *this);
  } catch (const ExprError& e) {
    Fail(ExprCol(text, e.offset, col), e.text);
  }
}

bool KtRun::EvalCond(const std::string& text, int col) {
  try {
    return EvalCondition(text, *this);
  } catch (const ExprError& e) {
    Fail(ExprCol(text, e.offset, col), e.text);
  }
}

int KtRun::EvalParamRef(std::string_view text, int col) {
  try {
    ExprParser p(text, *this);
    int n = p.ParamRef();
    if (!p.AtEnd()) Fail(col, "PARAMETER REFERENCE EXPECTED");
    return n;
  } catch (const ExprError& e) {
    Fail(ExprCol(text, e.offset, col), e.text);
  }
}

// <Ln>, <LnI> (truncated), <LnR> (rounded) in names. Blanks next to a substitution are not part of the
// name: `(OPF, TEST < L25I > < L27I >)` names TEST1231 (ln 3826-3830); blanks elsewhere are (`CYL BORES1`).
std::string KtRun::ExpandName(std::string_view name, int col) {
  if (name.find('<') == std::string_view::npos) return std::string(name);
  std::string out;
  for (size_t i = 0; i < name.size(); ++i) {
    if (name[i] != '<') {
      out += name[i];
      continue;
    }
    while (!out.empty() && out.back() == ' ') out.pop_back();
    size_t close = name.find('>', i);
    if (close == std::string::npos) Fail(col, "MISSING > IN NAME");
    std::string inner = Upper(Trim(name.substr(i + 1, close - i - 1)));
    char mode = 0;
    if (!inner.empty() && (inner.back() == 'I' || inner.back() == 'R')) {
      mode = inner.back();
      inner.pop_back();
    }
    double v;
    try {
      ExprParser p(inner, *this);
      v = Param(p.ParamRef());
      if (!p.AtEnd()) Fail(col, "PARAMETER REFERENCE EXPECTED IN <>");
    } catch (const ExprError& e) {
      Fail(col, e.text);
    }
    if (mode == 'I') {
      out += fmt::format("{}", static_cast<long long>(std::trunc(v)));
    } else if (mode == 'R') {
      out += fmt::format("{}", static_cast<long long>(std::floor(v + 0.5)));
    } else {
      out += FormatKtNumber(v);
    }
    i = close;
    while (i + 1 < name.size() && name[i + 1] == ' ') ++i;
  }
  return out;
}

void KtRun::SetFlag(int n) {
  if (ParamDefined(n)) machine_[n] = 1.0;
}

}  // namespace cell::interp::ktapl
