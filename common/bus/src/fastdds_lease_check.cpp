// The bus's own PDP::check_remote_participant_liveliness for Fast DDS 2.9, in place of the library's.
//
// Fast DDS 2.9.1's lease check has two faults that this cell hit (docs/architecture.md, "Leaving" and "A
// second Fast DDS 2.9.1 fault"). Both are in this one function, which runs on the participant's event thread
// when a peer's lease timer fires:
//  - it blocks on the PDP mutex. A receive thread that handles a peer's writer leaving holds that mutex while
//    it waits for the event thread to finish its timer (ResourceEvent::unregister_timer): a deadlock, and the
//    process hears nothing from then on;
//  - it asserts that the peer's record is not cleared. A receive thread that handles a peer's leaving clears
//    the record under the mutex and cancels its timer, but cannot stop a timer that has already started and
//    waits for the mutex: the assertion aborts the process.
// The library calls this function through its PLT (objdump of libfastrtps.so.2.9.1 shows both calls, from the
// lease timers' lambdas, going there), so a definition in the executable, exported (CMakeLists.txt), is the
// one it runs. This one takes the mutex only if it is free, and otherwise tries again 100 ms later, so the
// event thread never waits for a receive thread; and it passes over a cleared record. Otherwise it does what
// the library's does: a lease run out removes the peer, and a lease still running re-arms the timer for the
// moment it would run out. Debian 12 ships 2.9.1; with another Fast DDS the library's own is left in place
// and the backend warns (FastDdsLeaseCheckMended).
#include "fastdds_lease_check.h"

#include <dlfcn.h>

#include <chrono>
#include <cstdint>
#include <mutex>
#include <thread>

#include <fastrtps/config.h>

#if FASTRTPS_VERSION_MAJOR == 2 && FASTRTPS_VERSION_MINOR == 9
#define CELL_MEND_FAST_LEASE_CHECK 1
#include <fastdds/rtps/builtin/data/ParticipantProxyData.h>
#include <fastdds/rtps/builtin/discovery/participant/PDP.h>
#include <fastdds/rtps/resources/TimedEvent.h>
#else
#define CELL_MEND_FAST_LEASE_CHECK 0
#endif

#if CELL_MEND_FAST_LEASE_CHECK
namespace eprosima::fastrtps::rtps {

namespace {
// A held mutex is usually a receive thread's short piece of discovery work: a few quick tries spare a
// reschedule. The retry is long enough that a starved event loop does not find it due again at once (the loop
// lets other threads at its timers only once no timer it re-armed is due).
constexpr int kQuickTries = 5;
constexpr auto kQuickPause = std::chrono::microseconds(200);
constexpr double kRetryMs = 100.0;

std::chrono::microseconds LeaseOf(const ParticipantProxyData& peer) {
  return std::chrono::seconds(peer.m_leaseDuration.seconds) +
         std::chrono::microseconds(peer.m_leaseDuration.nanosec / 1000);
}
}  // namespace

void PDP::check_remote_participant_liveliness(ParticipantProxyData* remote_participant) {
  std::unique_lock<std::recursive_mutex> lock(*mp_mutex, std::try_to_lock);
  for (int i = 0; !lock.owns_lock() && i < kQuickTries; ++i) {
    std::this_thread::sleep_for(kQuickPause);
    lock.try_lock();
  }
  if (!lock.owns_lock()) {
    remote_participant->lease_duration_event->update_interval_millisec(kRetryMs);
    remote_participant->lease_duration_event->restart_timer();
    return;
  }
  // Cleared under the mutex by a departure handled on a receive thread after this timer started.
  if (!remote_participant->should_check_lease_duration || remote_participant->m_guid == GUID_t::unknown())
    return;

  const auto now = std::chrono::steady_clock::now();
  const auto runs_out = remote_participant->last_received_message_tm() + LeaseOf(*remote_participant);
  if (now > runs_out) {
    const GUID_t peer = remote_participant->m_guid;  // the record may be cleared once the mutex is let go
    lock.unlock();
    remove_remote_participant(peer, ParticipantDiscoveryInfo::DROPPED_PARTICIPANT);
    return;
  }
  remote_participant->lease_duration_event->update_interval_millisec(
      static_cast<double>(std::chrono::duration_cast<std::chrono::milliseconds>(runs_out - now).count()));
  remote_participant->lease_duration_event->restart_timer();
}

}  // namespace eprosima::fastrtps::rtps
#endif

namespace cell::bus {

bool FastDdsLeaseCheckMended() {
#if CELL_MEND_FAST_LEASE_CHECK
  // The name common/bus/CMakeLists.txt exports.
  void* resolved = dlsym(RTLD_DEFAULT, CELL_FASTDDS_LEASE_CHECK_SYMBOL);
  Dl_info theirs{};
  Dl_info ours{};
  if (resolved == nullptr || dladdr(resolved, &theirs) == 0 ||
      dladdr(reinterpret_cast<void*>(&FastDdsLeaseCheckMended), &ours) == 0)
    return false;
  return theirs.dli_fbase == ours.dli_fbase;
#else
  return false;
#endif
}

}  // namespace cell::bus
