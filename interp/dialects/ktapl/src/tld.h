// The one TLD parser (manual ln 3975-4097: "TLD TOOL LIFE DATA STATEMENT"), used by the executor for a
// program's (TLD,...) and by the dialect for tool-table files (cellctl tools load, cell-interp --tools).
//   (TLD,SnnTnnnnnnn[.s]CMWnnnPnnnnnDnnnnnnnnnLnnnnHnn.n)     ASCII form; %TLD,...% in EIA
// S socket, T tool (up to 7 digits, suffix .1-.7), C check, M manual, W pallet (a process compensation),
// P length, D diameter (signed; read in the unit in force, G70 inch / G71 metric, with the implied decimals
// of an axis word when written without a point), L life hhmm, H horsepower, B broken, E worn.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "cell/tooltable/tooltable.h"

namespace cell::interp::ktapl {

struct TldError {
  int col = 1;  // 1-based column in the line
  std::string text;
};

struct TldContext {
  bool metric = true;
  int max_pallet = 255;  // 127 for coded-pallet FMS stations (ln 4081-4083)
  int col0 = 1;          // column of the body's first character
  // Parameter substitution (T, P and D may be written Ln, ch. 8 "TLD - Tool Table Load Substitution"):
  // the value of Ln in program units, or throws TldError. Empty: parameters are an error.
  std::function<double(int n, int col)> param;
};

struct TldStatement {
  std::optional<tooltable::ToolEntry> entry;      // a primary or suffix data set
  std::optional<tooltable::ProcessComp> process;  // or a process compensation (W given)
};

// Parses the body of one TLD statement (the text after "TLD,"). Throws TldError.
TldStatement ParseTld(std::string_view body, const TldContext& ctx);

// The manual's ranges for one data set that did not come through a TLD statement (a station file's
// [[tools]], in millimetres): the same limits ParseTld applies, in one place. "" when it fits, else the
// TLD parser's message for the letter concerned ("TLD P VALUE 1000 MM OUTSIDE +-999.999 MM").
std::string CheckToolEntry(const tooltable::ToolEntry& e);

}  // namespace cell::interp::ktapl
