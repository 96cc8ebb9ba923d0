// Okuma tool data in the cell's tool table. The control keeps a tool offset table (VTOFX[n], VTOFZ[n]) and a
// nose radius compensation table (VNSRX[n], VNSRZ[n], and a nose R pattern) by number (manual ln 1885-1922,
// 2249-2274, 7723-7745); the T word TnnttOO picks nose-R set nn, turret station tt and offset set OO. The
// cell's tool table holds one entry per number n: tool "n" (socket = turret station n) carries offset n
// (x_offset on the diameter, z_offset) and nose-R set n (nose_radius, tip).
//
// Okuma's own form of a tool table is the manual's variables, written as a program of assignments:
//   VTOFX[1]=0.5 VTOFZ[1]=-0.25 VNSRX[1]=0.8 VNSRZ[1]=0.8 VNSRP[1]=3
// (VNSRP, the nose R pattern, is the cell's name: the manual keeps the pattern in the tool data but gives it
// no variable). '%', comments, sequence names and O names may stand around them; nothing else.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "cell/tooltable/tooltable.h"

namespace cell::interp::okuma {

class ToolData {
 public:
  void Load(const tooltable::ToolTable& t) {
    table_ = t;
    memo_n_ = 0;
  }
  const tooltable::ToolTable& table() const { return table_; }

  double OffsetX(int n) const;  // diameter
  double OffsetZ(int n) const;
  double NoseX(int n) const;
  double NoseZ(int n) const;
  // The compensation radius: the larger of the X and Z values (ln 3165-3166).
  double NoseRadius(int n) const;
  int Tip(int n) const;

  // Sets one value; returns the entry as it now stands. what: 'x' / 'z' offset, 'X' / 'Z' nose radius, 'P'
  // nose R pattern.
  const tooltable::ToolEntry& Set(int n, char what, double v);

 private:
  const tooltable::ToolEntry* Entry(int n) const;
  tooltable::ToolTable table_;
  // The offset in force is looked up for every axis conversion of every move: the last entry looked up is
  // kept as a copy, not found included (Load and Set forget it).
  mutable int memo_n_ = 0;
  mutable std::optional<tooltable::ToolEntry> memo_;
  std::map<int, std::pair<double, double>> nose_xz_;  // VNSRX / VNSRZ as written in this run
};

// Okuma tool data text applied on top of `base`. Throws cell::Error(kInvalidArgument)
// "SOURCE:LINE:COL: error: text" at the first bad line, or when the text sets nothing.
tooltable::ToolTable ParseToolDataText(std::string_view text, std::string_view source,
                                       const tooltable::ToolTable& base);

// The text form of a table (what ParseToolDataText reads back).
std::string ToolDataText(const tooltable::ToolTable& t);

}  // namespace cell::interp::okuma
