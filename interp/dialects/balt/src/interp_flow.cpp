// Balt-System block stepping and control flow: the run's life cycle, '%' tape delimiters and %:NAME
// programs, slashed blocks (USB), labels and the branch commands, RPT/ERP (3 levels), EPP, CLS (2 levels),
// the end-of-file checks (manual §5.4-5.6, §5.17.2; FILMS4 31-37, 94).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::balt {

const char* FilmsText(int code) {
  switch (code) {
    case 3:
      return "OUT OF OPERATING LIMITS";
    case 5:
      return "AUTO RETURN TO PROFILE ILLEGAL";
    case 8:
      return "MEASUREMENT MISMATCH";
    case 9:
      return "PROBE NOT RELEASED";
    case 10:
      return "THREADING/TAPPING ERROR";
    case 11:
      return "SYNTAX ERROR";
    case 12:
      return "DATA MISSING";
    case 13:
      return "FORMAT ERROR";
    case 15:
      return "UNDEFINED SYMBOL";
    case 16:
      return "STRING TOO LONG";
    case 17:
      return "NON EXISTENT FUNCTION";
    case 18:
      return "INDEX OUT OF RANGE";
    case 19:
      return "PARAMETER OVERFLOW";
    case 20:
      return "FUNCTION UNDEFINED";
    case 21:
      return "ILLEGAL NUMBER OF OPERATORS";
    case 22:
      return "OPERAND NOT PROVIDED";
    case 23:
      return "ILLEGAL NUMBER OF OPERANDS";
    case 24:
      return "OPERAND NOT ALLOWED";
    case 25:
      return "BLOCK DOES NOT MATCH";
    case 26:
      return "ORIGINS FILE NOT FOUND";
    case 27:
      return "ORIGIN NOT EXISTENT";
    case 29:
      return "AXIS ORIGIN/OFFSET NOT DEFINED";
    case 30:
      return "PROBING PARAMETERS UNDEFINED";
    case 31:
      return "RPT NEST >3 OR ERP WITHOUT RPT";
    case 32:
      return "SUBROUTINE NEST >2";
    case 33:
      return "EPP NEST >1";
    case 34:
      return "UNDEFINED LABEL";
    case 35:
      return "RPT OR EPP CYCLE NOT CLOSED";
    case 36:
      return "WRONG DATA SET";
    case 37:
      return "DUPLICATED LABEL";
    case 43:
      return "OFFSET FILE NOT FOUND";
    case 44:
      return "OFFSET NON EXISTENT";
    case 48:
      return "S NOT DEFINED";
    case 49:
      return "T NOT DEFINED";
    case 51:
      return "UNKNOWN M OR H CODES";
    case 55:
      return "TOOL LIFE FILE NOT FOUND";
    case 56:
      return "NO ALTERNATIVE TOOL DECLARED";
    case 57:
      return "ALTERNATIVE TOOL NOT IN FILE";
    case 59:
      return "BLOCK NOT ALLOWED";
    case 63:
      return "COMPUTATION EXCEPTION";
    case 69:
      return "TOO MANY AXES DEFINED";
    case 71:
      return "ERROR IN RECORD FORMAT";
    case 72:
      return "TOOL MONITORING LOOP";
    case 77:
      return "UNDEFINED PROFILE";
    case 78:
      return "PROGRAM TOO COMPLEX TO CALCULATE";
    case 82:
      return "T NOT ALLOWED";
    case 83:
      return "RANDOM TOOL FILE NOT FOUND";
    case 84:
      return "VIOLATION OF PROTECTED AREA";
    case 86:
      return "FEEDRATE NOT PROGRAMMED";
    case 87:
      return "DPT PARAMETERS MISSING";
    case 88:
      return "UNDEFINED CANNED CYCLE";
    case 90:
      return "MIXED TOOL CHANGE";
    case 91:
      return "WRONG OFFSET PARAMETERS";
    case 94:
      return "INCOMPLETE PROGRAM";
    case 96:
      return "AXIS NOT BELONGING TO WORK PLANE";
    case 97:
      return "G CODE NOT ALLOWED";
    case 98:
      return "G CODE NOT ALLOWED DURING G95";
    case 103:
      return "FUNCTION NOT CONFIGURED";
    default:
      return "PROGRAM ERROR";
  }
}

