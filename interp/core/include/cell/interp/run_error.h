// The error a dialect's executor throws at a column of the current block. The dialect turns it into its
// Diagnostic (program, line, the alarm and text as its manual writes them) where it steps the block.
#pragma once

#include <string>
#include <utility>

namespace cell::interp {

// Either `alarm`, the manual's alarm as written ("0003", "510", empty when it has none), with its `text`;
// or `code`, a numbered alarm the dialect titles from its own table (Balt-System FILMS4 nn; 0: none), with
// `text` the detail after the title.
struct RunError {
  std::string alarm;
  std::string text;
  int col = 1;
  int code = 0;
};

[[noreturn]] inline void Fail(int col, std::string text, std::string alarm = {}) {
  throw RunError{std::move(alarm), std::move(text), col};
}
[[noreturn]] inline void Fail(int col, int code, std::string detail = {}) {
  throw RunError{{}, std::move(detail), col, code};
}

}  // namespace cell::interp
