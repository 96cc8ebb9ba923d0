// Okuma block stepping and control flow: the run's life cycle, tape framing ('%', '$' headers and
// continuation lines, 158-character blocks), program names and sequence names, GOTO / IF (seed ln 7476-7539),
// CALL / RTS (ln 7962-8042), MODIN / MODOUT (ln 8048-8073), the program's end, and the stages between the
// executor and the command queue.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "cell/interp/scan.h"
#include "interp_internal.h"

namespace cell::interp::okuma {
namespace {

constexpr int kMaxDepth = 16;    // subprogram nesting (the manual sets no number; guards runaway recursion)
constexpr size_t kMaxModin = 8;  // ln 8058
constexpr size_t kMaxBlockChars = 158;  // ln 547

std::string_view TrimBlanks(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

bool StartsWithLabel(std::string_view line, const std::string& label) {
  std::string_view s = TrimBlanks(line);
  if (!s.empty() && s[0] == '/') s = TrimBlanks(s.substr(1));
  if (s.size() < label.size()) return false;
  for (size_t i = 0; i < label.size(); ++i) {
    char c = s[i];
    if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
    if (c != label[i]) return false;
  }
  return s.size() == label.size() || s[label.size()] == ' ' || s[label.size()] == '\t' ||
         s[label.size()] == '(';
}

// Whether the line at `at` may be a '$' continuation: its first character after blanks is '$'. A cheap
// look ahead, so that most blocks are not followed by a second split of the next line.
bool NextStartsContinuation(const TextSpan& span, const TextPos& at) {
  std::string_view text = span.text->view();
  for (std::size_t i = at.pos; i < span.end; ++i) {
    if (text[i] != ' ' && text[i] != '\t') return text[i] == '$';
  }
  return false;
}

bool IsContinuation(std::string_view line) {
  std::string_view s = TrimBlanks(line);
  return !s.empty() && s[0] == '$';
}

double ParamNumber(const std::string& v, double def) {
  try {
    double d = std::stod(v);
    return std::isfinite(d) ? d : def;
  } catch (...) {
    return def;
  }
}

}  // namespace

OkRun::OkRun(const RunOptions& o) : RunBase(o) {
  std::string select;
  for (const auto& [k, v] : o.params) {
    std::string key = scan::Upper(scan::Trim(k));
    std::string val = scan::Upper(scan::Trim(v));
    if (key == "UNIT_SYSTEM" || key == "UNIT") {
      if (val == "1UM" || val == "1MICRON" || val == "0.001MM") {
        units_ = UnitSystem::k1um;
      } else if (val == "10UM" || val == "0.01MM") {
        units_ = UnitSystem::k10um;
      } else if (val == "INCH" || val == "1INCH") {
        units_ = UnitSystem::kInch;
      } else if (val == "0.0001INCH" || val == "1/10000INCH") {
        units_ = UnitSystem::k10000thInch;
      } else {
        units_ = UnitSystem::k1mm;
      }
      inch_ = units_ == UnitSystem::kInch || units_ == UnitSystem::k10000thInch;
    } else if (key == "BLOCK_DELETE") {
      block_delete_ = ParamNumber(val, 0) != 0;
    } else if (key == "OPTIONAL_STOP") {
      optional_stop_ = ParamNumber(val, 0) != 0;
    } else if (key == "PROGRAM") {
      select = val;
    } else if (key == "ZERO_OFFSET_X") {
      zero_offset_[kX] = ParamNumber(val, 0);
    } else if (key == "ZERO_OFFSET_Z") {
      zero_offset_[kZ] = ParamNumber(val, 0);
    } else if (key == "ZERO_OFFSET_C") {
      zero_offset_[kC] = ParamNumber(val, 0);
    } else if (key == "ARC_TOLERANCE") {
      arc_tolerance_ = std::max(0.0, ParamNumber(val, 0.01));
    } else if (key == "CONTOUR_TOLERANCE") {
      // The chord error of G101-G103 paths; kept within 0.1 um - 1 mm (fewer than 0.1 um would only multiply
      // the pieces, more than 1 mm is no contour).
      const double t = ParamNumber(val, 0.001);
      contour_tol_ = std::isfinite(t) ? std::clamp(t, 0.0001, 1.0) : 0.001;
    } else if (key == "C_CENTER_OVERRIDE") {
      const double pct = ParamNumber(val, 100);
      centre_override_ = std::isfinite(pct) ? std::clamp(pct, 1.0, 1000.0) / 100 : 1;  // 1-1000 % (ln 6684)
    } else if (key == "SIDE_CONTOUR_PLANE") {
      side_inner_ = scan::Upper(scan::Trim(val)) == "INNER";  // MULTIPLE MACHINING Z-CE coordinate (ln 6719)
    } else if (key == "PECK_RETRACT") {
      peck_retract_ = std::max(0.0, ParamNumber(val, 0.5));
    } else if (key == "MULTI_PECK_RETRACT") {
      multi_peck_ = std::max(0.0, ParamNumber(val, 0.5));
    } else if (key == "MULTI_RETURN_POINT") {
      multi_return_start_ = ParamNumber(val, 0) != 0;
    } else if (key == "G184_TAPPING_MODE") {
      g184_sync_ = ParamNumber(val, 0) != 0;  // MULTIPLE MACHINING "G184 tapping mode" (ln 4539)
    } else if (key == "LAP_RELIEF") {
      lap_relief_ = std::max(0.0, ParamNumber(val, 0.1));
    } else if (key == "LAP_CLEARANCE") {
      lap_clearance_ = std::max(0.0, ParamNumber(val, 2.0));
    } else if (key == "M75_PATTERN") {
      m75_pattern_ = ParamNumber(val, 3) == 4 ? 4 : 3;
    } else if (key == "MAX_IDLE_BLOCKS") {
      max_idle_ = std::max(1L, static_cast<long>(ParamNumber(val, 1000000)));
    } else if (key == "VCHKL" || key == "VCHKD" || key == "VCHKZ" || key == "VCHKX" || key == "VTSL" ||
               key == "VTSDA" || key == "VTSDB" || key == "VWKR") {
      system_[{PackName(key), 0}] = ParamNumber(val, 0);  // barrier data of the parameter screen (ln 9046)
    } else if (key.rfind("RS232C", 0) == 0) {
      read_area_ = std::string(scan::Trim(v));  // READ data of the virtual channel (offline)
    }
  }
  for (const auto& [k, v] : o.variables) {
    std::string key = scan::Upper(scan::Trim(k));
    if (key.size() < 2 || key[0] != 'V' || !scan::AllDigits(key.substr(1)) || key.size() > 4) continue;
    int n = std::stoi(key.substr(1));
    if (n >= 1 && n <= 200 && std::isfinite(v)) {
      common_[static_cast<size_t>(n)] = v;
      common_set_.set(static_cast<size_t>(n));
    }
  }
  tools_.Load(o.tools);
  auto text = o.program ? o.program : ProgramText::FromString(o.program_text);
  frames_ = std::make_unique<Frames>(text);
  frames_->top().span.cr_ends_line = true;
  frames_->top().data.kind = FrameData::kMain;
  frames_->top().data.modin_limit = -1;
  if (!select.empty()) {
    // A main program of the file chosen by name (PSELECT's pm; ln 8824-8835).
    auto p = ProgramIn(text, select, true);
    if (!p) {
      Diagnostic d;
      d.program = opt_.program_name;
      d.line = 1;
      d.col = 1;
      d.text = fmt::format("program {} is not in {}", select, opt_.program_name);
      EndWithError(std::move(d));
      return;
    }
    auto& f = frames_->top();
    f.at = {p->begin, p->line};
    f.data.program_begin = p->begin;
    f.data.program_begin_line = p->line;
    f.data.tape_started = true;
    main_started_ = true;
  }
}

std::map<std::string, double> OkRun::Variables() const {
  std::map<std::string, double> out;
  for (size_t n = 1; n <= 200; ++n) {
    if (common_set_.test(n)) out["V" + std::to_string(n)] = common_[n];
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------------
// Output and the stages

bool OkRun::StagesEngaged() const {
  return staged_ || force_stage_ || corner_.engaged() || comp_.engaged() || lap_.active;
}

void OkRun::EmitUnitsOnce() {
  if (units_emitted_) return;
  units_emitted_ = true;
  UnitsOp& u = out_.Emplace<UnitsOp>(cur_line_);
  u.metric = !inch_;
  u.x_mode = XMode::kDiameter;
}

void OkRun::Commit() {
  staged_ = false;
  Sink(std::move(stage_));
}

void OkRun::Sink(Staged&& s) {
  corner_.Take(std::move(s));
  auto& from_corner = corner_.Ready();
  for (auto& r : from_corner) {
    comp_.Take(std::move(r));
    auto& from_comp = comp_.Ready();
    for (auto& q : from_comp) {
      if (q.kind != Staged::kOp) continue;
      if (lap_.active) {
        LapCapture(q);
      } else {
        out_.push_back(std::move(q.c));
      }
    }
    from_comp.clear();
  }
  from_corner.clear();
}

void OkRun::EndBlockStages(bool xz) {
  if (!StagesEngaged()) return;
  if (staged_) Commit();
  Staged m;
  m.kind = Staged::kBlockEnd;
  m.xz = xz;
  Sink(std::move(m));
}

void OkRun::Finish() {
  if (ended_) return;
  ended_ = true;
  if (staged_) Commit();
  corner_.Finish();
  Staged none;
  none.kind = Staged::kBlockEnd;
  Sink(std::move(none));
  comp_.Finish();
  for (auto& q : comp_.Ready()) {
    if (q.kind == Staged::kOp) out_.push_back(std::move(q.c));
  }
  comp_.Ready().clear();
  EmitUnitsOnce();
  End();
}

// ---------------------------------------------------------------------------------------------------------
// Stepping

void OkRun::ReportError(const RunError& e, int first_line) {
  Diagnostic d;
  d.program = opt_.program_name;
  d.alarm = e.alarm;
  d.text = e.text;
  if (cur_own_) {
    if (parsing_) {
      parsing_->Locate(e.col, first_line, &d.line, &d.col);
    } else {
      d.line = first_line;
      d.col = e.col;
    }
  } else {
    d.line = cur_line_;
    d.col = 1;
    for (size_t i = frames_->depth(); i-- > 0;) {
      const auto& f = (*frames_)[i];
      if (!f.report_own && !f.name.empty()) {
        d.text = fmt::format("{} (in {} line {})", e.text, f.name, first_line);
        break;
      }
    }
  }
  EndWithError(std::move(d));
}

void OkRun::StepOnce() {
  int first_line = cur_line_;
  parsing_ = nullptr;
  try {
    if (++idle_ > max_idle_) {
      Fail(1, fmt::format("the program ran {} blocks without motion or output (endless loop?)", max_idle_));
    }
    const Block* b = ReadBlock(&first_line);
    if (!b) {
      if (frames_->depth() == 1) {
        Finish();
        return;
      }
      Fail(1, fmt::format("subprogram {} ends without RTS", frames_->top().name));
    }
    ExecBlock(*b);
  } catch (const RunError& e) {
    ReportError(e, first_line);
  }
  // The barrier check sees every move before it goes out, those queued before an error too (ln 9081).
  if (CheckBarriers() && barrier_off_ != 0) BarrierOffAfterBlock();  // M20/M24 of the block
  cur_block_ = nullptr;
}

const Block* OkRun::ReadBlock(int* first_line) {
  Frames& fr = *frames_;
  for (;;) {
    std::optional<Line> line = fr.NextLine();
    if (!line) return nullptr;
    auto& top = fr.top();
    std::string_view t = line->text;
    if (!t.empty() && t.back() == '\r') t.remove_suffix(1);
    std::string_view s = TrimBlanks(t);
    cur_own_ = top.report_own;
    cur_line_ = top.report_own ? line->number : top.call_line;
    *first_line = line->number;
    if (s.empty()) continue;
    if (s == "%") {  // the tape's start (or end) character
      top.data.tape_started = true;
      continue;
    }
    if (s[0] == '$' && !top.data.tape_started) continue;  // "$NAME.MIN" tape header before the tape starts
    if (t.size() > kMaxBlockChars) {
      Fail(static_cast<int>(kMaxBlockChars) + 1,
           fmt::format("block longer than {} characters", kMaxBlockChars));
    }
    if (s[0] == '$') Fail(1, "'$' continuation line without a block before it");
    // Continuation lines ('$' at their start) belong to this block (ln 5158-5167); before the tape starts,
    // a '$' line after a comment is the tape header.
    const bool comment_only = s.front() == '(' && s.back() == ')' && s.find(')') == s.size() - 1;
    if (!comment_only) top.data.tape_started = true;
    const size_t start = line->start;
    bool continued = false;
    for (;;) {
      if (comment_only && !top.data.tape_started) break;
      if (!NextStartsContinuation(top.span, top.at)) break;  // the common case: no second read of the line
      TextPos save = top.at;
      std::optional<Line> next = fr.NextLine();
      if (!next || !IsContinuation(next->text)) {
        top.at = save;
        break;
      }
      std::string_view nt = next->text;
      if (!nt.empty() && nt.back() == '\r') nt.remove_suffix(1);
      if (nt.size() > kMaxBlockChars) {
        cur_line_ = top.report_own ? next->number : top.call_line;
        *first_line = next->number;
        Fail(static_cast<int>(kMaxBlockChars) + 1,
             fmt::format("block longer than {} characters", kMaxBlockChars));
      }
      if (!continued) {
        joined_.assign(t);
        segments_.clear();
        segments_.push_back({0, line->number, 1});
        continued = true;
      }
      size_t dollar = nt.find('$');
      joined_ += ' ';
      segments_.push_back({joined_.size(), next->number, static_cast<int>(dollar) + 2});
      joined_.append(nt.substr(dollar + 1));
    }
    const bool repeats = fr.depth() > 1 || top.jumped;
    if (repeats) {
      if (const Block* cached = cache_.Find(top.span.text.get(), start)) {
        parsing_ = cached;
        return cached;
      }
    }
    fresh_.Clear();
    if (continued) fresh_.segments = segments_;
    parsing_ = &fresh_;
    ParseBlock(continued ? std::string_view(joined_) : t, fresh_);
    if (repeats) {
      const Block& put = cache_.Put(top.span.text, start, std::move(fresh_));
      parsing_ = &put;
      return &put;
    }
    return &fresh_;
  }
}

bool OkRun::ProgramEnds(const Block& b) {
  (void)b;
  auto& top = frames_->top();
  if (frames_->depth() == 1) {
    if (!main_started_) {
      main_started_ = true;  // the main program's own name
      top.data.program_begin = top.at.pos;
      top.data.program_begin_line = top.at.line;
      return false;
    }
    return true;  // the next program of the file begins: this one has ended
  }
  Fail(b.program_col, fmt::format("subprogram {} ends without RTS (program {} begins)", top.name, b.program));
}

void OkRun::ExecBlock(const Block& b) {
  cur_block_ = &b;
  if (b.deleted && block_delete_) return;
  switch (b.stmt) {
    case Stmt::kProgramName:
      if (ProgramEnds(b)) Finish();
      return;
    case Stmt::kSchedule:
      Fail(b.stmt_col, fmt::format("{} is a schedule program statement: schedule programs (.SDF) run on the "
                                   "cell's scheduler (cellctl schedule run)",
                                   b.stmt_word));
    case Stmt::kNone:
      ExecNc(b);
      return;
    default:
      ExecStatement(b);
      return;
  }
}

void OkRun::ExecStatement(const Block& b) {
  switch (b.stmt) {
    case Stmt::kGoto:
      EndBlockStages(false);
      Jump(b.label, b.label_col);
      return;
    case Stmt::kIf: {
      bool yes;
      if (b.cond >= 0) {
        yes = Evaluate(b.pool, b.cond, *this).v != 0;
      } else {
        uint64_t n = PackName(b.defined);
        yes = std::any_of(locals_.begin(), locals_.end(), [n](const LocalVar& l) { return l.name == n; });
      }
      EndBlockStages(false);
      if (yes) Jump(b.label, b.label_col);
      return;
    }
    case Stmt::kCall: {
      auto p = FindProgram(b.program);
      if (!p) Fail(b.program_col, fmt::format("subprogram {} not found", b.program));
      EndBlockStages(false);
      CallProgram(*p, b.program, FrameData::kSub, frames_->top().data.modin_limit, &b);
      frames_->top().data.runs_left = b.repeat - 1;
      frames_->top().data.first = frames_->top().at;
      return;
    }
    case Stmt::kRts:
      EndBlockStages(false);
      Return(b.stmt_col);
      return;
    case Stmt::kModin: {
      if (modins_.size() >= kMaxModin) Fail(b.stmt_col, "MODIN nested more than 8 levels");
      auto p = FindProgram(b.program);
      if (!p) Fail(b.program_col, fmt::format("subprogram {} not found", b.program));
      for (const Item& it : b.items) {
        if (it.assign) Assignment(b.assigns[it.i], b, true);
      }
      modins_.push_back({b.program, *p});
      EndBlockStages(false);
      return;
    }
    case Stmt::kModout:
      if (modins_.empty()) Fail(b.stmt_col, "MODOUT without MODIN");
      modins_.pop_back();
      EndBlockStages(false);
      return;
    case Stmt::kRead:
    case Stmt::kWrite:
    case Stmt::kGet:
    case Stmt::kPut:
      ExecIo(b);
      EndBlockStages(false);
      return;
    default:
      return;
  }
}

// ---------------------------------------------------------------------------------------------------------
// Programs and sequence names

std::optional<ProgramRef> OkRun::ProgramIn(const std::shared_ptr<const ProgramText>& text,
                                           const std::string& name, bool own) {
  // A program's first call scans the whole file: its lines are split as ReadLine splits them (a '\n', a lone
  // '\r' or "\r\n" ends one), with one memchr per line for the '\n'; where the next '\r' is, is kept from one
  // search of up to 4 KB ahead (a file has none, or one per line), not looked for in every line. Not further
  // ahead: a long main program's pages go back as the scan passes them.
  const std::string_view v = text->view();
  const char* d = v.data();
  const size_t end = v.size();
  constexpr size_t kNoCr = std::string_view::npos;
  size_t cr_lim = 0, cr_pos = kNoCr;  // searched up to cr_lim: its first '\r' at cr_pos (kNoCr: none)
  auto line_end = [&](size_t from) {  // the first '\n' or '\r' at or after from, or end
    const void* n = std::memchr(d + from, '\n', end - from);
    const size_t nl = n ? static_cast<size_t>(static_cast<const char*>(n) - d) : end;
    const bool known = cr_pos != kNoCr ? cr_pos >= from : cr_lim >= nl;
    if (!known) {
      cr_lim = std::min(end, std::max(nl, from + 4096));
      const void* r = std::memchr(d + from, '\r', cr_lim - from);
      cr_pos = r ? static_cast<size_t>(static_cast<const char*>(r) - d) : kNoCr;
    }
    return cr_pos != kNoCr && cr_pos < nl ? cr_pos : nl;
  };
  size_t pos = 0;
  int line = 1;
  std::optional<ProgramRef> found;
  ReleaseBehind release;
  while (pos < end && !found) {
    const size_t eol = line_end(pos);
    const size_t next =
        eol >= end ? end : eol + (d[eol] == '\r' && eol + 1 < end && d[eol + 1] == '\n' ? 2 : 1);
    const std::string_view l = v.substr(pos, eol - pos);
    pos = next;
    ++line;
    release.At(*text, pos);
    // Only a line whose first non-blank is O can name a program: tested before trimming.
    size_t k = 0;
    while (k < l.size() && (l[k] == ' ' || l[k] == '\t')) ++k;
    if (k == l.size() || (l[k] != 'O' && l[k] != 'o')) continue;
    if (ProgramNameOf(TrimBlanks(l)) == name) found = ProgramRef{text, pos, line, own};
  }
  release.Done(*text, pos);
  return found;
}

std::optional<ProgramRef> OkRun::FindProgram(const std::string& name) {
  auto it = programs_.find(name);
  if (it != programs_.end()) return it->second;
  std::optional<ProgramRef> found;
  // The file being run, then the main program's file (programs in the same file are found by name, ln 8846).
  const auto& here = frames_->top().span.text;
  const auto& main = (*frames_)[0].span.text;
  found = ProgramIn(here, name, here == main);
  if (!found && here != main) found = ProgramIn(main, name, true);
  auto load = [&](const std::string& file) -> std::shared_ptr<const ProgramText> {
    auto f = files_.find(file);
    if (f != files_.end()) return f->second;
    if (!opt_.library) return nullptr;
    auto text = opt_.library(file);
    if (!text) return nullptr;
    auto t = ProgramText::FromString(std::move(*text));
    files_[file] = t;
    return t;
  };
  // The subprogram file PSELECT names (fs; the station passes it as SUB_FILE), then the program by its name
  // in the library (offline --lib DIR: DIR/O1234, DIR/O1234.SUB, ...; the station: its namespace, then HOST).
  if (!found) {
    auto sf = opt_.params.find("SUB_FILE");
    if (sf != opt_.params.end()) {
      for (std::string_view part : scan::Lines(sf->second)) {
        for (size_t b = 0; b < part.size();) {
          size_t c = part.find(',', b);
          std::string file(scan::Trim(part.substr(b, c == std::string_view::npos ? part.npos : c - b)));
          b = c == std::string_view::npos ? part.size() : c + 1;
          if (file.empty()) continue;
          if (auto t = load(file)) found = ProgramIn(t, name, false);
          if (found) break;
        }
      }
    }
  }
  if (!found) {
    if (auto t = load(name)) {
      found = ProgramIn(t, name, false);
      if (!found) found = ProgramRef{t, 0, 1, false};  // a file holding just that program's blocks
    }
  }
  if (found) programs_[name] = *found;
  return found;
}

void OkRun::CallProgram(const ProgramRef& p, const std::string& name, FrameData::Kind kind, int modin_limit,
                        const Block* args) {
  if (static_cast<int>(frames_->depth()) >= kMaxDepth) {
    Fail(1, fmt::format("subprograms nested more than {} levels", kMaxDepth - 1));
  }
  const int call_line = cur_line_;
  TextSpan span{p.text, p.begin, p.text->view().size(), p.line, true};
  auto& f = frames_->Push(std::move(span), name);
  f.report_own = p.own && cur_own_;
  f.call_line = call_line;
  f.data.kind = kind;
  f.data.modin_limit = modin_limit;
  f.data.program_begin = p.begin;
  f.data.program_begin_line = p.line;
  // A file fetched by the program's name and run from its first line may begin with its tape header
  // ("$ SHAFT-ABC.SUB %", ln 8518, 8705): skipped as in a main file until the tape starts.
  f.data.tape_started = p.begin != 0;
  // Variables set in the CALL block are registered as new entries of the subprogram, in the order written, so
  // that a later one may use an earlier one (ln 7634-7666, E-98 ln 8627).
  if (args) {
    for (const Item& it : args->items) {
      if (it.assign) Assignment(args->assigns[it.i], *args, true);
    }
  }
}

void OkRun::PopLocals(int level) {
  locals_.erase(
      std::remove_if(locals_.begin(), locals_.end(), [level](const LocalVar& l) { return l.level >= level; }),
      locals_.end());
}

void OkRun::Return(int col) {
  if (frames_->depth() <= 1) Fail(col, "RTS outside a subprogram");
  if (frames_->top().data.kind == FrameData::kLap) Fail(col, "RTS inside a LAP contour definition");
  auto& f = frames_->top();
  if (f.data.runs_left > 0) {
    // CALL ... Q n: RTS starts the next run; the CALL's arguments and the locals stay registered (judgement
    // 48).
    --f.data.runs_left;
    f.at = f.data.first;
    f.data.tape_started = f.data.program_begin != 0;
    f.jumped = true;
    return;
  }
  PopLocals(static_cast<int>(frames_->depth()));
  frames_->Pop();
}

std::optional<TextPos> OkRun::FindSequence(const std::string& name, bool from_start) {
  auto& f = frames_->top();
  if (auto known = f.data.labels.Find(name)) return known;
  auto scan_range = [&](TextPos from, bool stop_at_program) -> std::optional<TextPos> {
    TextPos p = from;
    std::optional<TextPos> hit;
    ReleaseBehind release(from.pos);  // as in ProgramIn
    while (p.pos < f.span.end && !hit) {
      TextPos here = p;
      Line l = ReadLine(f.span, p);
      release.At(*f.span.text, p.pos);
      if (StartsWithLabel(l.text, name)) {
        hit = here;
      } else if (stop_at_program) {
        std::string_view s = TrimBlanks(l.text);
        if (!s.empty() && (s[0] == 'O' || s[0] == 'o') && !ProgramNameOf(s).empty() &&
            here.pos > f.data.program_begin)
          break;
      }
    }
    release.Done(*f.span.text, p.pos);
    return hit;
  };
  std::optional<TextPos> hit;
  if (!from_start) hit = scan_range(f.at, true);
  if (!hit) hit = scan_range({f.data.program_begin, f.data.program_begin_line}, true);
  if (hit) f.data.labels.Remember(name, *hit);
  return hit;
}

void OkRun::Jump(const std::string& label, int col) {
  auto hit = FindSequence(label, false);
  if (!hit) Fail(col, fmt::format("sequence name {} not found in this program", label));
  auto& f = frames_->top();
  f.jumped = true;
  f.at = *hit;
}

void OkRun::SkipContourDefinition(const Block& b) {
  // A contour definition (Nname G81/G82/G83 ... G80) is found by its sequence name and skipped in normal
  // execution (ln 6383).
  (void)b;
  int first = cur_line_;
  for (;;) {
    const Block* n = ReadBlock(&first);
    if (!n) Fail(1, "contour definition without G80");
    bool g80 = false;
    for (const Word& w : n->words) {
      if (w.addr == MakeAddr('G') && !w.expr && w.num == 80) g80 = true;
    }
    if (g80) return;
  }
}

void OkRun::TriggerModin() {
  if (modins_.empty() || lap_.active) return;
  int limit = frames_->top().data.modin_limit;
  int n = limit < 0 ? static_cast<int>(modins_.size()) : std::min(limit, static_cast<int>(modins_.size()));
  // The outermost MODIN runs first, then the inner ones (ln 8069-8073): pushed in reverse.
  for (int i = n - 1; i >= 0; --i) {
    CallProgram(modins_[static_cast<size_t>(i)].program, modins_[static_cast<size_t>(i)].name,
                FrameData::kModin, i, nullptr);
  }
}

void OkRun::ResetProgramState() {
  // M02/M30 reset processing (ln 1940-1942, 7610, 1700): zero shifts, local variables, user alarm text.
  zero_shift_ = {};
  locals_.clear();
  vuacm_ = {};
  modal_.incremental = false;
  modal_.per_rev = true;
  modal_.turret_b = false;
  modal_.comp = 40;
  modal_.chuck_barrier = modal_.tail_barrier = false;  // barrier off at reset (ln 9108)
  modal_.mtool_release = false;                        // M152 at reset (ln 4741)
  modal_.feed_fixed = false;                           // M160 at reset (the station releases it at the end)
  mc_ = MToolCycle();
  conv_ = CoordConv();  // G136 at reset (ln 6815, 9398)
  contour_mode_ = false;
  f_ = 0;
}

}  // namespace cell::interp::okuma
