#include "cell/station/io.h"

#include <fmt/format.h>

#include <algorithm>

#include "cell/error/error.h"

namespace cell::station {

namespace {

bool IsHex(char c) {
  return (c >= '0' && c <= '9') || (c >= 'A' && c <= 'F');
}

std::vector<std::string> SplitCommas(const std::string& s) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = s.find(',', start);
    out.push_back(s.substr(start, comma - start));
    if (comma == std::string::npos) return out;
    start = comma + 1;
  }
}

int BitValue(const std::string& v, const std::string& spec) {
  if (v != "0" && v != "1")
    throw Error(Errc::kInvalidArgument, fmt::format("{}: a discrete bit is 0 or 1, not '{}'", spec, v));
  return v == "1" ? 1 : 0;
}

// KT-APL's list "O83D,0=1,O83E,3=0" (manual ln 3969, 4357): a word address, then bit=value pairs for it;
// at most 8 bits (ln 3958, 4353; the dialect checks it too).
std::vector<IoBit> ParseWordBits(const std::string& spec, char kind) {
  std::vector<IoBit> bits;
  std::string word;
  for (const std::string& f : SplitCommas(spec)) {
    const std::size_t eq = f.find('=');
    if (eq == std::string::npos) {
      word = f;
      if (!IsWordBitName(word + ".0", kind))
        throw Error(Errc::kInvalidArgument,
                    fmt::format("{}: '{}' is not a word address {}<1-4 hexadecimal digits>", spec, f, kind));
      continue;
    }
    if (word.empty())
      throw Error(Errc::kInvalidArgument, fmt::format("{}: a bit before its word address", spec));
    const std::string name = word + "." + f.substr(0, eq);
    if (!IsWordBitName(name, kind))
      throw Error(Errc::kInvalidArgument, fmt::format("{}: bit '{}' is not 0-15 (16-bit words)", spec, f));
    bits.push_back({name, BitValue(f.substr(eq + 1), spec)});
  }
  if (bits.empty()) throw Error(Errc::kInvalidArgument, fmt::format("{}: no bit", spec));
  if (bits.size() > 8) throw Error(Errc::kInvalidArgument, fmt::format("{}: at most 8 bits", spec));
  return bits;
}

}  // namespace

