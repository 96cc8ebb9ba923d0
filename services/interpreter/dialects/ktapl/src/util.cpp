// KT-APL helpers usable without a run: number format, heading metadata, tool tables.
#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <string>

#include "cell/error/error.h"
#include "cell/interp/ktapl.h"
#include "util.h"

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

namespace ktapl {

std::string Upper(std::string_view s) {
  std::string r(s);
  for (char& c : r) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return r;
}

std::string_view TrimView(std::string_view s) {
  size_t b = 0, e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t' || s[b] == '\r')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t' || s[e - 1] == '\r')) --e;
  return s.substr(b, e - b);
}

std::string Trim(std::string_view s) {
  return std::string(TrimView(s));
}

std::vector<std::string> SplitTopLevel(std::string_view body, char sep, bool angle) {
  std::vector<std::string> out;
  int depth = 0;
  bool quote = false;
  size_t start = 0;
  for (size_t i = 0; i < body.size(); ++i) {
    char c = body[i];
    if (quote) {
      if (c == '"') quote = false;
      continue;
    }
    if (c == '"') {
      quote = true;
    } else if (c == '(' || (angle && c == '<')) {
      ++depth;
    } else if ((c == ')' || (angle && c == '>')) && depth > 0) {
      --depth;
    } else if (c == sep && depth == 0) {
      out.emplace_back(body.substr(start, i - start));
      start = i + 1;
    }
  }
  out.emplace_back(body.substr(start));
  return out;
}

std::vector<Statement> FindStatements(std::string_view line, std::string* error) {
  std::vector<Statement> out;
  size_t i = 0;
  while (i < line.size()) {
    char c = line[i];
    if (c == '!') break;
    if (c == '(' ||
        (c == '%' && i + 3 < line.size() && std::isalpha(static_cast<unsigned char>(line[i + 1])))) {
      char close = c == '(' ? ')' : '%';
      int depth = 0;
      bool quote = false;
      size_t j = i + 1;
      for (; j < line.size(); ++j) {
        char d = line[j];
        if (quote) {
          if (d == '"') quote = false;
          continue;
        }
        if (d == '"') {
          quote = true;
        } else if (close == ')' && d == '(') {
          ++depth;
        } else if (d == close) {
          if (depth == 0) break;
          --depth;
        }
      }
      if (j >= line.size()) {
        if (error) *error = "MISSING CONTROL-IN CHARACTER";
        return out;
      }
      Statement st;
      st.col = static_cast<int>(i) + 1;
      std::string_view inner = line.substr(i + 1, j - i - 1);
      size_t k = 0;
      while (k < inner.size() && inner[k] == ' ') ++k;
      size_t m = k;
      while (m < inner.size() && m - k < 3 && std::isalnum(static_cast<unsigned char>(inner[m]))) ++m;
      st.mnemonic = Upper(inner.substr(k, m - k));
      size_t rest = m;
      while (rest < inner.size() && inner[rest] == ' ') ++rest;
      if (rest < inner.size() && inner[rest] == ',') {
        st.has_body = true;
        st.body = std::string(inner.substr(rest + 1));
      } else {
        st.has_body = false;
        st.body = std::string(inner.substr(rest));
      }
      st.end = j + 1;
      out.push_back(std::move(st));
      i = j + 1;
      continue;
    }
    ++i;
  }
  return out;
}

}  // namespace ktapl

