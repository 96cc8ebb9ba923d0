#include "cell/interp/scan.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

#include "cell/error/error.h"

namespace cell::interp::scan {

bool IsAlpha(char c) {
  return std::isalpha(static_cast<unsigned char>(c)) != 0;
}
bool IsAlnum(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0;
}
bool AllDigits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), IsDigit);
}

std::string Upper(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> Lines(std::string_view content) {
  std::vector<std::string_view> lines;
  std::size_t start = 0;
  while (start < content.size()) {
    std::size_t end = content.find('\n', start);
    if (end == std::string_view::npos) end = content.size();
    std::string_view line = content.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    start = end + 1;
  }
  return lines;
}

std::string_view SkipSequence(std::string_view s, bool* numbered) {
  if (numbered != nullptr) *numbered = false;
  if (!s.empty() && s.front() == '/') s = Trim(s.substr(1));
  if (s.size() >= 2 && s.front() == 'N' && IsDigit(s[1])) {
    std::size_t i = 1;
    while (i < s.size() && (IsDigit(s[i]) || s[i] == '.')) ++i;
    if (numbered != nullptr) *numbered = true;
    s = Trim(s.substr(i));
  }
  return s;
}

std::vector<std::string> Mnemonics(std::string_view upper) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < upper.size(); ++i) {
    if (upper[i] != '(' && !(upper[i] == '%' && i == 0)) continue;
    std::size_t j = i + 1;
    while (j < upper.size() && upper[j] == ' ') ++j;
    if (j + 3 > upper.size()) continue;
    std::string_view m = upper.substr(j, 3);
    if (!std::all_of(m.begin(), m.end(), [](char c) { return IsUpperAlpha(c) || IsDigit(c); })) continue;
    if (!IsUpperAlpha(m[0])) continue;
    std::size_t k = j + 3;
    while (k < upper.size() && upper[k] == ' ') ++k;
    if (k < upper.size() && (upper[k] == ',' || (upper[k] == ')' && upper[i] == '('))) out.emplace_back(m);
  }
  return out;
}

bool HasWord(std::string_view upper, std::string_view word) {
  std::size_t pos = 0;
  while ((pos = upper.find(word, pos)) != std::string_view::npos) {
    bool start_ok = pos == 0 || !(IsUpperAlpha(upper[pos - 1]) || IsDigit(upper[pos - 1]));
    std::size_t end = pos + word.size();
    bool end_ok = end >= upper.size() || !(IsDigit(upper[end]) || upper[end] == '.');
    if (start_ok && end_ok) return true;
    pos = end;
  }
  return false;
}

bool HasMCode(std::string_view upper, int code) {
  for (std::size_t pos = 0; (pos = upper.find('M', pos)) != std::string_view::npos; ++pos) {
    if (pos > 0 && (IsUpperAlpha(upper[pos - 1]) || IsDigit(upper[pos - 1]))) continue;
    std::size_t i = pos + 1;
    int value = 0, digits = 0;
    while (i < upper.size() && IsDigit(upper[i]) && digits < 4)
      value = value * 10 + (upper[i++] - '0'), ++digits;
    if (digits > 0 && value == code && (i >= upper.size() || !IsDigit(upper[i]))) return true;
  }
  return false;
}

void CheckNameCharacters(std::string_view name, std::string_view label) {
  auto invalid = [](const std::string& what) { throw Error(Errc::kInvalidArgument, what); };
  if (name.empty()) invalid(fmt::format("empty {} name", label));
  for (std::size_t i = 0; i < name.size(); ++i) {
    auto c = static_cast<unsigned char>(name[i]);
    if (c < 0x20 || c >= 0x7f) {
      invalid(fmt::format("{} name contains a non-printable or non-ASCII byte 0x{:02x} at position {}", label,
                          c, i + 1));
    }
    if (c == '*' || c == '?') {
      invalid(fmt::format("{} name '{}' contains the wildcard '{}' (wildcards are for listing only)", label,
                          name, static_cast<char>(c)));
    }
    if (c == '/' || c == '\\') {
      invalid(fmt::format(
          "{} name '{}' contains a path separator '{}'; the namespace is given separately (--node)", label,
          name, static_cast<char>(c)));
    }
  }
  if (name.front() == ' ' || name.back() == ' ') {
    invalid(fmt::format("{} name '{}' has leading or trailing spaces", label, name));
  }
}

void CheckPlainName(std::string_view name, std::string_view label) {
  CheckNameCharacters(name, label);
  auto invalid = [](const std::string& what) { throw Error(Errc::kInvalidArgument, what); };
  if (name.size() > 32) {
    invalid(fmt::format("{} name '{}' is too long: {} characters, at most 32", label, name, name.size()));
  }
  if (!IsAlnum(name.front()))
    invalid(fmt::format("{} name '{}' must begin with a letter or digit", label, name));
  for (char c : name) {
    if (!(IsAlnum(c) || c == '.' || c == '-' || c == '_')) {
      invalid(
          fmt::format("{} name '{}' contains '{}'; allowed: letters, digits, '.', '-', '_'", label, name, c));
    }
  }
}

}  // namespace cell::interp::scan
