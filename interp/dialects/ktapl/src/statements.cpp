// KT-APL block text helpers and the Type II statement scanner (see ktapl_statements.h).
#include "cell/interp/ktapl_statements.h"

#include <cctype>
#include <string>

namespace cell::interp::ktapl {

namespace {

bool IsAsciiAlpha(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
}

}  // namespace

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
  ForEachTopLevel(body, sep, angle, [&out](std::string_view field) { out.emplace_back(field); });
  return out;
}

bool NextStatement(std::string_view line, size_t& from, Statement& st, std::string* error, size_t* error_at) {
  size_t i = from;
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
        if (error_at) *error_at = i;
        from = line.size();
        return false;
      }
      st.col = static_cast<int>(i) + 1;
      std::string_view inner = line.substr(i + 1, j - i - 1);
      size_t k = 0;
      while (k < inner.size() && inner[k] == ' ') ++k;
      size_t m = k;
      // ASCII letters and digits (what isalnum and toupper give in the C locale, without their lookups).
      while (m < inner.size() && m - k < 3 &&
             (IsAsciiAlpha(inner[m]) || (inner[m] >= '0' && inner[m] <= '9')))
        ++m;
      st.mnemonic.assign(inner.substr(k, m - k));
      for (char& ch : st.mnemonic) ch = Up(ch);
      size_t rest = m;
      while (rest < inner.size() && inner[rest] == ' ') ++rest;
      st.has_body = rest < inner.size() && inner[rest] == ',';
      st.body.assign(inner.substr(st.has_body ? rest + 1 : rest));
      st.end = j + 1;
      from = j + 1;
      return true;
    }
    ++i;
  }
  from = line.size();
  return false;
}

std::vector<Statement> FindStatements(std::string_view line, std::string* error, size_t* error_at) {
  std::vector<Statement> out;
  size_t i = 0;
  Statement st;
  while (NextStatement(line, i, st, error, error_at)) out.push_back(std::move(st));
  return out;
}

}  // namespace cell::interp::ktapl
