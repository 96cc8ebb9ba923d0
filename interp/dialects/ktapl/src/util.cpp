// KT-APL helpers usable without a run: the number format. (Heading metadata and the statement scanner are
// in ktapl_meta/.)
#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <string>

#include "cell/interp/ktapl.h"

namespace cell::interp {

std::string FormatKtNumber(double v) {
  if (!std::isfinite(v)) return "0.0";
  bool neg = v < 0;
  double a = std::fabs(v);
  // The control keeps about two more significant digits than it shows; nudge by a relative 1e-10 before
  // truncating so that binary representation error (0.29 -> 0.28999999...) does not lose a digit.
  a *= 1.0 + 1e-10;
  if (a * 1e8 < 1.0) return "0.0";
  std::string out;
  if (a >= 1.0) {
    int int_digits = static_cast<int>(std::floor(std::log10(a))) + 1;
    int decimals = std::max(0, 8 - int_digits);
    double scale = std::pow(10.0, decimals);
    double t = std::floor(a * scale) / scale;
    out = fmt::format("{:.{}f}", t, decimals);
    if (decimals == 0) out += '.';
    // Truncation may have produced e.g. "10.000000" for 9.99999999 with 8 digits: keep 8 significant.
    size_t digits = 0;
    for (char c : out) digits += std::isdigit(static_cast<unsigned char>(c)) ? 1 : 0;
    if (digits > 8 && out.back() != '.') out.pop_back();
  } else {
    double t = std::floor(a * 1e8) / 1e8;
    out = fmt::format("{:.8f}", t);  // "0.xxxxxxxx"
    out.erase(0, 1);                 // leading zero suppressed
  }
  return neg ? "-" + out : out;
}

}  // namespace cell::interp
