// Internal helpers of the KT-APL dialect.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

// Upper, Trim, TrimView, SplitTopLevel, Statement, FindStatements (shared with the heading reader).
#include "cell/interp/ktapl_statements.h"

namespace cell::interp::ktapl {

// A vector with fixed inline capacity for the per-block word lists: a block is at most 80 characters, so
// it never holds more than 40 words, and the hot path allocates nothing. push_back reports overflow by
// returning false (callers filling from a checked list of words know it fits).
template <class T, size_t N>
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
  size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  T& operator[](size_t i) { return data()[i]; }
  const T& operator[](size_t i) const { return data()[i]; }
  T& front() { return data()[0]; }
  const T& front() const { return data()[0]; }
  T& back() { return data()[n_ - 1]; }
  const T& back() const { return data()[n_ - 1]; }
  // Keeps the first `k` elements (used with std::remove_if).
  void erase(T* from, T* to) {
    T* e = std::copy(to, end(), from);
    n_ = static_cast<size_t>(e - data());
  }
  void clear() { n_ = 0; }

 private:
  T* data() { return reinterpret_cast<T*>(buf_); }
  const T* data() const { return reinterpret_cast<const T*>(buf_); }
  alignas(T) unsigned char buf_[N * sizeof(T)];
  size_t n_ = 0;
};

}  // namespace cell::interp::ktapl
