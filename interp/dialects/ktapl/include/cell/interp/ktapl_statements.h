// KT-APL block text: trimming, upper case, top-level splitting and the Type II statements of a block
// ((MNE,body) or %MNE,body%). Shared by the executor and the heading reader (ktapl.h).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace cell::interp::ktapl {

// One character to upper case, ASCII only (std::toupper's locale lookup is slow on the interpreter's hot
// path, and KT-APL text is ASCII).
inline char Up(char c) {
  return (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : c;
}
std::string Upper(std::string_view s);
std::string Trim(std::string_view s);
// Trim without a copy.
std::string_view TrimView(std::string_view s);

// Splits at `sep` outside quotes and parentheses (and <...> when `angle`).
std::vector<std::string> SplitTopLevel(std::string_view body, char sep, bool angle = false);
// The same fields as views into `body`, handed to `field` in order (PAR's assignments: no copies per block).
template <class Fn>
void ForEachTopLevel(std::string_view body, char sep, bool angle, Fn&& field) {
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
      field(body.substr(start, i - start));
      start = i + 1;
    }
  }
  field(body.substr(start));
}

// A Type II statement found in a block: (MNE,body) or %MNE,body%.
struct Statement {
  std::string mnemonic;  // upper case
  std::string body;      // text after the comma
  bool has_body = false;
  int col = 0;     // 1-based column of the control-out character
  size_t end = 0;  // index just after the control-in character
};

// Type II statements at the top level of a block (not inside a ! comment). A statement without its
// control-in character ends the scan: `error` gets "MISSING CONTROL-IN CHARACTER" and `error_at` the index
// of that statement's control-out character; the statements before it are returned.
std::vector<Statement> FindStatements(std::string_view line, std::string* error, size_t* error_at = nullptr);
// The first of them at or after index `from` into `st` (its strings reused), `from` moved past it; false at
// the end of the block's statements (or at the one without its control-in character, as above).
bool NextStatement(std::string_view line, size_t& from, Statement& st, std::string* error,
                   size_t* error_at = nullptr);

}  // namespace cell::interp::ktapl
