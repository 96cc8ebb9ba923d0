// Sending and receiving over a Port with the line's flow control (XON/XOFF: DC1/DC3 from the control;
// RTS/CTS: the control's CTS) and pacing at the line rate, so that what a control's buffer holds when it
// says stop is a few bytes, as from a UART (docs/dnc.md "The line"). Errors are one line naming the device
// and the byte offset: "device /dev/ttyS0: byte 1234: hang-up".
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <string>

#include "cell/dnc/codes.h"
#include "cell/dnc/line.h"
#include "cell/dnc/settings.h"

namespace cell::dnc {

inline constexpr uint8_t kDc1 = 0x11;  // XON
inline constexpr uint8_t kDc3 = 0x13;  // XOFF

struct Stats {
  uint64_t bytes = 0;
  uint64_t stalls = 0;  // times the control said stop
  double seconds = 0;
  double stalled_s = 0;  // time spent stopped
  double Rate() const { return seconds > 0 ? static_cast<double>(bytes) / seconds : 0; }
};

struct SendOptions {
  Flow flow = Flow::kXonXoff;
  double bytes_per_s = 0;  // pacing: LineRate(serial) times a test's time scale; 0 sends unpaced
  std::chrono::milliseconds stall_timeout{30000};  // stopped this long: the control stopped answering
  std::function<void(const Stats&)> progress;      // about every 100 ms
  const std::atomic<bool>* cancel = nullptr;
};

// Sends `bytes` and returns once the last one is on the line (Drain). Throws Error naming the device and
// the offset of the first byte not sent: hang-up, the control stopped answering, cancelled.
Stats Send(Port& port, std::span<const uint8_t> bytes, const SendOptions& o);

struct ReceiveOptions {
  Flow flow = Flow::kXonXoff;
  std::chrono::milliseconds first_byte_timeout{600000};  // the operator starts the punch
  std::chrono::milliseconds idle_timeout{10000};         // then a gap this long: the control stopped
  std::function<void(const Stats&)> progress;
  const std::atomic<bool>* cancel = nullptr;
};

struct Received {
  std::string text;
  Stats stats;
};

// Receives one program in `f` up to its end-of-data code. Throws Error naming the device and the byte
// offset: a parity, framing or code error, a hang-up, a gap longer than the idle timeout before the end.
Received Receive(Port& port, const Format& f, const ReceiveOptions& o);

}  // namespace cell::dnc