KtaplMetadata ExtractKtaplMetadata(std::string_view text) {
  KtaplMetadata md;
  int line_no = 0;
  int stage = 0;  // 0 start, 1 after %, 2 after NAM, 3 after UTL, 4 after UCY, 5 body
  size_t pos = 0;
  bool seen_percent = false;
  while (pos <= text.size() && stage < 5) {
    size_t nl = text.find('\n', pos);
    std::string_view line =
        text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    pos = nl == std::string_view::npos ? text.size() + 1 : nl + 1;
    ++line_no;
    std::string t = ktapl::Trim(line);
    if (t.empty()) continue;
    if (t == "%") {
      if (seen_percent || stage > 0) {
        md.warnings.push_back(fmt::format("{}: % rewind stop is not the first item", line_no));
      }
      seen_percent = true;
      stage = std::max(stage, 1);
      continue;
    }
    if (t[0] != '(' && t[0] != '%') {
      stage = 5;
      break;
    }
    std::string err;
    auto sts = ktapl::FindStatements(t, &err);
    if (sts.size() != 1) {
      stage = 5;
      break;
    }
    const auto& st = sts[0];
    if (st.mnemonic == "NAM") {
      std::string name = ktapl::Trim(st.body);
      if (name.empty() || name.size() > 32) {
        md.warnings.push_back(fmt::format("{}: NAM name must have 1 to 32 characters", line_no));
      }
      if (name.size() > 32) name.resize(32);
      if (!name.empty()) md.name = name;
      if (stage >= 2) md.warnings.push_back(fmt::format("{}: NAM must come right after %", line_no));
      stage = std::max(stage, 2);
    } else if (st.mnemonic == "UTL") {
      if (stage >= 3) md.warnings.push_back(fmt::format("{}: UTL must come right after % and NAM", line_no));
      for (auto& f : ktapl::SplitTopLevel(st.body, ',')) {
        std::string tool = ktapl::Trim(f);
        if (!tool.empty() && (tool[0] == 'T' || tool[0] == 't')) tool.erase(0, 1);
        bool ok = !tool.empty() && tool.size() <= 7;
        for (char c : tool) ok = ok && std::isdigit(static_cast<unsigned char>(c));
        if (!ok) {
          md.warnings.push_back(fmt::format("{}: UTL tool '{}' is not a tool number of up to 7 digits",
                                            line_no, ktapl::Trim(f)));
          continue;
        }
        md.tools.push_back(tool);
      }
      stage = 3;
    } else if (st.mnemonic == "UCY") {
      if (stage < 3) {
        md.warnings.push_back(fmt::format("{}: UCY should come right after UTL", line_no));
      }
      std::string v = ktapl::Trim(st.body);
      bool ok = !v.empty() && v.size() <= 7;
      for (char c : v) ok = ok && std::isdigit(static_cast<unsigned char>(c));
      if (ok) {
        md.cycle_s = std::stol(v);
      } else {
        md.warnings.push_back(fmt::format("{}: UCY needs whole seconds (up to 7 digits)", line_no));
      }
      stage = 4;
    } else {
      stage = 5;
    }
  }
  // Statements of the heading found later in the program are misplaced.
  int ln = 0;
  size_t p = 0;
  bool past_heading = false;
  while (p <= text.size()) {
    size_t nl = text.find('\n', p);
    std::string_view line = text.substr(p, nl == std::string_view::npos ? std::string_view::npos : nl - p);
    p = nl == std::string_view::npos ? text.size() + 1 : nl + 1;
    ++ln;
    std::string t = ktapl::Trim(line);
    if (t.empty() || t == "%") continue;
    auto sts = ktapl::FindStatements(t, nullptr);
    bool heading = t[0] == '(' && sts.size() == 1 &&
                   (sts[0].mnemonic == "NAM" || sts[0].mnemonic == "UTL" || sts[0].mnemonic == "UCY");
    if (!heading) {
      past_heading = true;
      for (const auto& st : sts) {
        if (st.mnemonic == "NAM" || st.mnemonic == "UTL" || st.mnemonic == "UCY") {
          md.warnings.push_back(fmt::format("{}: {} is only read in the program heading", ln, st.mnemonic));
        }
      }
    } else if (past_heading) {
      md.warnings.push_back(fmt::format("{}: {} is only read in the program heading", ln, sts[0].mnemonic));
    }
  }
  if (!seen_percent) md.warnings.push_back("1: program does not start with the % rewind stop");
  return md;
}

}  // namespace cell::interp
