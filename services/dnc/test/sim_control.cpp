// The simulated control (sim_control.h).
#include "sim_control.h"

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <deque>
#include <stdexcept>

namespace cell::dnc::test {
namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}
void Tick() {
  std::this_thread::sleep_for(std::chrono::microseconds(200));
}

}  // namespace

Pty::Pty() {
  master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (master_ < 0 || ::grantpt(master_) != 0 || ::unlockpt(master_) != 0)
    throw std::runtime_error("posix_openpt");
  slave_ = ::ptsname(master_);
  ::fcntl(master_, F_SETFL, ::fcntl(master_, F_GETFL) | O_NONBLOCK);
}

Pty::~Pty() {
  CloseMaster();
}

void Pty::CloseMaster() {
  if (master_ >= 0) ::close(master_);
  master_ = -1;
}

SimControl::~SimControl() {
  Stop();
}

void SimControl::Stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void SimControl::Join() {
  if (thread_.joinable()) thread_.join();
}

void SimControl::StartReading() {
  thread_ = std::thread([this] { ReadLoop(); });
}

void SimControl::StartPunching(std::vector<uint8_t> bytes) {
  thread_ = std::thread([this, b = std::move(bytes)]() mutable { PunchLoop(std::move(b)); });
}

void SimControl::Flow(bool stop) {
  if (!o_.xonxoff || stop == xoff_sent_) return;
  uint8_t c = stop ? 0x13 : 0x11;
  if (::write(pty_.master(), &c, 1) == 1) {
    xoff_sent_ = stop;
    if (stop) ++xoffs_;
  }
}

void SimControl::Execute(std::deque<uint8_t>& buffer, double& executed, double& pause_until,
                         size_t& since_pause, double rate, double t, double fifo) {
  // Execution empties the buffer through the control's decoder (parity and code checks).
  while (!buffer.empty() && executed + 1 <= rate * t && t >= pause_until && !decoder_.complete()) {
    uint8_t b = buffer.front();
    buffer.pop_front();
    executed += 1;
    try {
      decoder_.Feed(std::span<const uint8_t>(&b, 1));
    } catch (const std::exception& e) {
      error_ = e.what();
      return;
    }
    if (o_.pause_every && ++since_pause >= o_.pause_every) {
      since_pause = 0;
      pause_until = t + o_.pause_s;
    }
  }
  if (buffer.empty() || t < pause_until)
    executed = std::max(executed, rate * t - fifo);  // idle: owes nothing
}

