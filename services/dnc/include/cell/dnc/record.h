// Okuma User Task records (READ/WRITE, OSP-E100L ln 8075-8109): up to 160 characters exchanged with an
// external device on the station's line, in JIS 8-bit or JIS 7-bit with even parity in the eighth bit, ended
// by the line's end code (NULL or '%', ln 8093-8094). No leader or trailer: a record is not a tape.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cell/dnc/codes.h"
#include "cell/dnc/line.h"

namespace cell::dnc {

inline constexpr size_t kRecordMax = 160;  // the read and write areas (ln 8085-8086)

// Why the line cannot carry records ("" when it can): READ/WRITE speak JIS (ln 8093-8094), not EIA.
std::string RecordRefusal(const Format& f);

// The record's bytes on the line, its end code last. Throws Error(kInvalidArgument): more than 160
// characters, a character the 7-bit code lacks (0x80 and up), the end code inside the record.
std::vector<uint8_t> EncodeRecord(const Format& f, std::string_view record);

struct RecordOptions {
  // Once the first byte has arrived, a gap this long before the end code: the device stopped (Alarm B case
  // 2, ln 8101). Before it the READ waits as long as the program does (until `cancel`).
  std::chrono::milliseconds idle_timeout{10000};
  const std::atomic<bool>* cancel = nullptr;
};

// Reads one record: its characters without the end code, the parity taken off. Reads byte by byte, so what
// arrives after the end code stays on the line for the next READ. Throws Error naming the device and the
// byte: more than 160 characters before the end code (ln 8100), a parity error, a hang-up, a gap,
// cancelled.
std::string ReadRecord(Port& port, const Format& f, const RecordOptions& o);

}  // namespace cell::dnc
