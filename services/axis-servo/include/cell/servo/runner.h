// Runner: a Machine on its own servo thread, safe to call from DDS listener threads.
//
//   Runner r(machine::LoadMachineConfig(file), ClockKind::kVirtual, [&](const Event& e) { publish(e); });
//   r.Start();
//   if (r.credits() > 0) r.Push(segment);       // from the segment listener
//   AxisState s = r.State();                    // from a wall-clock telemetry timer
//   r.Control([](Machine& m) { m.FeedHold(); }); // operator commands
//   r.Stop();                                   // or destructor
//
// The thread steps the machine every servo period (real clock: paced by the wall clock, sleeping outside
// the lock) or as fast as it can (virtual clock), and sleeps while a virtual machine is idle until Push()
// or Control() wakes it. Events are delivered on the servo thread, in order, with no lock held.
#pragma once

#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

#include "cell/servo/machine.h"

namespace cell::servo {

class Runner {
 public:
  using EventSink = std::function<void(const Event&)>;
  Runner(machine::MachineConfig config, ClockKind clock, EventSink sink);
  ~Runner();
  Runner(const Runner&) = delete;
  Runner& operator=(const Runner&) = delete;

  void Start();
  void Stop();

  std::size_t credits() const;
  void Push(const Segment& segment);  // throws like Machine::Push
  AxisState State() const;
  double machine_time() const;
  // Runs f(machine) under the lock (controls, tool table, part models, queries) and wakes the thread.
  template <class F>
  auto Control(F&& f) {
    std::unique_lock lock(mu_);
    struct Wake {
      Runner* r;
      ~Wake() { r->cv_.notify_all(); }
    } wake{this};
    return f(machine_);
  }
  // Blocks until the machine is idle with nothing queued (virtual clock) or `timeout_s` wall seconds.
  bool WaitIdle(double timeout_s);

 private:
  void Loop();

  mutable std::mutex mu_;
  std::condition_variable cv_;
  Machine machine_;
  EventSink sink_;
  std::thread thread_;
  bool running_ = false, idle_ = false;
};

}  // namespace cell::servo
