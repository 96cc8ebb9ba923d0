// What every fuzz target does with a run it started: take at most `steps` commands (a program may loop for
// ever) and format each as cell-interp prints it, so the JSON writer is fuzzed too.
#pragma once

#include "cell/interp/interp.h"

namespace cell::fuzz {

inline void Drain(interp::Run& run, int steps) {
  for (int i = 0; i < steps; ++i) {
    interp::Step s = run.Next();
    if (s.kind != interp::Step::kCanon) break;
    (void)interp::ToJsonLine(s.canon);
  }
}

}  // namespace cell::fuzz
