#pragma once

// The stacks of every thread of this process, written to a file descriptor: what a process that ends itself
// because a thread is stuck (Participant::Watch) leaves in its log, since by then nobody can attach gdb.

namespace cell::bus {

// Loads the unwinder, so that the signal handler below never allocates. Call once early (the watch thread).
void PrepareThreadStacks();

// For each thread of the process but the caller: a line "thread TID (NAME):", then its frames (glibc
// backtrace_symbols_fd: library, mangled symbol, offset, address), got by a signal (SIGRTMIN+5) handled on
// that thread. A thread that does not answer within 500 ms (signals blocked) gets "(no answer)". Returns
// the number of threads that answered.
int WriteThreadStacks(int fd);

}  // namespace cell::bus
