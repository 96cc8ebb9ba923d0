// The rules for names that cross the bus (stations, namespaces, routes, programs, idempotency keys), the one
// guarded way to put a string into a bounded IDL string field, and how a message echoes a bad name.
//
// Fast DDS's fixed_string<N> (every bounded `string<N>` of idl/) cuts a longer value on assignment, without a
// word: a 65-character route name would silently become another route's name. Assign() is the one place user
// data enters such a field: it refuses a value that does not fit (or holds a NUL, which would end it early).
// The rules are in docs/operations.md ("Names").
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "cell/error/error.h"

namespace cell::names {

// A name as an error message shows it: quoted, bytes outside printable ASCII and the backslash escaped
// (\xNN, \\), at most `max` characters of it with "..." (and the full length, unless the message states it)
// after a longer one. Never a
// 5,000-character line, never a terminal escape sequence.
std::string Shown(std::string_view name, std::size_t max = 40, bool with_length = true);

// Each Check* throws cell::Error(kInvalidArgument) with a one-line reason naming `what` and Shown(value).
// Station id: 1-16 characters of A-Z, a-z, 0-9, '_' or '-'.
bool IsStationId(std::string_view id);
void CheckStation(std::string_view id, std::string_view what = "station id");
// A program store namespace: HOST or a station id.
void CheckNode(std::string_view node, std::string_view what = "namespace");
// Route: 1-64 characters of letters, digits, spaces, '.', '-', '_', beginning with a letter or digit and not
// ending in a space.
inline constexpr std::size_t kMaxRoute = 64;
void CheckRoute(std::string_view name);
// Program or file name, the rule every namespace shares (the store adds each dialect's own rule): 1-128
// printable ASCII characters, no '*' or '?' (list wildcards), no '/' or '\', no leading or trailing space.
inline constexpr std::size_t kMaxProgram = 128;
void CheckProgram(std::string_view name, std::string_view what = "program name");
// A list pattern: the same as a program name, with '*' and '?' allowed.
void CheckPattern(std::string_view pattern);
// An inspection record or file ("run-KT01-12.json", "KT01/GAUGE.TXT") or a pattern of them: 1-128 printable
// ASCII characters, no "..", no '\', not beginning with '/'.
void CheckRecord(std::string_view name);
// CELLCTL_IDEMPOTENCY_KEY: 1-40 printable ASCII characters without spaces. The key on the wire is
// "<key>:<verb>" (WireKey), which must fit the 64-character header field.
inline constexpr std::size_t kMaxKey = 40;
void CheckKey(std::string_view key);
std::string WireKey(std::string_view key, std::string_view verb);

// field = value for a bounded IDL string (eprosima::fastrtps::fixed_string<N>, or anything with max_size and
// assign(data, size)): throws cell::Error(kInvalidArgument) "WHAT 'shown' is L characters long; at most N
// fit" instead of cutting it.
[[noreturn]] void ThrowTooLong(std::string_view what, std::string_view value, std::size_t max);
[[noreturn]] void ThrowNul(std::string_view what, std::string_view value);
template <class Field>
void Assign(Field& field, std::string_view value, std::string_view what) {
  if (value.size() > Field::max_size) ThrowTooLong(what, value, Field::max_size);
  if (value.find('\0') != std::string_view::npos) ThrowNul(what, value);
  field.assign(value.data(), value.size());
}
// Appends value to a sequence of bounded strings, guarded the same way.
template <class Seq>
void Append(Seq& seq, std::string_view value, std::string_view what) {
  typename Seq::value_type f;
  Assign(f, value, what);
  seq.push_back(f);
}
// For free text (reasons, alarm texts, details) where shortening is acceptable: cut to fit, visibly ("..." at
// the end), never in the middle of a UTF-8 sequence.
std::string Fit(std::string_view text, std::size_t max);
template <class Field>
void AssignText(Field& field, std::string_view text) {
  std::string s = Fit(text, Field::max_size);
  field.assign(s.data(), s.size());
}

}  // namespace cell::names
