// The tests' simulated control on the far end of a pseudo-terminal pair (docs/dnc.md "Tests"): a small
// receive buffer that sends XOFF when it fills and XON when it drains, pulls bytes off the line at the
// emulated line rate whether or not it has room (a byte arriving at a full buffer is lost, as on a real
// control), checks each byte's parity and code through the control's Decoder, and punches programs at the
// line rate. Time is scaled: the rates are the line's times the test's scale.
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "cell/dnc/codes.h"

namespace cell::dnc::test {

// A pseudo-terminal pair: the cell opens `slave` by name, the simulated control holds the master.
class Pty {
 public:
  Pty();
  ~Pty();
  int master() const { return master_; }
  const std::string& slave() const { return slave_; }
  void CloseMaster();

 private:
  int master_ = -1;
  std::string slave_;
};

struct SimOptions {
  Format format;
  double line_bytes_per_s = 20000;  // the emulated line
  size_t buffer = 256;              // the control's receive buffer
  size_t high = 64;                 // XOFF at this fill (192 bytes of slack: scheduling, not the sender)
  size_t low = 32;                  // XON at this fill
  double exec_bytes_per_s = 0;      // how fast it empties its buffer (0: as fast as the line)
  size_t pause_every = 0;           // every so many bytes executed, a pause (a long block)
  double pause_s = 0;
  bool xonxoff = true;          // sends DC1/DC3
  size_t hangup_after = 0;      // closes the master after this many bytes (0: never)
  size_t stop_after = 0;        // stops reading, or punching, after this many bytes (0: never)
  size_t damage_at = SIZE_MAX;  // punching: flips the low bit of this byte
};

class SimControl {
 public:
  SimControl(Pty& pty, SimOptions o) : pty_(pty), o_(std::move(o)), decoder_(o_.format) {}
  ~SimControl();

  void StartReading();                             // the control reads a program the cell sends
  void StartPunching(std::vector<uint8_t> bytes);  // the control punches a program the cell receives
  void Join();                                     // waits for the thread (reading: up to the end of data)
  void Stop();

  // Bytes pulled off the line so far: safe to read while it runs (a test waits for a send under way).
  size_t pulled() const { return pulled_; }
  // After Join.
  const std::vector<uint8_t>& wire() const {
    return wire_;
  }  // every byte it pulled off the line, trailer too
  std::string text() const { return decoder_.text(); }
  bool complete() const { return decoder_.complete(); }
  size_t lost() const { return lost_; }
  size_t xoffs() const { return xoffs_; }
  size_t max_fill() const { return max_fill_; }
  const std::string& error() const { return error_; }

 private:
  void ReadLoop();
  void PunchLoop(std::vector<uint8_t> bytes);
  void Flow(bool stop);
  void RunOutTrailer();
  void Execute(std::deque<uint8_t>& buffer, double& executed, double& pause_until, size_t& since_pause,
               double rate, double t, double fifo);

  Pty& pty_;
  SimOptions o_;
  Decoder decoder_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::vector<uint8_t> wire_;
  std::atomic<size_t> pulled_{0};
  size_t lost_ = 0, xoffs_ = 0, max_fill_ = 0;
  bool xoff_sent_ = false;
  std::string error_;
};

}  // namespace cell::dnc::test
