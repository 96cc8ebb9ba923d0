// KT-APL tool data and fixture offsets (manual ch. 6, 7): TLD (through tld.h, the one TLD parser), ZTB,
// UAT suffix sets, the length and diameter compensation of the active tool, FXC/UFX fixture offset lines.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::ktapl {

std::string ToolName(double v) {
  double ip = std::trunc(v + (v >= 0 ? 1e-9 : -1e-9));
  int suffix = static_cast<int>(std::floor((v - ip) * 10 + 0.5));
  if (suffix <= 0) return fmt::format("{}", static_cast<long long>(ip));
  return fmt::format("{}.{}", static_cast<long long>(ip), suffix);
}

void KtRun::StTld(const Statement& st, BlockCtx&, bool) {
  TldContext ctx;
  ctx.metric = metric_;
  ctx.max_pallet = max_pallet_;
  ctx.col0 = st.col;
  ctx.param = [this](int n, int col) {
    try {
      return Param(n);
    } catch (const ExprError& e) {
      throw TldError{col, e.text};
    }
  };
  TldStatement t;
  try {
    // The body's columns: it starts after "(TLD," (statement columns are those of the control-out).
    ctx.col0 = st.col + 5;
    t = ParseTld(st.body, ctx);
  } catch (const TldError& e) {
    Fail(e.col, e.text);
  }
  ToolDataOp data;
  if (t.process) {
    // ln 4073: "Before a process compensation is entered either a primary or a suffix compensation must
    // be entered."
    if (!tools_.UpsertProcess(*t.process)) {
      Fail(st.col, "PROCESS COMPENSATION NEEDS A PRIMARY OR SUFFIX ENTRY FIRST");
    }
    data.pallet = t.process->pallet;
    data.entry.tool = t.process->tool;
    data.entry.length = t.process->length;
    data.entry.diameter = t.process->diameter;
  } else {
    tools_.Upsert(*t.entry);
    data.entry = *t.entry;
  }
  Out<ToolDataOp>() = std::move(data);
  ApplyTool();
}

void KtRun::StZtb(const Statement& st, BlockCtx&, bool) {
  if (!st.has_body) Fail(st.col, "ZTB NEEDS A COMMA AND T AND/OR H");
  for (const auto& f : SplitTopLevel(st.body, ',')) {
    std::string k = Upper(Trim(f));
    if (k == "T") {
      tools_.Clear();
      Out<ToolDataOp>().cleared = true;
    } else if (k == "H") {
      fixtures_ = {};
      active_h_ = 0;
    } else {
      Fail(st.col, "ZTB TABLES ARE T AND H");
    }
  }
}

void KtRun::StUat(const Statement& st, BlockCtx&, bool) {
  std::string v = Trim(st.body);
  if (v.size() != 1 || v[0] < '0' || v[0] > '7') Fail(st.col, "UAT SUFFIX MUST BE 0-7");
  // ln 6179: G40 must be modal to invoke a suffix compensation.
  if (mode_.cutter_comp != CutterComp::kOff) {
    Fail(st.col, "G40 must be modal in order to invoke a Suffix Compensation (UAT)");
  }
  uat_ = v[0] - '0';
  ApplyTool();
}

// M06 loads the selected tool number. Its data set is chosen here, with the wear the machine has measured so
// far applied: the first that is neither worn nor broken, so a worn-out or broken tool gives way to an
// alternate of the same number (ln 1593, 1738; part 2 Fig. 6.1), and a number whose data sets are all worn
// or broken stops the run. A number without data sets is used as programmed (the magazine finds it).
void KtRun::ChangeTool(int col) {
  for (const auto& w : env_->TakeToolWear()) tools_.Charge(w);
  bool exists = false;
  const tooltable::ToolEntry* e = tools_.Select(selected_tool_, &exists);
  if (!e && exists) {
    Fail(col,
         fmt::format("TOOL {} IS WORN OR BROKEN AND NO ALTERNATE IS LEFT IN THE TOOL TABLE", selected_tool_));
  }
  int sisters = 0;
  for (const auto& t : tools_.entries()) sisters += t.tool == selected_tool_ && t.socket > 0;
  ToolChangeOp& c = Out<ToolChangeOp>();
  c.tool = selected_tool_;
  // The socket goes to the machine only when it has a choice to make (alternates in other sockets).
  active_socket_ = e ? e->socket : 0;
  c.socket = sisters > 1 ? active_socket_ : 0;
  active_tool_ = selected_tool_;
  uat_ = 0;
  ApplyTool();
}

