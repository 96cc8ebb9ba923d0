// A serial line: the byte port the transfers use (a termios tty, or a simulated line in tests), and the
// tty itself (open, raw mode, baud, data bits, parity, stop bits). Errors are one line naming the device:
// "device /dev/ttyS0: busy (held by another process)".
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "cell/dnc/settings.h"

namespace cell::dnc {

// What the flow-control layer needs of a line. Read and Write never block longer than `wait`. They throw
// Error with the reason alone ("hang-up", "parity or framing error (0xHH)"); the transfer adds the device
// and the byte offset.
class Port {
 public:
  virtual ~Port() = default;
  virtual const std::string& device() const = 0;
  // Bytes read into `out` (0: none within `wait`).
  virtual size_t Read(std::span<uint8_t> out, std::chrono::microseconds wait) = 0;
  // Bytes written (0: the line took none within `wait`).
  virtual size_t Write(std::span<const uint8_t> bytes, std::chrono::microseconds wait) = 0;
  // RTS/CTS: whether the far end lets us send, and our own request to send (lines without the signals: true).
  virtual bool ClearToSend() = 0;
  virtual void RequestToSend(bool on) = 0;
  // Blocks until every byte written is on the line.
  virtual void Drain() = 0;
};

// Marks of a tty's input with PARMRK (\377 \0 c: a parity or framing error on c; \377 \377: a data 0xFF)
// taken out, across reads.
class Unmarker {
 public:
  // Rewrites `bytes` in place and returns how many good bytes lead it; at a damaged byte it stops there and
  // sets `damaged` to it (the bytes after it are dropped: the transfer ends at the damage).
  size_t Take(std::span<uint8_t> bytes, std::optional<uint8_t>& damaged);

 private:
  int state_ = 0;  // 0 plain, 1 after \377, 2 after \377 \0
};

// A tty through termios: raw, 8 data bits carrying the eighth-bit parity of 7-bit codes (7E1 on the wire),
// CS7 for 7 bits without parity, the UART's parity only with 8 data bits and parity, CLOCAL (three-wire
// cables have no DCD), PARMRK marking framing and parity errors, no kernel flow control (the layer above
// does XON/XOFF and RTS/CTS). Exclusive: flock and TIOCEXCL, so a second process gets "busy".
class TtyPort : public Port {
 public:
  // Throws Error naming the device: kNotFound (does not exist), kUnavailable (busy), kPermissionDenied,
  // kInvalidArgument (not a tty, or a baud rate termios lacks).
  static std::unique_ptr<TtyPort> Open(const Serial& s);
  ~TtyPort() override;

  const std::string& device() const override { return device_; }
  size_t Read(std::span<uint8_t> out, std::chrono::microseconds wait) override;
  size_t Write(std::span<const uint8_t> bytes, std::chrono::microseconds wait) override;
  bool ClearToSend() override;
  void RequestToSend(bool on) override;
  void Drain() override;
  int fd() const { return fd_; }

 private:
  TtyPort(std::string device, int fd) : device_(std::move(device)), fd_(fd) {}
  [[noreturn]] void Fail(std::string_view what, int err) const;
  std::string device_;
  int fd_ = -1;
  Unmarker unmark_;
  std::optional<uint8_t> damaged_;  // thrown by the next Read, once the good bytes before it are taken
};

// Bytes per second on a line of `s`: start bit, data bits (the eighth-bit parity counted as data), UART
// parity bit, stop bits.
double LineRate(const Serial& s);

}  // namespace cell::dnc
