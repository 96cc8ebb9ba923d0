// The per-control defaults of a serial line (docs/dnc.md "Defaults") and the checks of a `[serial]` table.
#include "cell/dnc/settings.h"

#include <algorithm>
#include <array>

#include <fmt/format.h>

namespace cell::dnc {
namespace {

constexpr std::array<int, 13> kBauds = {110,  150,   300,   600,   1200,   2400,  4800,
                                        9600, 19200, 38400, 57600, 115200, 230400};

[[noreturn]] void Refuse(std::string_view key, std::string_view value, std::string_view allowed) {
  throw Error(Errc::kInvalidArgument, fmt::format("[serial] {} = {}: {}", key, value, allowed));
}

template <typename E, size_t N>
E Pick(std::string_view key, const std::string& value,
       const std::array<std::pair<std::string_view, E>, N>& names) {
  for (const auto& [name, e] : names)
    if (name == value) return e;
  std::string all;
  for (const auto& [name, e] : names) all += (all.empty() ? "" : " | ") + std::string(name);
  Refuse(key, fmt::format("\"{}\"", value), "one of " + all);
}

void ApplyNames(Serial& s, const config::SerialTable& k) {
  using P = std::pair<std::string_view, Parity>;
  using C = std::pair<std::string_view, Code>;
  using F = std::pair<std::string_view, Flow>;
  using N = std::pair<std::string_view, End>;
  if (k.parity) {
    s.format.parity =
        Pick("parity", *k.parity,
             std::array{P{"none", Parity::kNone}, P{"even", Parity::kEven}, P{"odd", Parity::kOdd}});
  }
  if (k.code) s.format.code = Pick("code", *k.code, std::array{C{"eia", Code::kEia}, C{"iso", Code::kIso}});
  if (k.flow) {
    s.flow =
        Pick("flow", *k.flow,
             std::array{F{"xonxoff", Flow::kXonXoff}, F{"rtscts", Flow::kRtsCts}, F{"none", Flow::kNone}});
  }
  if (k.end)
    s.format.end =
        Pick("end", *k.end, std::array{N{"nul", End::kNul}, N{"ctrl-z", End::kCtrlZ}, N{"%", End::kPercent}});
}

void Check(Control c, const Serial& s) {
  if (std::find(kBauds.begin(), kBauds.end(), s.baud) == kBauds.end()) {
    Refuse("baud", std::to_string(s.baud), "a standard rate from 110 to 230400");
  }
  if (c == Control::kEmco && (s.baud < 150 || s.baud > 4800)) {
    Refuse("baud", std::to_string(s.baud), "EMCOTRONIC D00 accepts 150-4800 (ln 5315, alarm 870 ln 7225)");
  }
  const Format& f = s.format;
  if (f.data_bits != 7 && f.data_bits != 8) Refuse("data_bits", std::to_string(f.data_bits), "7 or 8");
  if (s.stop_bits != 1 && s.stop_bits != 2) Refuse("stop_bits", std::to_string(s.stop_bits), "1 or 2");
  if (f.leader < 0 || f.leader > 1000) Refuse("leader", std::to_string(f.leader), "0 to 1000 NUL characters");
  if (f.code == Code::kEia) {
    if (f.data_bits != 8)
      Refuse("data_bits", std::to_string(f.data_bits), "EIA RS-244 is an 8-channel code: 8");
    if (f.parity == Parity::kEven)
      Refuse("parity", "\"even\"", "EIA RS-244 has odd parity in channel 5: odd or none");
    if (f.end == End::kCtrlZ) Refuse("end", "\"ctrl-z\"", "EIA RS-244 has no ctrl-Z: nul or %");
  }
  if (c == Control::kEmco && f.code == Code::kEia)
    Refuse("code", "\"eia\"", "EMCOTRONIC reads ISO only (O01 bit 0, ln 5562-5568)");
}

}  // namespace

std::string_view FlowName(Flow f) {
  switch (f) {
    case Flow::kXonXoff:
      return "xonxoff";
    case Flow::kRtsCts:
      return "rtscts";
    case Flow::kNone:
      return "none";
  }
  return "?";
}

// The controls' memories, in characters of program text (docs/dnc.md "Memory", judgement calls 16-17).
// Balt-System: "The size of the user memory is 64,000 characters" (ln 223), the figure the program store
// holds a memory MP0-MP6 to (program_store::kMemoryCapacity). EMCOTRONIC: "20 kB program memory" (ln 608),
// 20 x 1024. OSP-E100L: the one program capacity, 320 m of tape by default (ln 717-721), at the tape's 10
// characters an inch: 320 m / 2.54 mm = 125,984 characters.
constexpr int kBaltMemory = 64000;
constexpr int kEmcoMemory = 20 * 1024;
constexpr int kOkumaMemory = 125984;

Serial Defaults(Control c) {
  Serial s;
  s.format.control = c;
  s.format.code = Code::kIso;
  s.format.data_bits = 7;
  s.format.parity = Parity::kEven;
  s.format.leader = 50;
  s.stop_bits = 1;
  s.baud = 9600;
  s.flow = Flow::kXonXoff;
  s.format.end = End::kNul;
  switch (c) {
    case Control::kKtApl:  // J1-J3; the manual gives no memory size (J16)
      break;
    case Control::kBalt:  // J4-J5
      s.memory = kBaltMemory;
      break;
    case Control::kEmco:  // J6-J9
      s.memory = kEmcoMemory;
      s.baud = 2400;
      s.flow = Flow::kRtsCts;
      s.format.end = End::kCtrlZ;
      break;
    case Control::kOkuma:  // J10-J11
      s.memory = kOkumaMemory;
      s.format.end = End::kPercent;
      break;
  }
  return s;
}

Serial Resolve(Control c, const config::SerialTable& k) {
  Serial s = Defaults(c);
  if (k.device.empty())
    throw Error(Errc::kInvalidArgument, "[serial] device: required (e.g. \"/dev/ttyS0\")");
  s.device = k.device;
  if (k.baud) s.baud = *k.baud;
  if (k.data_bits) s.format.data_bits = *k.data_bits;
  if (k.stop_bits) s.stop_bits = *k.stop_bits;
  if (k.leader) s.format.leader = *k.leader;
  if (k.memory) s.memory = *k.memory;
  ApplyNames(s, k);
  // An EIA line is the tape's eight channels: 8 data bits unless the table says otherwise (and is refused).
  if (k.code && s.format.code == Code::kEia) {
    if (!k.data_bits) s.format.data_bits = 8;
    if (!k.parity) s.format.parity = Parity::kOdd;
  }
  Check(c, s);
  return s;
}

std::string MemoryRefusal(const Serial& s, size_t characters) {
  if (s.memory <= 0 || characters <= static_cast<size_t>(s.memory)) return "";
  return fmt::format("{} characters, more than the {} memory holds ({} characters, [serial] memory)",
                     characters, ControlName(s.format.control), s.memory);
}

}  // namespace cell::dnc
