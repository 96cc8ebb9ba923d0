// cell-dnc's bus binding (docs/dnc.md "On the bus"): the station's DNC requests served on its serial line,
// programs read from and stored into the program store, the line's state published on cell/dnc/status.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "cell/bus/bus.h"
#include "cell/dnc/line.h"
#include "cell/dnc/record.h"
#include "cell/dnc/settings.h"
#include "cell/dnc/transfer.h"
#include "cell/idl/dnc.h"
#include "cell/program_store/client.h"

namespace cell::dnc {

// How long the control may hold XOFF (or CTS low) before a transfer is given up. A send fills the control's
// memory, which reads as fast as the line; a drip feed waits while the control executes what its buffer
// holds, a long block or a dwell (judgement call 14).
inline constexpr std::chrono::seconds kSendStall{30};
inline constexpr std::chrono::seconds kDripStall{600};
// A program's READ whose station stopped asking after it this long is ended (the run was stopped, reset or
// its station died): the station asks every 200 ms while the READ waits (docs/dnc.md "Okuma READ/WRITE").
inline constexpr std::chrono::seconds kReadLease{3};

class Service {
 public:
  // Opens the line again after a transfer failed (a hang-up leaves a tty that must be opened again). Throws
  // what TtyPort::Open throws.
  using Opener = std::function<std::unique_ptr<Port>()>;
  // `line`: the station's line, opened (exclusively) before the process claimed its identity.
  Service(bus::Participant& p, std::string station, std::string dialect, Serial serial,
          std::unique_ptr<Port> line, Opener reopen);
  ~Service();  // a transfer under way is cancelled
  // From the main loop: publishes figures that changed since the line state was last written (a transfer's
  // progress is written at most every half second, and a line gone quiet calls no progress).
  // It also ends a program's READ whose station stopped asking after it (kReadLease).
  void Tick();
  Service(const Service&) = delete;
  Service& operator=(const Service&) = delete;

 private:
  cell::DncReply Handle(const cell::DncRequest& r);
  cell::DncReply Send(const cell::DncRequest& r, bool drip);
  cell::DncReply Receive(const cell::DncRequest& r);
  // A program's READ (started on its own thread, then asked after) and WRITE (docs/dnc.md "Okuma
  // READ/WRITE").
  cell::DncReply Read(const cell::DncRequest& r);
  cell::DncReply Write(const cell::DncRequest& r);
  // Throws when a program's READ holds the line: `what` ("dnc send") is refused until it ends.
  void CheckNotHeld(std::string_view what);
  struct ReadTask {
    std::string holder;  // "dispatch 12"
    std::thread thread;
    std::atomic<bool> cancel{false};
    std::atomic<bool> done{false};
    std::string record, error;  // once done
    std::chrono::steady_clock::time_point asked;
  };
  void ReadLoop(ReadTask& t);
  // Cancels a READ (its station went away) and waits for its thread.
  static void Abandon(std::unique_ptr<ReadTask> t);
  // Throws when a program of `characters` is longer than the control's memory (Serial::memory).
  void CheckMemory(const std::string& where, size_t characters) const;
  cell::DncReply Status();
  // The line, opened if it is not; a failed transfer closes it.
  Port& Line();
  // The transfer's state: begun, under way (at most every half second on the bus), ended.
  // `total`: the transfer's bytes when known (a send's), 0 for a receive.
  void Begin(cell::DncState state, const std::string& program, uint64_t total = 0);
  void Progress(const Stats& st, bool force = false);
  void End(const Stats& st, const std::string& error);
  Stats SendPaced(const std::vector<uint8_t>& bytes, decltype(SendOptions::stall_timeout) stall,
                  bool progress);
  void Publish();  // under mu_

  std::string station_;
  std::string dialect_;
  Serial serial_;
  Opener open_;
  std::unique_ptr<Port> port_;
  std::atomic<bool> cancel_{false};
  program_store::Client store_;
  std::mutex mu_;
  cell::DncStatus status_;
  std::chrono::steady_clock::time_point published_;
  bool dirty_ = false;  // status_ has figures not yet written
  bus::Writer<cell::DncStatus> status_w_;
  std::mutex task_mu_;
  std::unique_ptr<ReadTask> task_;  // a program's READ: it holds the line until asked after once done
  bus::Server<cell::DncRequest, cell::DncReply> server_;
};

}  // namespace cell::dnc
