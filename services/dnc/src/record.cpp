// Okuma READ/WRITE records on the line (docs/dnc.md "Okuma READ/WRITE").
#include "cell/dnc/record.h"

#include <fmt/format.h>

namespace cell::dnc {
namespace {

uint8_t EndCode(const Format& f) {
  return f.end == End::kPercent ? '%' : 0;
}

}  // namespace

std::string RecordRefusal(const Format& f) {
  if (f.code == Code::kEia)
    return "READ/WRITE speak JIS 7-bit or 8-bit (ln 8093-8094), and this line is set to EIA";
  if (f.end == End::kCtrlZ)
    return "READ/WRITE end a record with NULL or % (ln 8094), and this line ends with ctrl-Z";
  return "";
}

std::vector<uint8_t> EncodeRecord(const Format& f, std::string_view record) {
  if (const std::string why = RecordRefusal(f); !why.empty()) throw Error(Errc::kInvalidArgument, why);
  if (record.size() > kRecordMax)
    throw Error(Errc::kInvalidArgument,
                fmt::format("{} characters to send, more than the write area's 160", record.size()));
  const uint8_t end = EndCode(f);
  std::vector<uint8_t> out;
  out.reserve(record.size() + 1);
  for (size_t i = 0; i < record.size(); ++i) {
    const auto c = static_cast<uint8_t>(record[i]);
    if (c == end)
      throw Error(Errc::kInvalidArgument, fmt::format("character {}: the end code {} inside the record",
                                                      i + 1, end == 0 ? "NULL" : "%"));
    if (f.data_bits == 7 && c > 0x7F)
      throw Error(Errc::kInvalidArgument, fmt::format("character {}: 0x{:02X} has no JIS 7-bit code", i + 1,
                                                      static_cast<unsigned>(c)));
    out.push_back(WithParity(f, c));
  }
  out.push_back(WithParity(f, end));
  return out;
}

std::string ReadRecord(Port& port, const Format& f, const RecordOptions& o) {
  const uint8_t end = EndCode(f);
  std::string text;
  size_t offset = 0;
  auto last = std::chrono::steady_clock::now();
  auto fail = [&](std::string_view why, Errc code) {
    throw Error(code, fmt::format("device {}: byte {}: {}", port.device(), offset, why));
  };
  for (;;) {
    if (o.cancel && o.cancel->load()) fail("cancelled", Errc::kFailedPrecondition);
    uint8_t b = 0;
    size_t n = 0;
    try {
      n = port.Read(std::span<uint8_t>(&b, 1), std::chrono::microseconds(20000));
    } catch (const Error& e) {
      fail(e.what(), e.code());
    }
    const auto now = std::chrono::steady_clock::now();
    if (n == 0) {
      if (offset > 0 && now - last > o.idle_timeout)
        fail(fmt::format("the device stopped sending ({:.1f} s without a byte) before the end code",
                         o.idle_timeout.count() / 1000.0),
             Errc::kTimeout);
      continue;
    }
    last = now;
    if (f.data_bits == 7 && f.parity != Parity::kNone && WithParity(f, b & 0x7F) != b)
      fail(fmt::format("parity error (0x{:02X})", static_cast<unsigned>(b)), Errc::kInvalidArgument);
    const auto c = static_cast<uint8_t>(f.data_bits == 7 ? b & 0x7F : b);
    ++offset;
    if (c == end) return text;
    if (text.size() == kRecordMax)
      fail("more than 160 characters before the end code", Errc::kInvalidArgument);
    text.push_back(static_cast<char>(c));
  }
}

}  // namespace cell::dnc
