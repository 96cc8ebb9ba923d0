// Internal helpers of the KT-APL dialect.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace cell::interp::ktapl {

std::string Upper(std::string_view s);
std::string Trim(std::string_view s);
// Trim without a copy.
std::string_view TrimView(std::string_view s);

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
// Splits at `sep` outside quotes and parentheses (and <...> when `angle`).
std::vector<std::string> SplitTopLevel(std::string_view body, char sep, bool angle = false);

// A Type II statement found in a block: (MNE,body) or %MNE,body%.
struct Statement {
  std::string mnemonic;  // upper case
  std::string body;      // text after the comma
  bool has_body = false;
  int col = 0;     // 1-based column of the control-out character
  size_t end = 0;  // index just after the control-in character
};

// Type II statements at the top level of a block (not inside a ! comment).
std::vector<Statement> FindStatements(std::string_view line, std::string* error);

}  // namespace cell::interp::ktapl
