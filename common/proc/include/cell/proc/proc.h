// What /proc says about another process: its start time, for code that signals processes it did not fork
// itself (`cellctl down`, tests: a pid alone may since belong to another process, a pid with its start time
// may not), and what it uses (benchmarks, soaks).
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <optional>

namespace cell::proc {

// A process's start time (field 22 of /proc/PID/stat, clock ticks since boot); nullopt when there is no such
// process or it is a zombie (it has ended).
std::optional<std::uint64_t> StartTime(pid_t pid);

// Its resident memory (VmRSS of /proc/PID/status) in kB; nullopt when there is no such process.
std::optional<long> ResidentKb(pid_t pid);

// How many descriptors it has open (/proc/PID/fd); nullopt when there is no such process or they cannot be
// read.
std::optional<long> OpenDescriptors(pid_t pid);

}  // namespace cell::proc
