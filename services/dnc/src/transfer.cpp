// Send and receive with flow control and pacing (docs/dnc.md "The line").
#include "cell/dnc/transfer.h"

#include <algorithm>
#include <array>
#include <thread>

#include <fmt/format.h>

namespace cell::dnc {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::microseconds;

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

[[noreturn]] void FailAt(const Port& port, uint64_t offset, std::string_view why,
                         Errc code = Errc::kUnavailable) {
  throw Error(code, fmt::format("device {}: byte {}: {}", port.device(), offset, why));
}

// The sender's view of the control's flow control.
class Gate {
 public:
  Gate(Port& port, const SendOptions& o) : port_(port), o_(o) {}

  // Reads what the control sent (DC1/DC3) or its CTS; waits until `due` (the pacing) or, stopped, a
  // millisecond. True when sending may go on.
  bool Open(microseconds until_due, Stats& st, uint64_t offset) {
    microseconds wait = stopped_ ? microseconds(1000) : until_due;
    if (o_.flow == Flow::kXonXoff) {
      std::array<uint8_t, 64> in{};
      size_t n = port_.Read(in, wait);
      for (size_t i = 0; i < n; ++i) {
        if (in[i] == kDc3) Stop(st);
        if (in[i] == kDc1) Go(st);
      }
    } else if (o_.flow == Flow::kRtsCts) {
      if (port_.ClearToSend()) {
        Go(st);
      } else {
        Stop(st);
        std::this_thread::sleep_for(microseconds(200));
      }
      if (!stopped_ && wait.count() > 0) std::this_thread::sleep_for(wait);
    } else if (wait.count() > 0) {
      std::this_thread::sleep_for(wait);
    }
    if (stopped_ && Clock::now() - since_ > o_.stall_timeout) {
      FailAt(port_, offset,
             fmt::format("the control stopped answering ({} held for {:.1f} s)",
                         o_.flow == Flow::kXonXoff ? "XOFF" : "CTS low", o_.stall_timeout.count() / 1000.0),
             Errc::kTimeout);
    }
    return !stopped_;
  }

 private:
  void Stop(Stats& st) {
    if (stopped_) return;
    stopped_ = true;
    since_ = Clock::now();
    ++st.stalls;
  }
  void Go(Stats& st) {
    if (!stopped_) return;
    stopped_ = false;
    st.stalled_s += Since(since_);
  }

  Port& port_;
  const SendOptions& o_;
  bool stopped_ = false;
  Clock::time_point since_;
};

}  // namespace

Stats Send(Port& port, std::span<const uint8_t> bytes, const SendOptions& o) {
  Stats st;
  Gate gate(port, o);
  auto start = Clock::now();
  auto last_progress = start;
  // Up to a UART's FIFO (16 bytes) at a time, so that a stop arrives within a few characters.
  const size_t chunk = o.bytes_per_s > 0 ? 16 : 4096;
  double due = 0;  // seconds since start when the next chunk may go
  size_t sent = 0;
  try {
    while (sent < bytes.size()) {
      if (o.cancel && o.cancel->load()) FailAt(port, sent, "cancelled", Errc::kFailedPrecondition);
      double now = Since(start);
      microseconds until_due(due > now ? static_cast<int64_t>((due - now) * 1e6) : 0);
      if (!gate.Open(until_due, st, sent)) {
        due = std::max(due, Since(start));  // the line idles while stopped: no catching up afterwards
        continue;
      }
      if (o.bytes_per_s > 0 && Since(start) < due) continue;
      size_t n = port.Write(bytes.subspan(sent, std::min(chunk, bytes.size() - sent)), microseconds(10000));
      sent += n;
      if (o.bytes_per_s > 0)
        due = std::max(due, Since(start) - 0.002) + static_cast<double>(n) / o.bytes_per_s;
      st.bytes = sent;
      if (o.progress && Clock::now() - last_progress > std::chrono::milliseconds(100)) {
        last_progress = Clock::now();
        st.seconds = Since(start);
        o.progress(st);
      }
    }
    port.Drain();
  } catch (const Error& e) {
    if (std::string_view(e.what()).starts_with("device ")) throw;
    FailAt(port, sent, e.what(), e.code());
  }
  st.bytes = sent;
  st.seconds = Since(start);
  return st;
}

Received Receive(Port& port, const Format& f, const ReceiveOptions& o) {
  Received r;
  Decoder dec(f);
  if (o.flow == Flow::kRtsCts) port.RequestToSend(true);
  auto start = Clock::now();
  auto last_byte = start;
  auto last_progress = start;
  std::array<uint8_t, 4096> buf{};
  try {
    while (!dec.complete()) {
      if (o.cancel && o.cancel->load()) FailAt(port, dec.offset(), "cancelled", Errc::kFailedPrecondition);
      size_t n = port.Read(buf, microseconds(20000));
      auto now = Clock::now();
      if (n == 0) {
        bool started = dec.offset() > 0;
        if (!started && now - start > o.first_byte_timeout) {
          FailAt(port, 0, "nothing received", Errc::kTimeout);
        }
        if (started && now - last_byte > o.idle_timeout) {
          FailAt(port, dec.offset(),
                 fmt::format("the control stopped sending ({:.1f} s without a byte) before the end of data",
                             o.idle_timeout.count() / 1000.0),
                 Errc::kTimeout);
        }
        continue;
      }
      last_byte = now;
      dec.Feed(std::span<const uint8_t>(buf.data(), n));
      r.stats.bytes = dec.offset();
      if (o.progress && now - last_progress > std::chrono::milliseconds(100)) {
        last_progress = now;
        r.stats.seconds = Since(start);
        o.progress(r.stats);
      }
    }
  } catch (const Error& e) {
    if (std::string_view(e.what()).starts_with("device ")) throw;
    if (std::string_view(e.what()).starts_with("byte ")) {
      throw Error(e.code(), fmt::format("device {}: {}", port.device(), e.what()));
    }
    FailAt(port, dec.offset(), e.what(), e.code());
  }
  r.text = dec.text();
  r.stats.bytes = dec.offset();
  r.stats.seconds = Since(start);
  return r;
}

}  // namespace cell::dnc