bool IsWordBitName(std::string_view name, char kind) {
  const std::size_t dot = name.find('.');
  if (name.size() < 4 || name[0] != kind || dot == std::string_view::npos || dot < 2 || dot > 5) return false;
  if (!std::all_of(name.begin() + 1, name.begin() + static_cast<std::ptrdiff_t>(dot), IsHex)) return false;
  const std::string_view bit = name.substr(dot + 1);
  if (bit.empty() || bit.size() > 2 ||
      !std::all_of(bit.begin(), bit.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return false;
  return (bit.size() == 1 || bit[0] != '0') && std::stoi(std::string(bit)) <= 15;
}

std::optional<OutputSpec> ParseOutputSpec(const std::string& spec) {
  OutputSpec out;
  if (spec == "SAVE") {
    out.save = true;
    return out;
  }
  // Okuma "VDOUT[n]=v" (dialects/okuma interp_vars.cpp): the I/O variable as the program names it.
  if (spec.rfind("VDOUT[", 0) == 0) {
    const std::size_t eq = spec.find("]=");
    if (eq == std::string::npos) throw Error(Errc::kInvalidArgument, "malformed output " + spec);
    out.bits.push_back({spec.substr(0, eq + 1), BitValue(spec.substr(eq + 2), spec)});
    return out;
  }
  if (!spec.empty() && spec[0] == 'O') {
    out.bits = ParseWordBits(spec, 'O');
    return out;
  }
  return std::nullopt;
}

std::optional<std::vector<IoBit>> ParseWaitSpec(const std::string& spec) {
  if (spec.empty() || spec[0] != 'I') return std::nullopt;
  return ParseWordBits(spec, 'I');
}

std::string Describe(const std::vector<IoBit>& bits) {
  std::string out;
  for (const IoBit& b : bits) out += fmt::format("{}{}={}", out.empty() ? "" : " ", b.name, b.value);
  return out;
}

DiscreteIo::DiscreteIo(StationDb& db, const std::vector<config::AuxOutput>& aux,
                       std::function<void(const IoState&)> publish)
    : db_(db), publish_(std::move(publish)) {
  for (const auto& [n, v] : db_.LoadInputs()) now_.inputs[n] = v != 0 ? 1 : 0;
  for (const auto& a : aux) now_.outputs[a.output] = 0;
  for (const auto& [n, v] : db_.LoadOutputs()) {
    now_.outputs[n] = v.first;
    if (v.second != 0) now_.power_up[n] = v.second;
  }
}

IoState DiscreteIo::Get() const {
  std::lock_guard lk(mu_);
  return now_;
}

void DiscreteIo::Announce() const {
  std::lock_guard lk(mu_);
  publish_(now_);
}

void DiscreteIo::Changed() {
  ++now_.revision;
  publish_(now_);
}

std::uint32_t DiscreteIo::SetInputs(const std::vector<IoBit>& bits) {
  if (bits.empty()) throw Error(Errc::kInvalidArgument, "no input to set");
  std::map<std::string, double> rows;
  for (const IoBit& b : bits) {
    if (!IsWordBitName(b.name, 'I'))
      throw Error(Errc::kInvalidArgument,
                  "'" + b.name + "' is not an input: a KT-APL bit I<word>.<bit>, e.g. I04D.1 (bits 0-15)");
    if (b.value != 0 && b.value != 1) throw Error(Errc::kInvalidArgument, "an input is 0 or 1");
    rows[b.name] = b.value;
  }
  std::lock_guard lk(mu_);
  db_.SetInputs(rows);
  for (const auto& [n, v] : rows) now_.inputs[n] = static_cast<int>(v);
  Changed();
  return now_.revision;
}

void DiscreteIo::SetOutputs(const std::vector<IoBit>& bits) {
  std::map<std::string, int> rows;
  for (const IoBit& b : bits) {
    if (!config::IsValidIoName(b.name))
      throw Error(Errc::kInvalidArgument, "'" + b.name + "' is not an output");
    if (b.value != 0 && b.value != 1) throw Error(Errc::kInvalidArgument, "an output is 0 or 1");
    rows[b.name] = b.value;
  }
  std::lock_guard lk(mu_);
  db_.SetOutputs(rows);
  for (const auto& [n, v] : rows) now_.outputs[n] = v;
  Changed();
}

void DiscreteIo::SavePowerUp() {
  std::lock_guard lk(mu_);
  // Outputs listed but never set (the station file's, at 0) get a row too, so the saved default is whole.
  db_.SetOutputs(now_.outputs);
  db_.SavePowerUp();
  now_.power_up.clear();
  for (const auto& [n, v] : now_.outputs)
    if (v != 0) now_.power_up[n] = v;
  Changed();
}

bool DiscreteIo::Satisfied(const std::vector<IoBit>& condition) const {
  std::lock_guard lk(mu_);
  return std::all_of(condition.begin(), condition.end(), [&](const IoBit& b) {
    auto it = now_.inputs.find(b.name);
    return (it == now_.inputs.end() ? 0 : it->second) == b.value;
  });
}

void AuxIo::Spindle(const interp::SpindleOp& s) {
  const bool turning = s.dir == interp::SpindleDir::kCw || s.dir == interp::SpindleDir::kCcw;
  rotating_ = turning && (s.rpm > 0 || s.css > 0);
}

std::optional<IoBit> AuxIo::Aux(int m) {
  for (std::size_t i = 0; i < map_.size(); ++i) {
    const config::AuxOutput& a = map_[i];
    if (m == a.interlock_on || m == a.interlock_off) {
      interlocked_[i] = m == a.interlock_on;
      return std::nullopt;
    }
    if (m != a.m_on && m != a.m_off) continue;
    if (a.interlock && interlocked_[i] && rotating_) {
      const std::string off = a.interlock_off >= 0 ? fmt::format(" (M{} turns it off)", a.interlock_off) : "";
      const std::string note = a.note.empty() ? "" : " (" + a.note + ")";
      throw Error(
          Errc::kFailedPrecondition,
          fmt::format("M{} refused: the {} interlock is ON{} and the spindle rotates; stop the spindle "
                      "(M05) first{}",
                      m, a.name, off, note));
    }
    return IoBit{a.output, m == a.m_on ? 1 : 0};
  }
  return std::nullopt;
}

}  // namespace cell::station