// G38 (ln 1583-1593, 7034-7124): the machine checks the spindle tool at the detection post. A broken one is
// set broken in the tool table, "TOOL BROKEN" shows and the machine goes to CYCLE STOP (the operator
// inspects the tool and presses cycle start); the next M06 of its number chooses an alternate.
void KtRun::CheckTool(const Word* s) {
  int flutes = 0;
  if (s) {
    if (s->v < 0 || s->v > 99 || s->v != std::floor(s->v))
      Fail(s->col, "G38 S (NUMBER OF FLUTES) OUT OF RANGE 0-99");
    flutes = static_cast<int>(s->v);
  }
  const bool whole = env_->CheckTool(flutes);
  ProbeOp& c = Out<ProbeOp>();
  c.g = 38;
  c.to.pos = pos_;
  c.to.used = used_;
  c.result = whole ? ProbeOutcome::kToolOk : ProbeOutcome::kToolBroken;
  if (whole) return;
  if (!active_tool_.empty()) tools_.Charge(tooltable::ToolWear{active_tool_, active_socket_, 0, true});
  Out<MessageOp>().text = "TOOL BROKEN";
  StopOp& stop = Out<StopOp>();
  stop.m = 0;
  stop.why = "TOOL BROKEN";
}

void KtRun::ApplyTool() {
  tool_len_ = tool_dia_ = 0;
  if (active_tool_.empty()) return;
  std::string key = active_tool_;
  if (uat_ > 0) key += "." + std::to_string(uat_);
  // A process compensation for the pallet on the table is added to the data set (ln 4093-4095).
  tooltable::ToolTable::Compensation c;
  if (tools_.Effective(key, pallet_, &c, active_socket_)) {
    tool_len_ = c.length;
    tool_dia_ = c.diameter;
  }
}

std::string FixtureKey(int h, int axis) {
  return "H" + std::to_string(h) + "." + (axis < 0 ? 'I' : LetterOfAxis(axis));
}

std::optional<FixtureField> ParseFixtureKey(std::string_view key) {
  if (key.size() < 4 || key[0] != 'H' || key[key.size() - 2] != '.') return std::nullopt;
  std::string_view digits = key.substr(1, key.size() - 3);
  if (digits.empty() || digits.size() > 2 || digits[0] == '0') return std::nullopt;
  int h = 0;
  for (char c : digits) {
    if (c < '0' || c > '9') return std::nullopt;
    h = h * 10 + (c - '0');
  }
  if (h < 1 || h > kFixtureLines) return std::nullopt;
  const char letter = key.back();
  if (letter == 'I') return FixtureField{h, -1};
  for (int a : {kX, kY, kZ, kA, kB, kC})
    if (LetterOfAxis(a) == letter) return FixtureField{h, a};
  return std::nullopt;
}

void KtRun::StFxc(const Statement& st, BlockCtx&, bool) {
  const bool ufx = st.mnemonic == "UFX";
  std::string b = Upper(st.body);
  b.erase(std::remove(b.begin(), b.end(), ' '), b.end());
  b.erase(std::remove(b.begin(), b.end(), ','), b.end());
  ParsedBlock pb;
  try {
    ParseBlock(b, true, pb);
  } catch (RunError& e) {
    e.col = st.col;
    throw;
  }
  int h = -1;
  auto value = [&](const RawWord& w) -> double {
    if (w.kind == WordKind::kNumber) return ScaleLiteral(w.letter, w.num, metric_, false, false);
    double v;
    try {
      v = Param(w.param);
    } catch (const ExprError& e) {
      Fail(st.col, e.text);
    }
    return w.kind == WordKind::kNegParam ? -v : v;
  };
  for (const auto& w : pb.words) {
    double v = value(w);
    if (w.letter == 'H') {
      h = static_cast<int>(std::floor(v + 0.5));
      if (h < 1 || h > 32) Fail(st.col, "Error FXC 'H' codes range from 1..32");
      fixtures_[h].set = true;
      continue;
    }
    if (h < 0) Fail(st.col, "FXC/UFX NEEDS H FIRST");
    if (w.letter == 'I') {
      fixtures_[h].has_i = true;
      fixtures_[h].i = v;
      continue;
    }
    int a = AxisOfLetter(w.letter);
    if (a < 0) Fail(st.col, "Input Source Error");
    double mm = IsRotaryAxis(a) ? v : ToMm(v);
    if (ufx) {
      // offset = actual position - the given (programmed) position
      mm = pos_[a] - g98_[a] - (a == kZ ? tool_len_ : 0) - mm;
    }
    if (!IsRotaryAxis(a) && std::fabs(mm) > 42949.672) Fail(st.col, "Error axis fixture offset out of range");
    fixtures_[h].v[a] = mm;
  }
}

}  // namespace cell::interp::ktapl
