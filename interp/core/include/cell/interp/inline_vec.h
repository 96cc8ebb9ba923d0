// A vector with fixed inline capacity for per-block word lists: a block has a bounded length, so it never
// holds more than a known number of words, and the hot path allocates nothing. push_back reports overflow by
// returning false (callers filling from a checked list of words know it fits).
#pragma once

#include <algorithm>
#include <cstddef>
#include <type_traits>

namespace cell::interp {

template <class T, std::size_t N>
class InlineVec {
  static_assert(std::is_trivially_copyable_v<T>, "InlineVec holds plain values");

 public:
  InlineVec() = default;
  InlineVec(const InlineVec& o) : n_(o.n_) { std::copy(o.begin(), o.end(), begin()); }
  InlineVec& operator=(const InlineVec& o) {
    n_ = o.n_;
    std::copy(o.begin(), o.end(), begin());
    return *this;
  }
  bool push_back(const T& v) {
    if (n_ >= N) return false;
    data()[n_++] = v;
    return true;
  }
  T* begin() { return data(); }
  T* end() { return data() + n_; }
  const T* begin() const { return data(); }
  const T* end() const { return data() + n_; }
  std::size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  T& operator[](std::size_t i) { return data()[i]; }
  const T& operator[](std::size_t i) const { return data()[i]; }
  T& front() { return data()[0]; }
  const T& front() const { return data()[0]; }
  T& back() { return data()[n_ - 1]; }
  const T& back() const { return data()[n_ - 1]; }
  // Keeps the first `k` elements (used with std::remove_if).
  void erase(T* from, T* to) {
    T* e = std::copy(to, end(), from);
    n_ = static_cast<std::size_t>(e - data());
  }
  void clear() { n_ = 0; }

 private:
  T* data() { return reinterpret_cast<T*>(buf_); }
  const T* data() const { return reinterpret_cast<const T*>(buf_); }
  alignas(T) unsigned char buf_[N * sizeof(T)];
  std::size_t n_ = 0;
};

}  // namespace cell::interp
