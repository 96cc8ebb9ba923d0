#include "cell/names/names.h"
#include "cell/names/program_ref.h"

#include <algorithm>

namespace cell::names {

namespace {

bool Printable(char c) {
  return c >= 0x20 && c <= 0x7e;
}
bool Alnum(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
}

[[noreturn]] void Bad(std::string_view what, std::string_view value, std::string_view why) {
  throw Error(Errc::kInvalidArgument, std::string(what) + " " + Shown(value) + ": " + std::string(why));
}

void CheckLength(std::string_view what, std::string_view value, std::size_t max) {
  if (value.empty()) throw Error(Errc::kInvalidArgument, std::string(what) + " is empty");
  if (value.size() > max) ThrowTooLong(what, value, max);
}

// Printable ASCII only: no control characters (escape sequences), no bytes above 0x7e.
void CheckPrintable(std::string_view what, std::string_view value) {
  for (char c : value)
    if (!Printable(c)) Bad(what, value, "only printable ASCII characters are allowed");
}

}  // namespace

std::string Shown(std::string_view name, std::size_t max, bool with_length) {
  static const char* hex = "0123456789abcdef";
  std::string out = "'";
  std::size_t n = 0;
  for (char c : name) {
    if (n == max) break;
    ++n;
    auto u = static_cast<unsigned char>(c);
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '\'') {
      out += "\\'";
    } else if (Printable(c)) {
      out += c;
    } else {
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 15];
    }
  }
  out += "'";
  if (name.size() > max) {
    out.insert(out.size() - 1, "...");
    if (with_length) out += " (" + std::to_string(name.size()) + " characters)";
  }
  return out;
}

bool IsStationId(std::string_view id) {
  return !id.empty() && id.size() <= 16 &&
         std::all_of(id.begin(), id.end(), [](char c) { return Alnum(c) || c == '_' || c == '-'; });
}

void CheckStation(std::string_view id, std::string_view what) {
  if (!IsStationId(id)) Bad(what, id, "must be 1-16 characters of A-Z, a-z, 0-9, '_' or '-'");
}

// A station's further program memories (Balt-System MP0, MP2..MP6) are namespaces "ID/MPn"; its default
// memory MP1 is the station's own namespace "ID" (docs/program-store.md, "Memories").
void CheckNode(std::string_view node, std::string_view what) {
  if (node == "HOST" || IsStationId(node)) return;
  const std::size_t slash = node.find('/');
  if (slash != std::string_view::npos && IsStationId(node.substr(0, slash))) {
    std::string_view memory = node.substr(slash + 1);
    if (memory == "MP1") Bad(what, node, "MP1 is the station's default memory: write the station id alone");
    if (memory.size() == 3 && memory.substr(0, 2) == "MP" && memory[2] >= '0' && memory[2] <= '6') {
      if (node.size() > 16) Bad(what, node, "is longer than the 16 characters of a namespace");
      return;
    }
  }
  Bad(what, node, "must be HOST, a station id or a station's memory ID/MP0, ID/MP2 .. ID/MP6");
}

ProgramRef SplitProgramRef(std::string_view entry) {
  const std::size_t colon = entry.find(':');
  if (colon != std::string_view::npos && colon + 1 < entry.size()) {
    try {
      CheckNode(entry.substr(0, colon));
      return {std::string(entry.substr(0, colon)), std::string(entry.substr(colon + 1))};
    } catch (const Error&) {
      // not a namespace: the whole entry is the name
    }
  }
  return {"", std::string(entry)};
}

std::string NodeStation(std::string_view node) {
  if (node == "HOST") return "";
  return std::string(node.substr(0, node.find('/')));
}

void CheckProgramRef(std::string_view entry, std::string_view what) {
  CheckLength(what, entry, kMaxProgram);  // the whole entry crosses the bus as one program name
  const ProgramRef ref = SplitProgramRef(entry);
  CheckProgram(ref.name, what);
}

void CheckRoute(std::string_view name) {
  CheckLength("route name", name, kMaxRoute);
  CheckPrintable("route name", name);
  if (!Alnum(name.front())) Bad("route name", name, "must begin with a letter or digit");
  if (name.back() == ' ') Bad("route name", name, "must not end in a space");
  for (char c : name)
    if (!Alnum(c) && c != ' ' && c != '.' && c != '-' && c != '_')
      Bad("route name", name, "only letters, digits, spaces, '.', '-' and '_' are allowed");
}

void CheckPattern(std::string_view pattern) {
  CheckLength("pattern", pattern, kMaxProgram);
  CheckPrintable("pattern", pattern);
  if (pattern.find_first_of("/\\") != std::string_view::npos) Bad("pattern", pattern, "no '/' or '\\'");
}

void CheckProgram(std::string_view name, std::string_view what) {
  CheckLength(what, name, kMaxProgram);
  CheckPrintable(what, name);
  if (name.find_first_of("*?") != std::string_view::npos)
    Bad(what, name, "'*' and '?' are list wildcards, not name characters");
  if (name.find_first_of("/\\") != std::string_view::npos) Bad(what, name, "no '/' or '\\'");
  if (name.front() == ' ' || name.back() == ' ') Bad(what, name, "no leading or trailing space");
  // A namespace is a directory on the stations' side (and in exports): "." and ".." name directories.
  if (name == "." || name == "..") Bad(what, name, "'.' and '..' name directories, not programs");
}

void CheckRecord(std::string_view name) {
  CheckLength("record name", name, kMaxProgram);
  CheckPrintable("record name", name);
  if (name.find("..") != std::string_view::npos || name.front() == '/' ||
      name.find('\\') != std::string_view::npos)
    Bad("record name", name, "no \"..\", no '\\', no leading '/'");
}

void CheckKey(std::string_view key) {
  const std::string_view what = "CELLCTL_IDEMPOTENCY_KEY";
  if (key.size() > kMaxKey)
    throw Error(Errc::kInvalidArgument,
                std::string(what) + " " + Shown(key, 40, false) + " is " + std::to_string(key.size()) +
                    " characters long; at most " + std::to_string(kMaxKey) +
                    " are allowed (it travels with the verb in a 64-character field)");
  CheckLength(what, key, kMaxKey);
  for (char c : key)
    if (!Printable(c) || c == ' ')
      Bad(what, key, "only printable ASCII characters without spaces are allowed");
}

std::string WireKey(std::string_view key, std::string_view verb) {
  CheckKey(key);
  std::string k = std::string(key) + ":" + std::string(verb);
  if (k.size() > 64) ThrowTooLong("idempotency key", k, 64);  // a verb too long for the rule above: a bug
  return k;
}

void ThrowTooLong(std::string_view what, std::string_view value, std::size_t max) {
  throw Error(Errc::kInvalidArgument, std::string(what) + " " + Shown(value, 40, false) + " is " +
                                          std::to_string(value.size()) + " characters long; at most " +
                                          std::to_string(max) + " are allowed");
}

void ThrowNul(std::string_view what, std::string_view value) {
  Bad(what, value, "contains a NUL byte");
}

std::string Fit(std::string_view text, std::size_t max) {
  std::string s(text);
  std::replace(s.begin(), s.end(), '\0', ' ');
  if (s.size() <= max) return s;
  std::size_t cut = max >= 3 ? max - 3 : 0;
  // Back up to the start of a UTF-8 sequence (continuation bytes are 10xxxxxx).
  while (cut > 0 && (static_cast<unsigned char>(s[cut]) & 0xc0) == 0x80) --cut;
  return s.substr(0, cut) + std::string("...").substr(0, max - cut);
}

}  // namespace cell::names
