// Small text scanners the dialects share for what the host reads without running a program (names, headings,
// detection evidence): lines, upper-casing, sequence numbers, three-letter statements, words and M codes.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace cell::interp::scan {

inline bool IsDigit(char c) {
  return c >= '0' && c <= '9';
}
inline bool IsUpperAlpha(char c) {
  return c >= 'A' && c <= 'Z';
}
bool IsAlpha(char c);
bool IsAlnum(char c);
bool AllDigits(std::string_view s);

std::string Upper(std::string_view s);
// Blanks and tabs at both ends; a trailing '\r' too.
std::string_view Trim(std::string_view s);
// Lines without "\n" and a trailing "\r".
std::vector<std::string_view> Lines(std::string_view content);

// Skips an optional block delete "/" and a sequence number "N<digits>" (and spaces) at the start of an
// upper-cased, trimmed block. Sets `numbered` when there was an N number.
std::string_view SkipSequence(std::string_view s, bool* numbered = nullptr);

// Three-letter statements in an upper-cased block: "(MNE," or "(MNE)" anywhere, and the EIA form "%MNE,"
// at the start.
std::vector<std::string> Mnemonics(std::string_view upper);

// `word` ("M30", "G84") in an upper-cased block, not part of a longer word or number.
bool HasWord(std::string_view upper, std::string_view word);
// M code `code` in any spelling (M2, M02, M002).
bool HasMCode(std::string_view upper, int code);

// Generic name checks every dialect makes first: not empty, printable ASCII, no wildcard, no path separator,
// no leading or trailing blank. Throws cell::Error(kInvalidArgument) naming `label` ("KT-APL", "Okuma").
void CheckNameCharacters(std::string_view name, std::string_view label);

// A plain file name (EMCO, Balt-System programs on the host): letters, digits, '.', '-', '_', at most 32
// characters, beginning with a letter or digit.
void CheckPlainName(std::string_view name, std::string_view label);

}  // namespace cell::interp::scan
