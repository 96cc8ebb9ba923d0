// The skeleton every dialect's executor shares: commands a block produces wait in a queue until the caller
// takes them, and blocks are executed one at a time only when the queue is empty (read-ahead stops at each
// block, so a queue buster's answer is there before the next block runs).
#pragma once

#include <utility>

#include "cell/interp/canon_queue.h"
#include "cell/interp/run.h"

namespace cell::interp {

class RunBase : public Run {
 public:
  void NextInto(Step& s) final {
    while (out_.empty() && !finished_) StepOnce();
    if (!out_.empty()) {
      s.kind = Step::kCanon;
      s.canon = std::move(out_.front());
      out_.pop_front();
      return;
    }
    s = final_;
  }
  const Canon* NextInPlace(Step& s) final {
    while (out_.empty() && !finished_) StepOnce();
    if (!out_.empty()) {
      // Popped, but its slot is written again only when a later call runs the next block.
      const Canon* c = &out_.front();
      out_.pop_front();
      return c;
    }
    s = final_;
    return nullptr;
  }

 protected:
  RunBase() = default;
  // Keeps the options but the program text (it may be large: the dialect reads it once into its frames), the
  // tool table and the variables (the dialect reads them into its own state); env_ is the caller's
  // environment or the offline one.
  explicit RunBase(const RunOptions& o);
  RunBase(const RunBase&) = delete;
  RunBase& operator=(const RunBase&) = delete;

  // Executes one block (or ends the run with End / Fail).
  virtual void StepOnce() = 0;

  // A new command at the end of the queue, filled in place.
  template <class T>
  T& Emit(int line) {
    return out_.Emplace<T>(line);
  }
  void Emit(Canon c) { out_.push_back(std::move(c)); }

  // The run ends after the queued commands: at its end, or at its first error (the run stops there).
  void End() {
    finished_ = true;
    final_.kind = Step::kEnd;
  }
  void EndWithError(Diagnostic d) {
    finished_ = true;
    final_.kind = Step::kError;
    final_.diag = std::move(d);
  }
  bool finished() const { return finished_; }

  CanonQueue out_;
  RunOptions opt_;
  Environment* env_ = &default_env_;

 private:
  Environment default_env_;
  bool finished_ = false;
  Step final_;
};

}  // namespace cell::interp
