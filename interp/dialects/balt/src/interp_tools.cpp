// Balt-System tool data (manual ln 2472-2488, §5.17.5, §5.17.7, §6.4-6.6): the T word "tool.offset", M06
// activating the offset (length on the axis its record names, diameter K), the offsets file FI1COR as the
// run's tool table, the tool life file GE1TOL with its alternative tools, RQU / RQP and TOF.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "cell/error/error.h"
#include "interp_internal.h"

namespace cell::interp::balt {

void SplitTool(const Val& v, double value, int* tool, int* offset, bool* has_offset) {
  double whole = std::floor(value);
  // A number past any tool's range stays past it (the callers' 1-9999 check names it) without overflowing.
  *tool = static_cast<int>(std::min(whole, 99999999.0));
  if (v.kind == Val::kNum) {
    // The digits after the point are the offset number as written: T1.10 is offset 10 (a judgement call).
    *has_offset = v.point && v.frac >= 0;
    *offset = v.frac < 0 ? 0 : v.frac;
    return;
  }
  // From an E parameter: the decimals up to four places, trailing zeros dropped (12.12 -> 12).
  long frac = std::lround((value - whole) * 10000);
  while (frac != 0 && frac % 10 == 0) frac /= 10;
  *offset = static_cast<int>(frac);
  *has_offset = frac != 0;
}

void BaltRun::ToolWord(const Word& w) {
  double v = ValueOf(w.v, w.col);
  if (v < 0) Fail(w.col, 13, "T is positive");
  int tool = 0, offset = 0;
  bool has_offset = false;
  SplitTool(w.v, v, &tool, &offset, &has_offset);
  if (tool > 9999) Fail(w.col, 18, fmt::format("tool {} (tools are 1-9999)", tool));
  if (offset > 9999) Fail(w.col, 18, fmt::format("offset {} (offsets are 1-9999)", offset));
  if (tool > 0) RandomPocket(tool, w.col);  // "the interface checks whether the programmed T is valid"
  next_tool_ = tool;
  next_offset_ = has_offset ? offset : 0;
  next_tool_col_ = w.col;
  if (tool > 0) Out<ToolSelectOp>().tool = std::to_string(tool);
}

const tooltable::ToolEntry* BaltRun::FindOffset(int n) const {
  return tools_.Find(std::to_string(n));
}

// M06 (ln 2476-2488, 2565): the tool of the T word goes in and its offset becomes active; "TM6" (no offset
// number) deactivates the offset. With a tool life file, a tool out of life gives way to its alternative.
void BaltRun::ToolChange(int col) {
  if (next_tool_ < 0) Fail(col, 49, "M06 without T");
  int tool = next_tool_, offset = next_offset_;
  const int requested = tool;
  if (life_ && tool > 0) {
    auto it = life_->tools.find(tool);
    if (it == life_->tools.end())
      Fail(next_tool_col_, 82, fmt::format("tool {} is not in the tool life file", tool));
    std::set<int> seen{tool};
    for (;;) {
      ToolLife& t = it->second;
      bool usable = t.status == 'B' || t.status == 'C' || t.status == 'E' || t.status == 'F';
      if (usable && !((t.status == 'B' || t.status == 'E') && t.left_min < t.min_min)) {
        if (t.status == 'B') t.status = 'E';
        if (t.status == 'C') t.status = 'F';
        life_changed_ = true;
        break;
      }
      // ln 8480-8493: the alternative; a tool alternative to itself ends in FILMS4 72, to T0 in the
      // machine logic's message.
      if (t.alt_tool == 0)
        Fail(next_tool_col_, 56, fmt::format("tool {} is out of use and has no alternative", t.tool));
      if (seen.count(t.alt_tool))
        Fail(next_tool_col_, 72, fmt::format("tool {} and its alternatives", requested));
      seen.insert(t.alt_tool);
      offset = t.alt_offset;
      it = life_->tools.find(t.alt_tool);
      if (it == life_->tools.end()) Fail(next_tool_col_, 57, fmt::format("tool {}", t.alt_tool));
      tool = it->first;
    }
  }
  tool_len_ = 0;
  tool_dia_ = 0;
  len_axis_ = kZ;
  active_offset_ = offset;
  if (offset > 0) {
    const tooltable::ToolEntry* e = FindOffset(offset);
    if (!e && !tools_.entries().empty())
      Fail(next_tool_col_, 44, fmt::format("offset {} is not in FI1COR", offset));
    if (e) {
      tool_len_ = e->length;
      tool_dia_ = e->diameter;
      int a = AxisOfLetter(e->length_axis);
      len_axis_ = a >= 0 ? a : kZ;
    }
  }
  FrameChanged();  // the new length applies with the next move of its axis
  const int pocket = tool > 0 ? RandomPocket(tool, next_tool_col_) : 0;
  if (random_) spindle_special_ = tool > 0 && random_->special.at(tool) ? tool : 0;
  ToolChangeOp& c = Out<ToolChangeOp>();
  c.tool = std::to_string(tool);
  c.offset = offset;
  c.socket = pocket;  // with FI1RAN the pocket its record names (ln 8551-8553); else the station's table
}

// FI1RAN on memory MP0 (ln 8527); offline (--lib) under its bare name.
void BaltRun::LoadRandomTools() {
  auto text = opt_.library ? opt_.library("FI1RAN/MP0") : std::nullopt;
  if (!text && opt_.library) text = opt_.library("FI1RAN");
  if (!text) return;
  try {
    random_ = ParseRandomTools(*text);
  } catch (const FileError& e) {
    throw Error(Errc::kInvalidArgument, fmt::format("FI1RAN:{}:{}: error: [FILMS4 {:02}] {}: {}", e.line,
                                                    e.col, e.code, FilmsText(e.code), e.text));
  }
}

// The pocket of `tool` under random tool management, 0 without it. A tool the file does not hold is FILMS4
// 82 (judgement call 47); RANDOM_TOOLS=1 without the file FILMS4 83 (ln 10144-10145); a standard tool while a
// special one is on the spindle FILMS4 90 (ln 10158-10160: T0 M06 puts the special tool away first).
int BaltRun::RandomPocket(int tool, int col) {
  if (!random_) {
    if (random_required_) Fail(col, 83, fmt::format("T{}: FI1RAN is not on MP0 (RANDOM_TOOLS=1)", tool));
    return 0;
  }
  auto it = random_->pocket.find(tool);
  if (it == random_->pocket.end()) Fail(col, 82, fmt::format("tool {} is not in the random tool file", tool));
  if (spindle_special_ != 0 && tool != spindle_special_ && !random_->special.at(tool))
    Fail(col, 90,
         fmt::format("standard tool {} while special tool {} is on the spindle", tool, spindle_special_));
  return it->second;
}

void BaltRun::LoadToolLife() {
  // On memory MP3 (ln 8172); offline (--lib) under its bare name.
  auto text = opt_.library ? opt_.library("GE1TOL/MP3") : std::nullopt;
  if (!text && opt_.library) text = opt_.library("GE1TOL");
  if (!text) return;
  try {
    life_ = ParseToolLife(*text);
  } catch (const FileError& e) {
    throw Error(Errc::kInvalidArgument, fmt::format("GE1TOL:{}:{}: error: [FILMS4 {:02}] {}: {}", e.line,
                                                    e.col, e.code, FilmsText(e.code), e.text));
  }
}

void BaltRun::SaveToolLife() {
  life_changed_ = false;
  if (life_) SaveFile("GE1TOL/MP3", life_->Format());
}

// A file saved into a memory: the station's store refuses it when the memory would hold more than 64,000
// characters (FILMS3 15 NO FREE SECTORS, ln 223, 9758-9759), and the run stops at the block that changed it
// with that message instead of going on with a change the memory did not keep.
void BaltRun::SaveFile(const std::string& lib, const std::string& text) {
  if (!opt_.save) return;
  try {
    opt_.save(lib, text);
  } catch (const cell::Error& e) {
    Fail(1, 0, e.what());
  }
}

// (RQU,tool,offset,Z..,K..) / (RQP,...) (ln 6820-6872, 7357-7412): increments added to the offset's length
// and diameter, in the characterized unit, unscaled; in effect from the next M06. With tool life management
// the tool's active alternative (status E / F) is requalified.
void BaltRun::CmdRqu(const Command& c) {
  CheckOperands(c, 3, 4);
  int tool = OperandInt(c.ops[0], 1, 9999);
  int offset = OperandInt(c.ops[1], 1, 9999);
  if (life_) {
    auto it = life_->tools.find(tool);
    if (it == life_->tools.end())
      Fail(c.ops[0].col, 82, fmt::format("tool {} is not in the tool life file", tool));
    std::set<int> seen{tool};
    while (it != life_->tools.end() && it->second.status != 'E' && it->second.status != 'F') {
      int alt = it->second.alt_tool;
      if (alt == 0 || seen.count(alt)) break;
      seen.insert(alt);
      auto next = life_->tools.find(alt);
      if (next == life_->tools.end()) break;
      if (next->second.status == 'E' || next->second.status == 'F') offset = it->second.alt_offset;
      it = next;
    }
  }
  if (tools_.entries().empty()) Fail(c.ops[1].col, 43, "no offsets file (FI1COR)");
  const tooltable::ToolEntry* found = FindOffset(offset);
  if (!found) Fail(c.ops[1].col, 44, fmt::format("offset {} is not in FI1COR", offset));
  tooltable::ToolEntry e = *found;
  const double unit = basic_metric_ ? 1.0 : kInch;
  std::uint32_t seen = 0;
  for (std::size_t k = 2; k < c.ops.size(); ++k) {
    const Operand& o = c.ops[k];
    if (o.text.empty()) Fail(o.col, 12, "Z.. or K.. expected");
    char letter = o.text[0];
    if (letter == 'K') {
      if (seen & 1u) Fail(o.col, 24, "K twice");
      seen |= 1u;
      std::string_view rest = o.text.substr(1);
      double v = rest.find_first_not_of(' ') == std::string_view::npos ? 0 : Eval(rest, o.col + 1);
      e.diameter += v * unit;
      continue;
    }
    AxisValue a = OperandAxis(o.text, o.col, true);
    if (a.axis != AxisOfLetter(e.length_axis)) {
      Fail(o.col, 91, fmt::format("offset {} has its length on {}, not {}", offset, e.length_axis, letter));
    }
    if (seen & 2u) Fail(o.col, 24, "the length twice");
    seen |= 2u;
    e.length += a.v * unit;
  }
  tools_.Upsert(e);
  ToolDataOp& d = Out<ToolDataOp>();
  d.entry = e;
}

// (TOF,n) (ln 6740-6762): tool n out of use (status A); the tool on the spindle of its family when tool life
// management is active. The station learns it from the file_op.
void BaltRun::CmdTof(const Command& c) {
  CheckOperands(c, 1, 1);
  int tool = OperandInt(c.ops[0], 1, 9999);
  if (life_) {
    auto it = life_->tools.find(tool);
    if (it == life_->tools.end())
      Fail(c.ops[0].col, 82, fmt::format("tool {} is not in the tool life file", tool));
    std::set<int> seen{tool};
    auto target = it;
    while (it != life_->tools.end()) {
      if (it->second.status == 'E' || it->second.status == 'F') {
        target = it;
        break;
      }
      int alt = it->second.alt_tool;
      if (alt == 0 || seen.count(alt)) break;
      seen.insert(alt);
      it = life_->tools.find(alt);
    }
    target->second.status = 'A';
    tool = target->first;
    life_changed_ = true;
    SaveToolLife();
  }
  FileOpOp& f = Out<FileOpOp>();
  f.what = "TOF";
  f.args = std::to_string(tool);
}

}  // namespace cell::interp::balt
