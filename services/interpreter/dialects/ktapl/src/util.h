// Internal helpers of the KT-APL dialect.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace cell::interp::ktapl {

std::string Upper(std::string_view s);
std::string Trim(std::string_view s);
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
