// The stacks of this process's threads, written to a file descriptor by the threads themselves (a signal,
// SIGRTMIN+5, handled on each): what a process leaves in its log when it is stuck and nobody can attach gdb
// in time. The daemon writes its main thread's when a start-up step hangs; the bus writes every thread's
// before it ends a process whose receive thread is stuck.
#pragma once

namespace cell::stacks {

// Loads the unwinder, so that the signal handler never allocates. Call once early, on any thread; the
// writers below call it too.
void Prepare();

// The calling thread's kernel id (what WriteThreadStack takes).
long ThisThread();

// A line "thread TID (NAME):", then that thread's frames (glibc backtrace_symbols_fd: library, mangled
// symbol, offset, address), or "  (no answer)" when it does not answer within 500 ms (signals blocked, or
// ended). Not for the calling thread itself. Returns whether it answered. One writer at a time per process.
bool WriteThreadStack(int fd, long tid);

// WriteThreadStack for every thread of the process but the caller. Returns the number that answered.
int WriteThreadStacks(int fd);

}  // namespace cell::stacks
