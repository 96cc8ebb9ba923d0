// A Balt-System run's start: the settings of RunOptions::params (the characterization: unit, rotary and
// indexing axes, spindle axes, ...; docs/dialects/balt.md), the station's E parameters, the tool table (the
// offsets file), the origin and tool life files, and the power-up state of Table 5.2.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "cell/error/error.h"
#include "interp_internal.h"

namespace cell::interp::balt {
namespace {

std::string Upper(std::string_view s) {
  std::string out(s);
  for (char& c : out) {
    if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
  }
  return out;
}

std::string Trim(std::string_view s) {
  std::size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string_view::npos) return {};
  std::size_t e = s.find_last_not_of(" \t\r");
  return std::string(s.substr(b, e - b + 1));
}

[[noreturn]] void BadSetting(const std::string& key, const std::string& why) {
  throw Error(Errc::kInvalidArgument, fmt::format("setting {}: {}", key, why));
}

double Number(const std::string& key, const std::string& v) {
  try {
    std::size_t used = 0;
    double d = std::stod(v, &used);
    if (used != v.size() || !std::isfinite(d)) BadSetting(key, fmt::format("'{}' is not a number", v));
    return d;
  } catch (const std::logic_error&) {
    BadSetting(key, fmt::format("'{}' is not a number", v));
  }
}

std::uint32_t Axes(const std::string& key, const std::string& v, bool rotary_only) {
  std::uint32_t m = 0;
  for (char c : v) {
    if (c == ',' || c == ' ') continue;
    int a = AxisOfLetter(c);
    if (a < 0 || (rotary_only && !IsRotaryAxis(a)))
      BadSetting(key, fmt::format("'{}' is not {}", c, rotary_only ? "a rotary axis (A B C)" : "an axis"));
    m |= 1u << a;
  }
  return m;
}

// M_CODES / H_CODES: the machine-logic codes the machine builder assigned (ln 2500, 420-422), as numbers
// 0-99 separated by commas or spaces; NONE (or empty) for none.
std::bitset<100> Codes(const std::string& key, const std::string& v) {
  std::bitset<100> b;
  if (v == "NONE") return b;
  std::size_t i = 0;
  while (i < v.size()) {
    if (v[i] == ',' || v[i] == ' ') {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < v.size() && IsDigit(v[j])) ++j;
    if (j == i || j - i > 2) BadSetting(key, fmt::format("'{}' is not a list of codes 0-99", v));
    b.set(static_cast<std::size_t>(std::stoi(v.substr(i, j - i))));
    i = j;
  }
  return b;
}

}  // namespace

BaltRun::BaltRun(const RunOptions& o) : RunBase(o) {
  scale_.fill(1.0);
  std::size_t syvar_bytes = 200;
  std::map<int, double> initial_e;
  for (const auto& [k, v] : o.params) {
    std::string key = Upper(Trim(k)), val = Upper(Trim(v));
    if (key == "UNITS") {
      if (val == "MM" || val == "METRIC" || val == "G71") {
        basic_metric_ = true;
      } else if (val == "INCH" || val == "G70") {
        basic_metric_ = false;
      } else {
        BadSetting(key, "mm or inch");
      }
    } else if (key == "USB") {
      block_delete_enabled_ = Number(key, val) != 0;
    } else if (key == "USO" || key == "OPTIONAL_STOP") {
      optional_stop_ = Number(key, val) != 0;
    } else if (key == "ROLLOVER") {
      rollover_mask_ = Axes(key, val, true);
    } else if (key.size() == 7 && key.rfind("INDEX_", 0) == 0) {
      int a = AxisOfLetter(key[6]);
      if (a < 0 || !IsRotaryAxis(a)) BadSetting(key, "INDEX_A, INDEX_B or INDEX_C");
      double step = Number(key, val);
      if (step <= 0 || step > 360) BadSetting(key, "degrees per index, 0-360");
      index_step_[a] = step;
    } else if (key == "SPINDLE_AXES") {
      spindle_axes_ = Axes(key, val, false);
    } else if (key == "M_CODES") {
      logic_m_ = Codes(key, val);
    } else if (key == "H_CODES") {
      logic_h_ = Codes(key, val);
    } else if (key == "INTERFACE_LOGIC") {
      interface_logic_ = Number(key, val) != 0;
    } else if (key == "RANDOM_TOOLS") {
      random_required_ = Number(key, val) != 0;
    } else if (key == "TRANSDUCER") {
      transducer_ = Number(key, val) != 0;
    } else if (key == "PECK_CLEARANCE") {
      peck_clearance_ = std::max(0.0, Number(key, val));
    } else if (key == "E_PARAMETERS") {
      max_e_ = static_cast<int>(std::clamp(Number(key, val), 30.0, 9999.0));
    } else if (key == "SYVAR_BYTES") {
      syvar_bytes = static_cast<std::size_t>(std::clamp(Number(key, val), 1.0, 65536.0));
    } else if (key == "MAX_IDLE_BLOCKS") {
      max_idle_ = std::max(1L, static_cast<long>(Number(key, val)));
    } else if (key == "DPT") {
      std::vector<double> p;
      std::size_t s = 0;
      while (s <= val.size()) {
        std::size_t c = val.find(',', s);
        p.push_back(Number(key, Trim(val.substr(s, c == std::string::npos ? std::string::npos : c - s))));
        if (c == std::string::npos) break;
        s = c + 1;
      }
      if (p.size() != 3 || p[1] <= 0 || p[2] <= 0 || p[0] < 0) BadSetting(key, "Qa,Qs,Vm");
      dpt_ = true;
      dpt_qa_ = p[0];
      dpt_qs_ = p[1];
      dpt_vm_ = p[2];
    } else if (key.size() > 1 && key[0] == 'E' && std::all_of(key.begin() + 1, key.end(), IsDigit)) {
      initial_e[std::stoi(key.substr(1))] = Number(key, val);
    }
  }
  e_.assign(static_cast<std::size_t>(max_e_) + 1, 0.0);
  e_set_.assign(e_.size(), false);
  sa_.assign(1024, 0);
  sk_.assign(1024, 0);
  syvar_.assign(syvar_bytes, 0);
  // The station's E parameters (persistent, ln 5499), then the settings' values.
  auto put = [&](int n, double v) {
    if (n < 0 || n > max_e_ || !std::isfinite(v)) return;
    try {
      SetParam(n, v, 1);
    } catch (const RunError&) {
      // a value outside the parameter's format is left out
    }
  };
  for (const auto& [k, v] : o.variables) {
    std::string key = Upper(Trim(k));
    if (key.size() > 1 && key[0] == 'E' && std::all_of(key.begin() + 1, key.end(), IsDigit) &&
        key.size() < 7) {
      put(std::stoi(key.substr(1)), v);
    }
  }
  for (const auto& [n, v] : initial_e) put(n, v);
  mode_.metric = basic_metric_;
  tools_ = o.tools;
  LoadOrigins();
  LoadToolLife();
  LoadRandomTools();
  frames_ = std::make_unique<Frames>(o.program ? o.program : ProgramText::FromString(o.program_text));
}

}  // namespace cell::interp::balt
