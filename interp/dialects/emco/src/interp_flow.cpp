// EMCO run life cycle and program structure (manual ln 780-1025, 1212-1331, 2179-2298, 5126-5138,
// 5368-5398): the main program from its header to M30, subroutines O22-O255 called with G25 and ended by
// M17, G27 jumps to a block number, what carries into the next program (Variables), the operator monitor
// parameters (params), the part counter and work presetting.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "cell/error/error.h"
#include "cell/interp/scan.h"
#include "interp_internal.h"

namespace cell::interp::emco {

namespace {

// A monitor value: a decimal integer (or a number for the lengths); throws with the parameter's name.
double Number(const std::string& key, const std::string& text) {
  std::string v(scan::Trim(text));
  try {
    std::size_t used = 0;
    double d = std::stod(v, &used);
    if (used != v.size() || !std::isfinite(d)) throw std::invalid_argument(v);
    return d;
  } catch (const std::exception&) {
    throw Error(Errc::kInvalidArgument, fmt::format("monitor parameter {}: '{}' is not a number", key, v));
  }
}

int Integer(const std::string& key, const std::string& text, int lo, int hi) {
  double d = Number(key, text);
  if (d != std::floor(d) || d < lo || d > hi) {
    throw Error(Errc::kInvalidArgument, fmt::format("monitor parameter {}: '{}' must be a whole number {}-{}",
                                                    key, scan::Trim(text), lo, hi));
  }
  return static_cast<int>(d);
}

// "PSO3.X" -> register 3, axis 'X'; 0 when the key is not a PSO name.
int PsoKey(const std::string& key, char* axis) {
  if (key.size() != 6 || key.compare(0, 3, "PSO") != 0 || key[4] != '.') return 0;
  if (key[3] < '1' || key[3] > '5' || (key[5] != 'X' && key[5] != 'Z')) return 0;
  *axis = key[5];
  return key[3] - '0';
}

// The modal codes a station keeps (ln 1304-1314: the STATUS screen's groups), with the codes each takes.
struct KeptCodes {
  const char* name;
  std::vector<int> codes;
};
const KeptCodes kKeptCodes[] = {{"G.1", {96, 97}},         {"G.2", {94, 95}}, {"G.3", {53, 54, 55}},
                                {"G.5", {56, 57, 58, 59}}, {"G.7", {70, 71}}, {"G.8", {40, 41, 42}},
                                {"M.0", {3, 4, 5, 19}},    {"M.1", {38, 39}}, {"M.3", {8, 9}},
                                {"M.5", {25, 26}},         {"M.6", {20, 21}}, {"M.7", {23, 24}},
                                {"M.8", {50, 51}},         {"M.9", {52, 53}}};

}  // namespace

// One rule for what a station keeps (Variables() reports exactly these; RestoreVariables takes only these).
std::string CheckKeptVariable(std::string_view name, double value) {
  if (!std::isfinite(value)) return fmt::format("{} = {} is not a number", name, value);
  const bool whole = value == std::floor(value);
  for (const auto& k : kKeptCodes) {
    if (name != k.name) continue;
    if (whole && std::find(k.codes.begin(), k.codes.end(), static_cast<int>(value)) != k.codes.end())
      return "";
    return fmt::format("{} = {} is not one of the group's codes {}", name, value, fmt::join(k.codes, " "));
  }
  auto range = [&](double lo, double hi, bool integer) -> std::string {
    if ((!integer || whole) && value >= lo && value <= hi) return "";
    return fmt::format("{} = {} is outside {}{}..{}", name, value, integer ? "the whole numbers " : "", lo,
                       hi);
  };
  if (name == "ACT.F" || name == "ACT.S" || name == "G92.S") return range(0, 9999, false);  // F4, S4
  if (name == "ACT.T") return range(0, 9999, true);                                         // T4: TTCC
  if (name == "D03") return range(0, 32767, true);  // the part counter wraps above 32767 (ln 5368-5378)
  char axis = 0;
  if (PsoKey(std::string(name), &axis) > 0) return range(-9999.999, 9999.999, false);  // +-43 (ln 1118)
  return fmt::format(
      "'{}' is not a variable an EMCO station keeps (G.1-G.8 and M.0-M.9 modal codes, ACT.F ACT.S ACT.T, "
      "G92.S, D03, PSO1.X..PSO5.Z)",
      name);
}

EmRun::EmRun(const RunOptions& o)
    : RunBase(o),
      corner_([this](Item&& it) { Route(std::move(it), 1); }),
      comp_([this](Item&& it) { Route(std::move(it), 2); }),
      tools_(o.tools) {
  ReadParams(o);
  mode_.metric = (mon_.o11 & 2) == 0;
  mode_.turret_logic = (mon_.o11 & 8) ? 51 : 50;
  mode_.door = (mon_.o11 & 16) ? 53 : 52;
  RestoreVariables(o.variables);
  if (t_ % 100 != 0) {
    Correction c = LookUp(tools_, t_ % 100);
    tool_off_ = {c.z, c.x};
  }
  frames_ = std::make_unique<Frames>(o.program ? o.program : ProgramText::FromString(o.program_text));
}

// Operator monitor parameters by their own names (chapter 6), and SKIP (the block skip key).
void EmRun::ReadParams(const RunOptions& o) {
  for (const auto& [k, v] : o.params) {
    std::string key = scan::Upper(scan::Trim(k));
    char axis = 0;
    if (key == "O11") {
      mon_.o11 = Integer(key, v, 0, 255);
    } else if (key == "O22") {
      mon_.o22 = Integer(key, v, 0, 255);
    } else if (key == "O40") {
      mon_.o40 = Integer(key, v, 0, 255);
    } else if (key == "S00") {
      mon_.s00 = Integer(key, v, 0, 32767);
    } else if (key == "S01") {
      mon_.s01 = Integer(key, v, 0, 20);
    } else if (key == "S02") {
      mon_.s02 = Integer(key, v, 0, 32767);
    } else if (key == "M08") {
      mon_.m08 = Number(key, v);
      if (mon_.m08 < 0 || mon_.m08 > 360)
        throw Error(Errc::kInvalidArgument, "monitor parameter M08: 0-360 degrees");
    } else if (key == "D02") {
      mon_.d02 = Integer(key, v, 0, 32767);
    } else if (key == "D03") {
      parts_ = Integer(key, v, 0, 32767);
    } else if (key == "R03") {
      mon_.limit_x_plus = Number(key, v);
    } else if (key == "R06") {
      mon_.limit_x_minus = Number(key, v);
    } else if (key == "R05") {
      mon_.limit_z_plus = Number(key, v);
    } else if (key == "R08") {
      mon_.limit_z_minus = Number(key, v);
    } else if (key == "SKIP") {
      mon_.skip = Integer(key, v, 0, 1) != 0;
    } else if (key == "MAX_IDLE_BLOCKS") {
      mon_.max_idle = std::max(1, Integer(key, v, 1, 1000000000));
    } else if (int r = PsoKey(key, &axis); r > 0) {
      double d = Number(key, v);
      (axis == 'X' ? pso_[r].y : pso_[r].x) = d;
    }
  }
}

// What carries from program to program (ln 1212-1292): the self-holding G codes of groups 1-8 and the M
// codes, F, S, T; what the station keeps: the PSO registers, the part counter, the G92 spindle limit.
void EmRun::RestoreVariables(const std::map<std::string, double>& vars) {
  auto get = [&](const char* name) -> std::optional<double> {
    auto it = vars.find(name);
    if (it == vars.end() || !CheckKeptVariable(name, it->second).empty()) return std::nullopt;
    return it->second;
  };
  auto code = [&](const char* name) -> std::optional<int> {
    if (auto v = get(name)) return static_cast<int>(*v);
    return std::nullopt;
  };
  if (auto v = code("G.1")) mode_.css = *v == 96;
  if (auto v = code("G.2")) mode_.per_min = *v == 94;
  if (auto v = code("G.3")) mode_.shift_a = *v - 53;
  if (auto v = code("G.5")) mode_.shift_b = *v == 56 ? 0 : *v - 54;
  if (auto v = code("G.7")) mode_.metric = *v == 71;
  if (auto v = code("M.0")) mode_.spindle = *v;
  if (auto v = code("M.1")) mode_.exact_stop = *v == 38;
  if (auto v = code("M.3")) mode_.coolant = *v == 8;
  if (auto v = code("M.5")) mode_.chuck = *v;
  if (auto v = code("M.6")) mode_.tailstock = *v;
  if (auto v = code("M.7")) mode_.catcher = *v;
  if (auto v = code("M.8")) mode_.turret_logic = *v;
  if (auto v = code("M.9")) mode_.door = *v;
  if (auto v = code("ACT.T")) t_ = *v;
  if (auto v = code("D03")) parts_ = *v;
  if (auto v = get("ACT.F")) feed_ = *v;
  if (auto v = get("ACT.S")) speed_ = *v;
  if (auto v = get("G92.S")) speed_limit_ = *v;
  for (const auto& [k, v] : vars) {
    char axis = 0;
    if (int r = PsoKey(k, &axis); r > 0 && CheckKeptVariable(k, v).empty())
      (axis == 'X' ? pso_[r].y : pso_[r].x) = v;
  }
}

std::map<std::string, double> EmRun::Variables() const {
  std::map<std::string, double> v;
  v["G.1"] = mode_.css ? 96 : 97;
  v["G.2"] = mode_.per_min ? 94 : 95;
  v["G.3"] = mode_.shift_a == 0 ? 53 : 53 + mode_.shift_a;
  v["G.5"] = mode_.shift_b == 0 ? 56 : 54 + mode_.shift_b;
  v["G.7"] = mode_.metric ? 71 : 70;
  v["G.8"] = mode_.comp;
  v["M.0"] = mode_.spindle;
  v["M.1"] = mode_.exact_stop ? 38 : 39;
  v["M.3"] = mode_.coolant ? 8 : 9;
  v["M.5"] = mode_.chuck;
  v["M.6"] = mode_.tailstock;
  v["M.7"] = mode_.catcher;
  v["M.8"] = mode_.turret_logic;
  v["M.9"] = mode_.door;
  v["ACT.F"] = feed_;
  v["ACT.S"] = speed_;
  v["ACT.T"] = t_;
  v["G92.S"] = speed_limit_;
  v["D03"] = parts_;
  for (int r = 1; r <= 5; ++r) {
    v[fmt::format("PSO{}.X", r)] = pso_[r].y;
    v[fmt::format("PSO{}.Z", r)] = pso_[r].x;
  }
  return v;
}

void EmRun::EmitUnits() {
  if (units_emitted_) return;
  units_emitted_ = true;
  UnitsOp& u = out_.Emplace<UnitsOp>(cur_line_);
  u.metric = mode_.metric;
  u.x_mode = XMode::kDiameter;
}

// Everything before the first "%" or "O" line is ignored (ln 5633); a text without any header runs from its
// first line.
void EmRun::FindMainProgram() {
  auto& f = frames_->top();
  TextPos p = f.at;
  while (p.pos < f.span.end) {
    TextPos line_start = p;
    Line l = ReadLine(f.span, p);
    if (!IsHeaderLine(l.text)) continue;
    Block b;
    ParseBlock(l.text, b);
    f.data.number = b.program;
    f.data.body_begin = p.pos;
    f.data.body_line = p.line;
    f.at = p;
    if (line_start.pos > (1u << 20)) f.span.text->Release(0, line_start.pos);
    cur_line_ = l.number;
    return;
  }
  f.data.body_begin = f.at.pos;  // no header: the whole text is the program
  f.data.body_line = f.at.line;
}

void EmRun::StepOnce() {
  Frames& fr = *frames_;
  try {
    if (!main_started_) {
      main_started_ = true;
      FindMainProgram();
      // Work presetting with no quantity: the start is refused (ALARM 785, ln 7168-7170).
      if ((mon_.o40 & 32) && mon_.d02 == 0) Alarm(785, 1, "monitor D02 = 0");
    }
    std::optional<Line> line = fr.NextLine();
    if (!line) {
      if (fr.depth() == 1) {
        FinishRun();
      } else {
        EndOfSubroutine();  // a subroutine without M17 ends as if it had one
      }
      return;
    }
    const auto& top = fr.top();
    cur_own_ = top.report_own;
    cur_line_ = top.report_own ? line->number : top.call_line;
    if (++idle_ > mon_.max_idle) {
      Fail(1, fmt::format("PROGRAM RAN {} BLOCKS WITHOUT MOTION (ENDLESS G27 LOOP?)", mon_.max_idle));
    }
    ExecLine(*line);
  } catch (const RunError& e) {
    Diagnostic d;
    d.program = opt_.program_name;
    d.line = cur_line_;
    d.col = cur_own_ ? e.col : 1;
    d.alarm = e.alarm;
    d.text = e.text;
    if (!cur_own_) d.text += fmt::format(" (in O{:04d})", fr.top().data.number);
    EmitUnits();
    EndWithError(std::move(d));
  }
}

void EmRun::ExecLine(const Line& line) {
  Frames& fr = *frames_;
  auto& f = fr.top();
  bool repeats = fr.depth() > 1 || f.jumped || parts_this_start_ > 0;
  const Block* b = repeats ? cache_.Find(f.span.text.get(), line.start) : nullptr;
  if (b == nullptr) {
    ParseBlock(line.text, scratch_);
    b = repeats ? &cache_.Put(f.span.text, line.start, Block(scratch_)) : &scratch_;
  }
  if (b->header) {
    // The next program of the file begins: this one has ended (its M30 or M17 missing).
    if (fr.depth() == 1) {
      FinishRun();
    } else {
      EndOfSubroutine();
    }
    return;
  }
  if (b->skip && mon_.skip) return;
  if (b->count == 0) {
    // A bare block number is a block without position words: not allowed after a chamfer/radius block
    // (ln 6839-6841, judgement 31). Blank and comment lines are not blocks (comments go on read-in, ln 5634).
    if (b->has_n && corner_next_) Alarm(382, 1, "a block without X(U)/Z(W) after the chamfer/radius block");
    return;
  }
  Execute(*b);
}

// No further block in the current program after the one just read (ALARM 340).
bool EmRun::LastBlock() const {
  const auto& f = frames_->top();
  TextPos p = f.at;
  while (p.pos < f.span.end) {
    Line l = ReadLine(f.span, p);
    if (IsHeaderLine(l.text)) return true;
    std::string_view t = scan::Trim(l.text);
    if (!t.empty() && t[0] != '(') return false;
  }
  return true;
}

namespace {

// The programs in `text` by number: where each one's blocks start (after its header) and end (at the next
// header). A text without any header is one program: `whole` gets it.
std::map<int, TextSpan> IndexPrograms(const std::shared_ptr<const ProgramText>& text,
                                      std::optional<TextSpan>* whole) {
  std::map<int, TextSpan> out;
  TextSpan all{text, 0, text->view().size(), 1};
  TextPos p;
  TextSpan* open = nullptr;
  bool any_header = false;
  ReleaseBehind release;  // memory stays flat however long the text (a mapped file)
  while (p.pos < all.end) {
    Line l = ReadLine(all, p);
    release.At(*text, p.pos);
    if (!IsHeaderLine(l.text)) continue;
    any_header = true;
    if (open) open->end = l.start;
    open = nullptr;
    Block b;
    try {
      ParseBlock(l.text, b);
    } catch (const RunError&) {
      continue;
    }
    if (b.program >= 0 && !out.count(b.program))
      open = &(out[b.program] = TextSpan{text, p.pos, all.end, p.line});
  }
  if (whole && !any_header) *whole = all;
  return out;
}

}  // namespace

// A subroutine's text: the program's own file first (several programs may follow each other, ln 5635), then
// the library (--lib, the station's store). Found programs are kept: a loop calls them again.
const EmRun::Subroutine* EmRun::FindSubroutine(int number) {
  if (!own_indexed_) {
    own_indexed_ = true;
    const auto& text = (*frames_)[0].span.text;
    for (auto& [n, span] : IndexPrograms(text, nullptr)) subs_[n] = {span, true};
  }
  if (auto it = subs_.find(number); it != subs_.end()) return &it->second;
  if (!opt_.library) return nullptr;
  for (const std::string& n :
       {fmt::format("O{:04d}", number), fmt::format("O{}", number), std::to_string(number)}) {
    if (std::optional<std::string> body = opt_.library(n)) {
      std::optional<TextSpan> whole;
      std::map<int, TextSpan> in = IndexPrograms(ProgramText::FromString(std::move(*body)), &whole);
      std::optional<TextSpan> span = in.count(number) ? std::optional<TextSpan>(in.at(number)) : whole;
      if (!span) continue;
      return &(subs_[number] = {*span, false});
    }
  }
  return nullptr;
}

// G25 L<number><runs> (ln 2179-2273): the subroutine O<number> runs <runs> times (1-99), then the program
// goes on after the G25 block. The subroutine is looked up in the program's own file first (several
// programs may follow each other, ln 5635), then in the library (--lib, the station's store).
void EmRun::CallSubroutine(const BlockWords& bw, int col) {
  if (!bw.l.set || bw.l.point || bw.l.raw < 100)
    Alarm(380, bw.l.set ? bw.l.col : col, "G25 needs L<number><2-digit runs>");
  int l = static_cast<int>(bw.l.raw);
  int number = l / 100, runs = l % 100;
  if (runs < 1) Alarm(380, bw.l.col, fmt::format("run count {} (1-99)", runs));
  Frames& fr = *frames_;
  for (const auto& f : fr) {
    if (f.data.number == number) Alarm(380, bw.l.col, fmt::format("O{:04d} is already active", number));
  }
  if (static_cast<int>(fr.depth()) - 1 >= kMaxNesting) Alarm(300, col);
  if (LastBlock()) Alarm(340, col);
  std::string name = "O0000";  // O{:04d}, by hand: this runs for every call (number <= 255, L <= 25599)
  for (int i = 4, n = number; i >= 1 && n > 0; --i, n /= 10)
    name[static_cast<size_t>(i)] = static_cast<char>('0' + n % 10);
  const Subroutine* sub = FindSubroutine(number);
  if (!sub) Alarm(310, bw.l.col, name);
  const TextSpan* span = &sub->span;
  bool own = sub->own;
  // Empty: no block in it (ALARM 310 "does not include any blocks").
  {
    TextPos p{span->begin, span->begin_line};
    bool any = false;
    while (p.pos < span->end && !any) {
      std::string_view t = scan::Trim(ReadLine(*span, p).text);
      any = !t.empty() && t[0] != '(';
    }
    if (!any) Alarm(310, bw.l.col, name + " has no blocks");
  }
  TextSpan body = *span;
  int call_line = cur_line_;
  bool caller_own = fr.top().report_own;
  auto& f = fr.Push(body, name);
  f.report_own = own && caller_own;
  f.call_line = call_line;
  f.data.number = number;
  f.data.runs_left = runs;
  f.data.body_begin = body.begin;
  f.data.body_line = body.begin_line;
}

// M17 (ln 4977-4981): back to the caller after the last run.
void EmRun::ReturnFromSubroutine(int col) {
  Frames& fr = *frames_;
  if (fr.depth() == 1) Alarm(330, col, "M17 in a program started as the main program");
  auto& f = fr.top();
  if (f.data.number < mon_.o22 || f.data.number > 255) {
    Alarm(630, col, fmt::format("O{:04d} is outside O{:04d}-O0255 (monitor O22)", f.data.number, mon_.o22));
  }
  EndOfSubroutine();
}

// The end of one run of a subroutine: the next run, or back to the caller.
void EmRun::EndOfSubroutine() {
  Frames& fr = *frames_;
  auto& f = fr.top();
  if (--f.data.runs_left > 0) {
    f.at = {f.data.body_begin, f.data.body_line};
    f.jumped = true;  // its blocks run again (parse cache)
    return;
  }
  fr.Pop();
}

// G27 L<block number> (ln 2286-2298): continue at block N<L> of the same program.
void EmRun::Jump(const BlockWords& bw, int col) {
  if (!bw.l.set || bw.l.point || bw.l.raw < 0 || bw.l.raw > 9999) {
    Alarm(380, bw.l.set ? bw.l.col : col, "G27 needs L<block number>");
  }
  if (LastBlock()) Alarm(340, col);
  int target = static_cast<int>(bw.l.raw);
  auto& f = frames_->top();
  std::optional<TextPos> at = f.data.blocks.Find(target);
  if (!at) {
    TextPos p{f.data.body_begin, f.data.body_line};
    while (p.pos < f.span.end) {
      TextPos start = p;
      Line l = ReadLine(f.span, p);
      if (IsHeaderLine(l.text)) break;
      std::string_view t = scan::Trim(l.text);
      if (!t.empty() && t[0] == '/') t = scan::Trim(t.substr(1));
      if (t.empty() || (t[0] != 'N' && t[0] != 'n')) continue;
      std::size_t i = 1;
      while (i < t.size() && (t[i] == ' ' || t[i] == '\t')) ++i;
      int n = 0, digits = 0;
      while (i < t.size() && scan::IsDigit(t[i]) && digits < 5) n = n * 10 + (t[i++] - '0'), ++digits;
      if (digits > 0 && n == target) {
        at = start;
        f.data.blocks.Remember(target, start);
        break;
      }
    }
  }
  if (!at) Alarm(380, bw.l.col, fmt::format("no block N{:04d} in this program", target));
  f.at = *at;
  f.jumped = true;
}

// M30 (ln 5126-5138): spindle and coolant off, parts catcher back, G40, the part counter; with work
// presetting (monitor O40 bit 5) the program starts again until D02 parts are done (ln 5380-5398).
void EmRun::EndOfProgram(int col) {
  if (frames_->depth() > 1) Alarm(330, col, "M30 in a subroutine");
  if (corner_next_) Alarm(382, col);
  if (comp_.on()) comp_.Finish();
  mode_.comp = 40;
  comp_request_ = 0;
  if (mode_.spindle != 5) {
    mode_.spindle = 5;
    SpindleOp(cur_line_);
  }
  Coolant(false);
  if (mode_.catcher == 24) {
    mode_.catcher = 23;
    Canon c;
    c.line = cur_line_;
    c.Set<AuxOp>().m = 23;
    EmitOther(std::move(c));
  }
  if (mon_.o40 & 16) parts_ = parts_ >= 32767 ? 0 : parts_ + 1;
  mode_.motion = Motion::kNone;  // group 0 does not carry over (ln 1216)
  if ((mon_.o40 & 32) && ++parts_this_start_ < mon_.d02) {
    auto& f = frames_->top();
    f.at = {f.data.body_begin, f.data.body_line};
    first_block_ = true;
    return;
  }
  Canon c;
  c.line = cur_line_;
  c.Set<EndOp>().m = 30;
  EmitOther(std::move(c));
  ended_ = true;
  EmitUnits();
  End();
}

// The end of the text (or the next program's header) without M30.
void EmRun::FinishRun() {
  if (corner_next_) Alarm(382, 1);
  if (comp_.on() || comp_request_ == 41 || comp_request_ == 42) Alarm(580, 1);
  EmitUnits();
  End();
}

}  // namespace cell::interp::emco