void SimControl::ReadLoop() {
  std::deque<uint8_t> buffer;
  auto start = Clock::now();
  double pulled = 0, executed = 0, pause_until = 0, last_t = 0;
  size_t since_pause = 0;
  // A real control says XOFF the moment its buffer reaches `high`. This thread says it only when it runs:
  // when it ran later than the slack above `high` lasts on the line (a loaded test machine), the sender could
  // not have heard the XOFF in time, so what overflows then is the simulation's lateness, not a lost byte.
  const double slack_s = static_cast<double>(o_.buffer - std::min(o_.buffer, o_.high)) / o_.line_bytes_per_s;
  while (!stop_ && !decoder_.complete() && error_.empty()) {
    Tick();
    double t = Since(start);
    const bool late = t - last_t > slack_s;
    last_t = t;
    // The line delivers at most its rate. A late tick of ours is owed (what the line carried meanwhile
    // arrives now); an idle line owes nothing beyond a FIFO's worth.
    const double fifo = std::max(16.0, o_.line_bytes_per_s * 0.002);
    double room = o_.line_bytes_per_s * t - pulled;
    uint8_t in[4096];
    size_t want = room >= 1 ? std::min(static_cast<size_t>(room), sizeof in) : 0;
    ssize_t n = want > 0 ? ::read(pty_.master(), in, want) : 0;
    // Each byte arrives at its own moment on the line; the control executes up to that moment before it
    // lands (its UART and its execution run side by side, whenever this thread gets the processor).
    double rate = o_.exec_bytes_per_s > 0 ? o_.exec_bytes_per_s : o_.line_bytes_per_s;
    for (ssize_t i = 0; i < n; ++i) {
      double arrives = std::min(t, (pulled + static_cast<double>(i) + 1) / o_.line_bytes_per_s);
      Execute(buffer, executed, pause_until, since_pause, rate, arrives, fifo);
      wire_.push_back(in[i]);
      if (buffer.size() >= o_.buffer && !late) {
        ++lost_;
      } else {
        buffer.push_back(in[i]);
      }
      max_fill_ = std::max(max_fill_, buffer.size());
    }
    if (n > 0) pulled += static_cast<double>(n);
    pulled_ = wire_.size();
    if (n < static_cast<ssize_t>(want)) pulled = std::max(pulled, o_.line_bytes_per_s * t - fifo);
    if (buffer.size() >= o_.high) Flow(true);
    Execute(buffer, executed, pause_until, since_pause, rate, t, fifo);
    if (buffer.size() <= o_.low) Flow(false);
    if (o_.hangup_after && wire_.size() >= o_.hangup_after) {
      pty_.CloseMaster();
      return;
    }
    if (o_.stop_after && wire_.size() >= o_.stop_after && o_.xonxoff) {
      Flow(true);  // says stop and never goes on: a control that stopped answering
      o_.xonxoff = false;
    }
  }
  RunOutTrailer();
}

void SimControl::RunOutTrailer() {
  // After the end of data the reader runs the trailer through (blank tape) until the line is quiet.
  if (!decoder_.complete()) return;
  Flow(false);
  auto quiet = Clock::now();
  while (!stop_ && Since(quiet) < 0.2) {
    Tick();
    uint8_t in[512];
    ssize_t n = ::read(pty_.master(), in, sizeof in);
    if (n > 0) {
      wire_.insert(wire_.end(), in, in + n);
      quiet = Clock::now();
    }
  }
}

void SimControl::PunchLoop(std::vector<uint8_t> bytes) {
  auto start = Clock::now();
  size_t sent = 0;
  bool held = false;  // the cell's XOFF
  double due = 0;
  while (!stop_ && sent < bytes.size()) {
    Tick();
    uint8_t in[64];
    ssize_t n = ::read(pty_.master(), in, sizeof in);
    for (ssize_t i = 0; i < n; ++i) {
      if (in[i] == 0x13) held = true;
      if (in[i] == 0x11) held = false;
    }
    double t = Since(start);
    if (held || t < due) continue;
    if (o_.hangup_after && sent >= o_.hangup_after) {
      // The cell reads what is on the line first: a pty's hang-up discards what is still in its buffer.
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      pty_.CloseMaster();
      return;
    }
    if (o_.stop_after && sent >= o_.stop_after) continue;  // silent, line still up
    size_t k = std::min<size_t>(16, bytes.size() - sent);
    if (o_.hangup_after) k = std::min(k, o_.hangup_after - sent);
    if (o_.stop_after) k = std::min(k, o_.stop_after - sent);
    std::vector<uint8_t> out(bytes.begin() + static_cast<long>(sent),
                             bytes.begin() + static_cast<long>(sent + k));
    for (size_t i = 0; i < k; ++i)
      if (sent + i == o_.damage_at) out[i] ^= 0x01;
    ssize_t w = ::write(pty_.master(), out.data(), out.size());
    if (w > 0) {
      wire_.insert(wire_.end(), out.begin(), out.begin() + w);
      sent += static_cast<size_t>(w);
      due = std::max(due, t - 0.002) + static_cast<double>(w) / o_.line_bytes_per_s;
    }
  }
  // Keep the line open until the test stops us (a close is a hang-up).
  while (!stop_) Tick();
}

}  // namespace cell::dnc::test
