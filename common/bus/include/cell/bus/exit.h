// Ending a one-shot process (cellctl) once its participants are gone.
#pragma once

namespace cell::bus {

// Flushes stdout and stderr and ends the process with `code` without running static destructors. Call it
// only after every bus::Participant of the process has been destroyed (their goodbyes are sent then, so no
// other process waits out a lease for them). What it skips: Fast DDS's factory destructor, which sleeps
// 100 ms (RTPSDomain::stopAll) for participants a process left behind, and ran before the buffered output
// was written: 100 of a `cellctl` verb's 140 ms on a running cell (issue 38 item 2).
[[noreturn]] void ExitProcess(int code);

}  // namespace cell::bus
