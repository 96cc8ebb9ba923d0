// The oracle's one random source: the generator's programs and the property checks that write their own
// draw from it, so a seed means the same programs everywhere.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

namespace cell::oracle {

// splitmix64: the same sequence on every platform (std distributions are implementation-defined).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : s_(seed) {}
  std::uint64_t Next() {
    std::uint64_t z = (s_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  int Int(int lo, int hi) { return lo + static_cast<int>(Next() % static_cast<std::uint64_t>(hi - lo + 1)); }
  double Real(double lo, double hi) { return lo + (hi - lo) * static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  bool Chance(int percent) { return Int(1, 100) <= percent; }
  template <class T>
  const T& Pick(const std::vector<T>& v) {
    return v[Next() % v.size()];
  }

 private:
  std::uint64_t s_;
};

// `v` on the grid of `step` (a dialect's least input increment), so neither side of a comparison rounds it.
inline double Grid(double v, double step) {
  return std::round(v / step) * step;
}

}  // namespace cell::oracle