namespace {

// A '%' (or "ER") tape start / end line, or a %:NAME program header.
bool TapeDelimiter(std::string_view t, bool* header) {
  *header = t.size() > 1 && t[0] == '%' && t[1] == ':';
  return (!t.empty() && t[0] == '%') || t == "ER";
}

std::string_view TrimBlanks(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// The label of a block ("/"NAME" ..."), without parsing it.
std::string_view LabelOf(std::string_view t) {
  t = TrimBlanks(t);
  if (!t.empty() && t[0] == '/') t = TrimBlanks(t.substr(1));
  if (t.size() < 3 || t[0] != '"') return {};
  std::size_t e = t.find('"', 1);
  if (e == std::string_view::npos || e == 1) return {};
  return t.substr(1, e - 1);
}

}  // namespace

void BaltRun::EmitUnitsOnce() {
  if (units_emitted_) return;
  units_emitted_ = true;
  out_.Emplace<UnitsOp>(cur_line_).metric = mode_.metric;
}

void BaltRun::StepOnce() {
  Frames& fr = *frames_;
  std::optional<Line> line = fr.NextLine();
  const auto& top = fr.top();
  cur_own_ = top.report_own;
  cur_line_ = !line ? cur_line_ : (top.report_own ? line->number : top.call_line);
  try {
    try {
      if (!line) {
        EndOfText();
      } else {
        if (++idle_ > max_idle_) {
          Fail(1, 0,
               fmt::format("PROGRAM RAN {} BLOCKS WITHOUT MOTION OR OUTPUT (ENDLESS LOOP?)", max_idle_));
        }
        ExecLine(*line);
      }
      ContourDrain();
    } catch (const ContourError& e) {
      ContourFail(
          e);  // a contour refusal no nearer handler placed: still this block's alarm, never an escape
    }
  } catch (const RunError& e) {
    Diagnostic d;
    d.program = opt_.program_name;
    d.line = cur_line_;
    d.col = cur_own_ ? e.col : 1;
    if (e.code > 0) d.alarm = fmt::format("FILMS4 {:02}", e.code);
    d.text = e.code > 0 ? std::string(FilmsText(e.code)) : std::string();
    if (!e.text.empty()) d.text = d.text.empty() ? e.text : d.text + ": " + e.text;
    if (!cur_own_ && line) {
      for (std::size_t i = fr.depth(); i-- > 0;) {
        if (!fr[i].report_own) {
          d.text += fmt::format(" (in {} line {})", fr[i].name, line->number);
          break;
        }
      }
    }
    // What the run produced before the error stays (DESIGN §4); what compensation had not settled (a corner
    // whose next element the error left unchecked) is not produced.
    for (auto& c : contour_.TakeChecked()) out_.push_back(std::move(c));
    contour_.Reset();
    staged_ = false;
    EndWithError(std::move(d));
  }
}

void BaltRun::ExecLine(const Line& line) {
  std::string_view text = line.text;
  if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
  std::string_view t = TrimBlanks(text);
  if (t.empty()) return;
  auto& f = frames_->top();
  bool header = false;
  if (TapeDelimiter(t, &header)) {
    // The first '%' starts the tape; a later one (or the next %:NAME program) ends this program.
    if (f.data.started) f.at.pos = f.span.end;
    f.data.started = true;
    return;
  }
  if (text.size() > kMaxBlockChars) Fail(128, 16, "a block has fewer than 128 characters");
  if (t[0] == ';') return;  // comment block
  f.data.started = true;
  const std::size_t li = frames_->depth() - 1;
  // Blocks that may run again: in subroutines and EPP ranges, inside an open repeat, after a branch.
  const bool repeats = li > 0 || f.jumped || !f.data.repeats.empty();
  if (!repeats) {
    const ParsedBlock pb = ParseBlock(text);         // made in place: no empty block made first and assigned
    if (pb.slash && !block_delete_enabled_) return;  // USB=0: a slashed block is a comment (ln 2333)
    ExecBlock(pb);
    return;
  }
  const ParsedBlock* pb = cache_.Find(f.span.text.get(), line.start);
  if (!pb) pb = &cache_.Put(f.span.text, line.start, ParseBlock(text));
  if (pb->slash && !block_delete_enabled_) return;
  ExecBlock(*pb);
}

void BaltRun::ExecBlock(const ParsedBlock& pb) {
  cur_sync_ = pb.sync == '#';
  // '#' (ln 2346, 7536-7586): the block is analysed only once the blocks before it have been executed.
  // Offline every block already is; on a station the environment waits for the servo.
  if (cur_sync_) [[unlikely]]
    env_->Synchronize();
  switch (pb.kind) {
    case BlockKind::kEmpty:
      break;
    case BlockKind::kAssign:
      Assign(pb.assign);
      break;
    case BlockKind::kExec:
      ExecSyvar(pb);
      break;
    case BlockKind::kIso: {
      for (const Command& c : pb.commands) {
        const CommandEntry* e = FindCommand(c.mnemonic);
        if (!e || !e->flow) ExecCommand(c, e);
      }
      ExecIso(pb);
      for (const Command& c : pb.commands) {
        const CommandEntry* e = FindCommand(c.mnemonic);
        if (e && e->flow) ExecCommand(c, e);
      }
      break;
    }
  }
  if (staged_) [[unlikely]]
    CommitStage();
  if (contour_.engaged()) [[unlikely]] {
    try {
      contour_.EndBlock();
    } catch (const ContourError& e) {
      ContourFail(e);
    }
  }
}

// K14 (ln 4195-4205): "@ SYVARn.mCH" runs the ISO text held in m characters from SYVARn as a block of its
// own line. Without a count (`@ SYVAR12.CH`, the manual's second example, which runs the 8 characters stored
// there) the text runs to the first byte never written, at most 32 characters (judgement call 40). An error
// in that text is reported at the @ operand, naming the text.
void BaltRun::ExecSyvar(const ParsedBlock& pb) {
  std::string_view e = pb.exec;
  if (e.rfind("SYVAR", 0) != 0) Fail(pb.exec_col, 24, "@ executes a SYVAR string");
  // The assignment reader reads the target's index and format; its views point into `target`, which must
  // outlive `ref`.
  const std::string target = std::string(e) + "=0";
  ParsedBlock ref = ParseBlock(target);
  if (ref.kind != BlockKind::kAssign || ref.assign.name != "SYVAR" || !ref.assign.has_index)
    Fail(pb.exec_col, 11, "@ SYVARn.mCH expected");
  const Assignment& a = ref.assign;
  const int index = static_cast<int>(a.gindex.num);
  std::string_view f = a.fmt.empty() ? std::string_view("CH") : a.fmt;
  std::string text;
  if (f == "CH") {
    if (index < 0 || static_cast<std::size_t>(index) >= syvar_.size())
      Fail(pb.exec_col, 18, fmt::format("SYVAR{} is outside the area", index));
    const std::size_t n = std::min<std::size_t>(32, syvar_.size() - static_cast<std::size_t>(index));
    text.assign(reinterpret_cast<const char*>(syvar_.data()) + index, n);
  } else {
    text = GlobalString("SYVAR", index, f, pb.exec_col);
  }
  if (std::size_t nul = text.find('\0'); nul != std::string::npos) text.resize(nul);
  while (!text.empty() && text.back() == ' ') text.pop_back();
  if (text.empty()) Fail(pb.exec_col, 22, fmt::format("SYVAR{} holds no text", index));
  exec_text_ = text;
  try {
    ParsedBlock inner = ParseBlock(exec_text_);
    if (inner.kind == BlockKind::kExec) Fail(1, 24, "@ inside @");
    ExecBlock(inner);
  } catch (RunError& err) {
    err.col = pb.exec_col;
    err.text = fmt::format("in \"{}\": {}", exec_text_, err.text);
    throw;
  }
}

void BaltRun::EndOfText() {
  Frames& fr = *frames_;
  if (fr.depth() > 1) {
    auto kind = fr.top().data.kind;
    if (kind == FrameData::kCall && !fr.top().data.repeats.empty()) {
      Fail(1, 35, fmt::format("RPT without ERP in {}", fr.top().name));
    }
    fr.Pop();
    return;
  }
  CheckEndOfFile(true);
  FinishProgram(0);
}

void BaltRun::CheckEndOfFile(bool main) {
  if (!frames_->top().data.repeats.empty()) Fail(1, 35, "RPT without ERP at the end of the program");
  if (!main) return;
  if (gtl_profile_) Fail(1, 94, "GTL profile still open (G21 without G20)");
  if (mode_.comp != 40) Fail(1, 94, fmt::format("cutter compensation G{} still active", mode_.comp));
  if (mode_.cycle != 80) Fail(1, 94, fmt::format("fixed cycle G{} still active (G80 missing)", mode_.cycle));
}

// M02 / M30 or the end of the text: what compensation holds is written, then the end.
void BaltRun::FinishProgram(int m) {
  try {
    if (contour_.engaged()) {
      CommitStage();
      contour_.Release();
    }
  } catch (const ContourError& e) {
    ContourFail(e);
  }
  ContourDrain();
  if (m != 0) Out<EndOp>().m = m;
  CommitStage();
  ContourDrain();
  EmitUnitsOnce();
  if (origins_changed_) SaveOrigins();
  if (life_changed_) SaveToolLife();
  End();
}

// Labels of a frame's text, scanned once (ln 6059: "NAME" before the block number).
std::optional<TextPos> BaltRun::FindLabel(std::string_view label, int col, bool after_block) {
  auto& f = frames_->top();
  // An EPP range looks labels up in the program it is part of.
  const TextSpan& span = f.span;
  std::size_t begin = f.data.kind == FrameData::kEpp ? f.data.file_begin : span.begin;
  std::size_t end = f.data.kind == FrameData::kEpp ? f.data.file_end : span.end;
  int begin_line = f.data.kind == FrameData::kEpp ? f.data.file_line : span.begin_line;
  LabelKey key{span.text.get(), begin};
  auto it = labels_.find(key);
  if (it == labels_.end()) {
    if (labels_.size() >= 64) labels_.clear();  // bounded: a few programs at a time
    LabelIndex idx;
    idx.pin = span.text;
    TextSpan all{span.text, begin, end, begin_line};
    TextPos p{begin, begin_line};
    while (p.pos < end) {
      TextPos here = p;
      Line l = ReadLine(all, p);
      std::string_view name = LabelOf(l.text);
      if (name.empty()) continue;
      auto [e, fresh] = idx.labels.try_emplace(std::string(name), LabelEntry{here, p, false});
      if (!fresh) e->second.duplicate = true;
    }
    it = labels_.emplace(key, std::move(idx)).first;
  }
  auto hit = it->second.labels.find(std::string(label));
  if (hit == it->second.labels.end()) Fail(col, 34, fmt::format("\"{}\"", label));
  if (hit->second.duplicate) Fail(col, 37, fmt::format("\"{}\"", label));
  return after_block ? hit->second.after : hit->second.at;
}

void BaltRun::Jump(std::string_view label, int col) {
  for (;;) {
    auto& f = frames_->top();
    TextPos to = *FindLabel(label, col, false);
    if (f.data.kind == FrameData::kEpp && (to.pos < f.span.begin || to.pos >= f.span.end)) {
      frames_->Pop();  // a branch out of an EPP range ends it
      continue;
    }
    f.at = to;
    f.jumped = true;
    return;
  }
}

int BaltRun::CallLevels() const {
  int n = 1;
  for (const auto& f : *frames_) {
    if (f.data.kind == FrameData::kCall) ++n;
  }
  return n;
}

namespace {

// The next "%:NAME" header line at or after `pos`, searched a MiB at a time: a mapped main file gives each
// searched window back (it faults in again when the run reaches it), so resident memory stays flat however
// long the program is.
std::size_t FindHeaderLine(const ProgramText& main, std::string_view header, std::size_t pos) {
  constexpr std::size_t kWindow = std::size_t{1} << 20;
  std::string_view text = main.view();
  while (pos < text.size()) {
    std::size_t end = std::min(text.size(), pos + kWindow);
    std::size_t hit = text.substr(0, std::min(text.size(), end + header.size())).find(header, pos);
    main.Release(pos, end);
    if (hit == std::string_view::npos || hit >= end) {
      pos = end;
      continue;
    }
    std::size_t after = hit + header.size();
    bool line_start = hit == 0 || text[hit - 1] == '\n';
    bool name_end = after >= text.size() || text[after] == '\n' || text[after] == '\r' || text[after] == ' ';
    if (line_start && name_end) return hit;
    pos = hit + 1;
  }
  return std::string_view::npos;
}

}  // namespace

// A program by name: a %:NAME program of the main file, then the library (--lib, the store).
std::optional<std::string> BaltRun::FindProgram(const std::string& name) {
  const ProgramText& main = *(*frames_)[0].span.text;
  std::string_view text = main.view();
  if (std::size_t pos = FindHeaderLine(main, "%:" + name, 0); pos != std::string_view::npos) {
    std::size_t body = text.find('\n', pos);
    body = body == std::string_view::npos ? text.size() : body + 1;
    std::size_t end = body;
    // To the next '%' line.
    while (end < text.size()) {
      std::size_t nl = text.find('\n', end);
      std::string_view l =
          TrimBlanks(text.substr(end, (nl == std::string_view::npos ? text.size() : nl) - end));
      if (!l.empty() && l[0] == '%') break;
      end = nl == std::string_view::npos ? text.size() : nl + 1;
    }
    return std::string(text.substr(body, end - body));
  }
  if (!opt_.library) return std::nullopt;
  return opt_.library(name);
}

void BaltRun::Call(std::string_view target, int col) {
  std::string name(target);
  std::string device;
  if (std::size_t slash = name.find('/'); slash != std::string::npos) {
    device = name.substr(slash + 1);
    name = name.substr(0, slash);
  }
  // ln 5954: up to 6 letters and digits, the first a letter, capitals; a device of 2-3 characters.
  bool ok = !name.empty() && name.size() <= 6 && IsUpper(name[0]) &&
            std::all_of(name.begin(), name.end(), [](char c) { return IsUpper(c) || IsDigit(c); });
  if (!ok)
    Fail(col, 24, fmt::format("'{}' is not a program name (1-6 capitals and digits, first a letter)", name));
  if (!device.empty() && (device.size() < 2 || device.size() > 3 || !IsUpper(device[0]))) {
    Fail(col, 36, fmt::format("'{}' is not a device", device));
  }
  if (CallLevels() >= kMaxCallLevels) Fail(col, 32, fmt::format("(CLS,{}) is a third call level", name));
  // The same text object for every call of a program: its parsed blocks and labels are found again.
  const std::string key = device.empty() || device == "MP1" ? name : name + "/" + device;
  std::shared_ptr<const ProgramText> body;
  if (auto it = programs_.find(key); it != programs_.end()) {
    body = it->second;
  } else {
    std::optional<std::string> text;
    // A device other than the default MP1 is asked for as NAME/DEV first (the station's memories).
    if (key != name && opt_.library) text = opt_.library(key);
    if (!text) text = FindProgram(name);
    if (!text) Fail(col, 36, fmt::format("program {} not found", name));
    body = ProgramText::FromString(std::move(*text));
    if (programs_.size() >= 32) programs_.clear();
    programs_[key] = body;
  }
  TextSpan span{body, 0, body->view().size(), 1};
  const int call_line = cur_line_;
  auto& f = frames_->Push(std::move(span), name);
  f.report_own = false;
  f.call_line = call_line;
  f.data.kind = FrameData::kCall;
}

void BaltRun::Epp(std::string_view from, std::string_view to, int col) {
  for (const auto& f : *frames_) {
    if (f.data.kind == FrameData::kEpp) Fail(col, 33, "EPP inside EPP");
  }
  TextPos a = *FindLabel(from, col, false);
  TextPos b_end = *FindLabel(to, col, true);
  if (b_end.pos <= a.pos) Fail(col, 34, fmt::format("\"{}\" comes before \"{}\"", to, from));
  auto& cur = frames_->top();
  TextSpan span{cur.span.text, a.pos, b_end.pos, a.line};
  FrameData data;
  data.kind = FrameData::kEpp;
  data.started = true;
  data.file_begin = cur.data.kind == FrameData::kEpp ? cur.data.file_begin : cur.span.begin;
  data.file_end = cur.data.kind == FrameData::kEpp ? cur.data.file_end : cur.span.end;
  data.file_line = cur.data.kind == FrameData::kEpp ? cur.data.file_line : cur.span.begin_line;
  const bool own = cur.report_own;
  const int call_line = cur.call_line;
  auto& f = frames_->Push(std::move(span), std::string(from));
  f.report_own = own;
  f.call_line = call_line;
  f.jumped = true;
  f.data = data;
}

// Whether the next block is a corner word (r.. or b.. alone): the move before it must be held for it.
bool BaltRun::NextIsCornerWord() {
  const auto& f = frames_->top();
  TextPos p = f.at;
  // Most next lines start with their first word: that character decides, without reading the line.
  if (p.pos < f.span.end) {
    const char c0 = f.span.text->view()[p.pos];
    switch (c0) {
      case ' ':
      case '\t':
      case '\r':
      case '\n':
      case ';':
      case '/':
      case '"':
      case 'N':
      case '#':
      case '&':
        break;
      default:
        return c0 == 'r' || c0 == 'b';
    }
  }
  for (int k = 0; k < 4 && p.pos < f.span.end; ++k) {
    Line l = ReadLine(f.span, p);
    std::string_view t = TrimBlanks(l.text);
    if (t.empty() || t[0] == ';') continue;
    if (t[0] == '/') t = TrimBlanks(t.substr(1));
    if (!t.empty() && t[0] == '"') {
      std::size_t e = t.find('"', 1);
      t = e == std::string_view::npos ? std::string_view() : TrimBlanks(t.substr(e + 1));
    }
    if (t.size() > 1 && t[0] == 'N' && IsDigit(t[1])) {
      std::size_t i = 1;
      while (i < t.size() && IsDigit(t[i])) ++i;
      t = TrimBlanks(t.substr(i));
    }
    if (!t.empty() && (t[0] == '#' || t[0] == '&')) t = TrimBlanks(t.substr(1));
    return !t.empty() && (t[0] == 'r' || t[0] == 'b');
  }
  return false;
}

}  // namespace cell::interp::balt
