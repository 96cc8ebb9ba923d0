// Route specifications: the `--op "KT01,KT02:PROG1,PROG2"` form of `cellctl route define` and the route file
// format documented in docs/scheduler.md.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace cell::scheduler {

// One operation of a route: the stations eligible for it, in preference order for ties, and the programs it
// runs (its USING list: the pallet map dispatched for that visit).
struct OpSpec {
  std::vector<std::string> stations;
  std::vector<std::string> programs;
  bool operator==(const OpSpec&) const = default;
};

struct RouteSpec {
  std::string name;
  std::vector<OpSpec> ops;
  bool operator==(const RouteSpec&) const = default;
};

// "ST1,ST2:PROG1,PROG2". Names are trimmed; a name holding ',' or ':' is written in double quotes.
// Throws cell::Error (kInvalidArgument) naming the column of the problem.
OpSpec ParseOpSpec(std::string_view text);

// The route file: blank lines and lines starting with '#' are ignored;
//   ROUTE name            starts a route (the rest of the line, trimmed, is the name)
//   OP ST1,ST2 : P1,P2    adds an operation to the current route (same syntax as ParseOpSpec)
// Keywords are case-insensitive. Throws cell::Error "SOURCE:LINE:COL: error: text".
std::vector<RouteSpec> ParseRouteFile(std::string_view text, std::string_view source = "route");

// Writes routes in the route file format (ParseRouteFile reads it back).
std::string FormatRouteFile(const std::vector<RouteSpec>& routes);

}  // namespace cell::scheduler
