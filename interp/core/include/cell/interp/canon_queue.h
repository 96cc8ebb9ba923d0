// FIFO of canonical commands a run has produced and the caller has not taken yet: a ring over a vector,
// because a deque of Canon (larger than a deque node) allocates and frees a node for every command.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

#include "cell/interp/canon.h"

namespace cell::interp {

class CanonQueue {
 public:
  bool empty() const { return size_ == 0; }
  std::size_t size() const { return size_; }
  Canon& front() { return ring_[head_]; }
  void pop_front() {
    head_ = (head_ + 1) & mask_;
    --size_;
  }
  void push_back(Canon c) { Slot() = std::move(c); }
  // A new last command with payload T at its defaults, filled in place by the caller (the motion hot path:
  // no Canon copies).
  template <class T>
  T& Emplace(int line) {
    Canon& c = Slot();
    c.line = line;
    return c.Set<T>();
  }
  void clear() { head_ = size_ = 0; }
  // The i-th waiting command from the front; dropping all from the i-th on (a command found unsafe to run,
  // Okuma's barrier check).
  Canon& at(std::size_t i) { return ring_[(head_ + i) & mask_]; }
  void truncate(std::size_t n) {
    if (n < size_) size_ = n;
  }

 private:
  Canon& Slot() {
    if (size_ == ring_.size()) Grow();
    Canon& c = ring_[(head_ + size_) & mask_];
    ++size_;
    return c;
  }
  void Grow() {
    std::vector<Canon> bigger(ring_.empty() ? 16 : ring_.size() * 2);
    for (std::size_t i = 0; i < size_; ++i) bigger[i] = std::move(ring_[(head_ + i) & mask_]);
    ring_.swap(bigger);
    mask_ = ring_.size() - 1;
    head_ = 0;
  }
  // The ring's size is a power of two (16, doubled when full): positions wrap with a mask, not a division
  // (two per command, one to add and one to take it).
  std::vector<Canon> ring_;
  std::size_t mask_ = 0;
  std::size_t head_ = 0, size_ = 0;
};

}  // namespace cell::interp
