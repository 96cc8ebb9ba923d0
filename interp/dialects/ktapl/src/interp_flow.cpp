// KT-APL block stepping and control flow: the run's life cycle, one block at a time, DFS/DFC definitions,
// CLS and cycle calls, (END) with run counts, GTO (manual ch. 4 and 8).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::ktapl {

KtRun::KtRun(const RunOptions& o) : RunBase(o) {
  auto param_number = [](const std::string& key) -> int {
    if (key.size() < 2 || key.size() > 5 || key[0] != 'L' ||
        !std::all_of(key.begin() + 1, key.end(), IsDigit)) {
      return -1;
    }
    return std::stoi(key.substr(1));
  };
  for (const auto& [k, v] : o.params) {
    std::string key = Upper(Trim(k));
    std::string val = Upper(Trim(v));
    auto num = [&](double def) {
      try {
        double d = std::stod(val);
        return std::isfinite(d) ? std::clamp(d, -1e12, 1e12) : def;
      } catch (...) {
        return def;
      }
    };
    if (key == "UNITS") {
      basic_metric_ = (val == "MM" || val == "METRIC" || val == "G71");
    } else if (key == "BLOCK_DELETE") {
      block_delete_ = num(0) != 0;
    } else if (key == "OPTIONAL_STOP") {
      optional_stop_ = num(0) != 0;
    } else if (key == "OPERATOR") {
      operator_ = num(0) != 0;
    } else if (key == "PALLET") {
      pallet_ = static_cast<int>(std::clamp(num(0), 0.0, 999.0));
    } else if (key == "PART_NUMBER") {
      part_number_ = val;
    } else if (key == "CODED_PALLETS") {
      max_pallet_ = num(0) != 0 ? 127 : 255;
    } else if (key == "B_AXIS") {
      b_index_ = val != "ROTARY";
    } else if (key == "MAX_IDLE_BLOCKS") {
      max_idle_ = std::max(1L, static_cast<long>(num(1000000)));
    } else if (int n = param_number(key); n >= 100 && n <= 999) {
      program_[n] = num(0);
    } else if (n >= 1000 && n <= 2999) {
      machine_[n] = num(0);
    }
  }
  // The station's persistent machine parameters (L1000-L2999) and fixture table (H1.X ..., FixtureKey).
  for (const auto& [k, v] : o.variables) {
    if (!std::isfinite(v)) continue;
    if (auto f = ParseFixtureKey(k)) {
      FixtureLine& line = fixtures_[f->h];
      line.set = true;
      if (f->axis < 0) {
        line.has_i = true;
        line.i = v;
      } else {
        line.v[f->axis] = v;
      }
      continue;
    }
    int n = param_number(Upper(Trim(k)));
    if (n >= 1000 && n <= 2999) machine_[n] = v;
  }
  metric_ = basic_metric_;
  tools_ = o.tools;
  frames_ = std::make_unique<Frames>(o.program ? o.program : ProgramText::FromString(o.program_text));
}

std::map<std::string, double> KtRun::Variables() const {
  std::map<std::string, double> out;
  for (const auto& [n, v] : machine_) out["L" + std::to_string(n)] = v;
  // The fixture table stays in the CNC's memory too (FXC/UFX, manual ch. 6): every line that was set.
  for (int h = 1; h <= kFixtureLines; ++h) {
    const FixtureLine& line = fixtures_[h];
    if (!line.set) continue;
    for (int a : {kX, kY, kZ, kA, kB, kC}) out[FixtureKey(h, a)] = line.v[a];
    if (line.has_i) out[FixtureKey(h, -1)] = line.i;
  }
  return out;
}

void KtRun::Finish(Step::Kind kind) {
  if (kind == Step::kEnd) {
    if (comp_.engaged()) CompFinish();
    EmitUnitsOnce();
    End();
  }
}

void KtRun::EmitUnitsOnce() {
  if (units_emitted_) return;
  units_emitted_ = true;
  out_.Emplace<UnitsOp>(cur_line_).metric = metric_;
}

void KtRun::SetUnits(bool metric) {
  if (metric == metric_) return;
  metric_ = metric;
  if (!units_emitted_) return;
  if (comp_.engaged()) [[unlikely]] {
    CompSlot<UnitsOp>().metric = metric_;
    return;
  }
  out_.Emplace<UnitsOp>(cur_line_).metric = metric_;
}

void KtRun::StepOnce() {
  Frames& fr = *frames_;
  std::optional<Line> line = fr.NextLine();
  if (!line) {
    if (fr.depth() == 1) {
      Finish(Step::kEnd);
    } else {
      fr.Pop();  // a library body without (END): implicit return
    }
    return;
  }
  const auto& top = fr.top();
  cur_own_ = top.report_own;
  cur_line_ = top.report_own ? line->number : top.call_line;
  try {
    if (++idle_ > max_idle_) {
      Fail(1, fmt::format("PROGRAM RAN {} BLOCKS WITHOUT MOTION OR OUTPUT (ENDLESS LOOP?)", max_idle_));
    }
    ExecBlock(line->text, line->start);
  } catch (const RunError& e) {
    Diagnostic d;
    d.program = opt_.program_name;
    d.line = cur_line_;
    d.col = cur_own_ ? e.col : 1;
    d.alarm = e.alarm;
    d.text = e.text;
    if (!cur_own_) {
      for (size_t i = fr.depth(); i-- > 0;) {
        if (!fr[i].report_own) {
          d.text = fmt::format("{} (in {} line {})", e.text, fr[i].name, line->number);
          break;
        }
      }
    }
    EndWithError(std::move(d));
  } catch (const ExprError& e) {
    Diagnostic d;
    d.program = opt_.program_name;
    d.line = cur_line_;
    d.col = 1;
    d.text = e.text;
    EndWithError(std::move(d));
  }
  block_ = {};  // the view is only valid while its block runs (diagnostic columns)
}

void KtRun::ExecBlock(std::string_view text, size_t start) {
  if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
  if (text.size() + 1 > 80) Fail(80, "BLOCK EXCEEDS 80 CHARACTERS");
  block_ = text;
  std::string_view t = TrimView(text);
  if (t.empty() || t == "%") return;
  size_t li = frames_->depth() - 1;
  auto& f = frames_->top();
  const ParsedBlock* cached = nullptr;
  bool repeats = li > 0 || f.jumped;
  if (repeats) cached = cache_.Find(f.span.text.get(), start);
  if (!cached) {
    ParseBlock(text, false, fresh_);
    cached = repeats ? &cache_.Put(f.span.text, start, std::move(fresh_)) : &fresh_;
  }
  const ParsedBlock& pb = *cached;
  if (pb.deleted && block_delete_) return;
  if (!pb.comment.empty() || !block_comment_.empty()) block_comment_ = pb.comment;  // most have none
  for (const auto& st : pb.stmts) {
    if (st.mnemonic == "DFS" || st.mnemonic == "DFC") {
      Define(st, li);
      return;
    }
  }
  BlockCtx bc;
  bc.words = pb.words;
  bc.items = static_cast<int>(pb.words.size() + pb.stmts.size());
  bc.own_words = static_cast<int>(pb.words.size());
  for (const auto& st : pb.stmts) ExecStatement(st, bc, false);
  if (bc.gto_count > 0) {
    int others = 0;
    for (const auto& st : pb.stmts) {
      if (st.mnemonic != "GTO" && st.mnemonic != "LBL" && st.mnemonic != "IFT") ++others;
    }
    if (others > 0 || !pb.words.empty() || bc.gto_count > 1) {
      Fail(bc.jump_col, "GTO MUST BE THE ONLY STATEMENT IN ITS BLOCK");
    }
  }
  ExecTypeI(bc, &pb);
  if (comp_.engaged()) [[unlikely]] {
    // Error 0003 counts blocks that reach the ready list: Type I words and statements that act on the
    // machine or the operator; PAR, IFT, GTO and LBL only compute and branch (the manual's own G833/G834
    // loops run five of them between Z/U moves under G41/G42, ln 7298-7311 and 7395-7408; judgement call 42).
    bool counts = !pb.words.empty();
    for (const auto& st : pb.stmts) {
      if (st.mnemonic != "PAR" && st.mnemonic != "IFT" && st.mnemonic != "GTO" && st.mnemonic != "LBL")
        counts = true;
    }
    CompEndBlock(counts);
  }
  if (bc.cycle_return) {
    ReturnFromCycle();
    return;
  }
  if (bc.jump) DoJump(*bc.jump, bc.jump_col);
  if (bc.call) DoCall(bc.call->def, std::move(bc.call->locals), false);
  if (bc.end) DoEnd(bc.end_col);
}

void KtRun::ReturnFromCycle() {
  while (frames_->depth() > 1) {
    const bool cycle = frames_->top().data.is_cycle;
    frames_->Pop();
    if (cycle) return;
  }
}

void KtRun::Define(const Statement& st, size_t li) {
  auto fields = SplitTopLevel(st.body, ',');
  std::string name = Upper(Trim(fields[0]));
  bool save = fields.size() > 1 && Upper(Trim(fields[1])) == "SAVE";
  if (name.empty()) Fail(st.col, fmt::format("{} NEEDS A NAME", st.mnemonic));
  if (li > 0) Fail(st.col, "DEFINITIONS ARE NOT ALLOWED INSIDE A SUBROUTINE OR CYCLE");
  bool is_cycle = st.mnemonic == "DFC";
  auto gnum = [&]() -> int {
    if (name.size() < 2 || name.size() > 5 || name[0] != 'G') return -1;
    for (size_t k = 1; k < name.size(); ++k) {
      if (!IsDigit(name[k])) return -1;
    }
    return std::stoi(name.substr(1));
  }();
  if (is_cycle) {
    bool ok = (gnum >= 801 && gnum <= 899) || (gnum >= 81 && gnum <= 89) || (gnum >= 24 && gnum <= 27);
    if (!ok) Fail(st.col, "DFC NAME MUST BE G801-G899 (OR A SUPPLIED CYCLE G24-G27, G81-G89)");
  } else if ((gnum >= 80 && gnum <= 89) || (gnum >= 800 && gnum <= 899) || (gnum >= 24 && gnum <= 27) ||
             gnum == 31) {
    Fail(st.col, "SUBROUTINE NAME MAY NOT BE A CYCLE NAME");
  }
  if (local_defs_ >= kMaxDefinitions && !defs_.count(name)) {
    Fail(st.col, "MORE THAN 20 SUBROUTINE AND CYCLE DEFINITIONS");
  }
  auto& f = (*frames_)[li];
  Def d;
  d.span = {f.span.text, f.at.pos, f.span.end, f.at.line};
  d.report_own = f.report_own;
  d.is_cycle = is_cycle;
  d.name = name;
  const size_t def_start = f.at.pos;
  // Skip to the block holding (END).
  TextPos p = f.at;
  bool found = false;
  while (p.pos < f.span.end) {
    Line b = ReadLine(f.span, p);
    for (const auto& s : FindStatements(b.text, nullptr)) {
      if (s.mnemonic == "END") found = true;
      if (s.mnemonic == "DFS" || s.mnemonic == "DFC") {
        Fail(st.col, "DEFINITIONS MAY NOT BE NESTED (MISSING (END)?)");
      }
    }
    if (found) break;
  }
  if (!found) Fail(st.col, fmt::format("{} {} HAS NO (END)", st.mnemonic, name));
  d.span.end = p.pos;
  f.at = p;
  if (!defs_.count(name)) ++local_defs_;
  defs_[name] = d;
  if (save && opt_.save) {
    opt_.save(name, std::string(f.span.text->view().substr(def_start, p.pos - def_start)));
  }
}

std::optional<Def> KtRun::LoadLibrary(const std::string& name, const std::string& body) {
  auto text = ProgramText::FromString(body);
  Def d;
  d.span.text = text;
  d.report_own = false;
  d.name = name;
  d.is_cycle = name.size() > 1 && name[0] == 'G' && IsDigit(name[1]);
  // Find the (DFS,name) / (DFC,name) header; without one the whole text is the body.
  TextSpan all{text, 0, text->view().size(), 1};
  d.span.end = all.end;
  TextPos p{0, 1};
  while (p.pos < all.end) {
    Line b = ReadLine(all, p);
    for (const auto& s : FindStatements(b.text, nullptr)) {
      if ((s.mnemonic == "DFS" || s.mnemonic == "DFC") &&
          Upper(Trim(SplitTopLevel(s.body, ',')[0])) == name) {
        d.span.begin = p.pos;
        d.span.begin_line = p.line;
        return d;
      }
    }
  }
  return d;
}

std::optional<Def> KtRun::FindDef(const std::string& name) {
  auto it = defs_.find(name);
  if (it != defs_.end()) return it->second;
  auto fi = files_.find(name);
  if (fi != files_.end() && open_file_ != name) return LoadLibrary(name, fi->second.text);
  auto ci = lib_cache_.find(name);
  if (ci != lib_cache_.end()) return ci->second;
  std::optional<std::string> text;
  if (opt_.library) text = opt_.library(name);
  if (!text) text = KtaplStandardLibrary(name);
  if (!text) return std::nullopt;
  auto d = LoadLibrary(name, *text);
  if (d) lib_cache_[name] = *d;
  return d;
}

bool KtRun::RunningCycle() const {
  return std::any_of(frames_->begin(), frames_->end(), [](const auto& f) { return f.data.is_cycle; });
}

void KtRun::CallCycle(int g) {
  const std::string name = fmt::format("G{}", g);
  auto d = FindDef(name);
  if (!d) Fail(1, fmt::format("Error - Subroutine or Defined Cycle Not Found ({})", name));
  DoCall(*d, {}, true);
  frames_->top().name = name;
}

void KtRun::DoCall(const Def& d, std::map<int, double> locals, bool is_cycle) {
  if (static_cast<int>(frames_->depth()) >= kMaxLevels) {
    Fail(1, "Error - subroutine nesting exceeds 3 levels");
  }
  const int call_line = cur_line_;
  auto& f = frames_->Push(d.span, d.name);
  f.report_own = d.report_own && cur_own_ && !is_cycle;  // cycles report the calling block's line
  f.call_line = call_line;
  f.data.is_cycle = is_cycle;
  if (!locals.count(0)) locals[0] = 1;
  f.data.locals = std::move(locals);
}

void KtRun::DoEnd(int col) {
  if (frames_->depth() <= 1) Fail(col, "(END) WITHOUT A SUBROUTINE OR CYCLE");
  auto& f = frames_->top();
  double count = f.data.locals.count(0) ? f.data.locals[0] - 1 : 0;
  if (count > 0) {
    f.data.locals[0] = count;
    f.at = {f.span.begin, f.span.begin_line};
    return;
  }
  frames_->Pop();
}

void KtRun::DoJump(int label, int col) {
  auto& f = frames_->top();
  f.jumped = true;
  if (auto known = f.data.labels.Find(label)) {
    f.at = *known;
    return;
  }
  // The label's block, searching forward from here, then from the frame's start (outside definitions).
  auto scan = [&](TextPos from, size_t to) -> std::optional<TextPos> {
    TextPos p = from;
    bool in_def = false;
    while (p.pos < to) {
      TextPos here = p;
      Line b = ReadLine(f.span, p);
      bool maybe = false;
      for (size_t k = 0; k + 2 < b.text.size(); ++k) {
        const char c0 = Up(b.text[k]), c1 = Up(b.text[k + 1]), c2 = Up(b.text[k + 2]);
        if ((c0 == 'L' && c1 == 'B' && c2 == 'L') || (c0 == 'D' && c1 == 'F') ||
            (c0 == 'E' && c1 == 'N' && c2 == 'D')) {
          maybe = true;
        }
      }
      if (!maybe) continue;
      for (const auto& s : FindStatements(b.text, nullptr)) {
        if (s.mnemonic == "DFS" || s.mnemonic == "DFC") in_def = true;
        if (s.mnemonic == "END" && in_def) {
          in_def = false;
          continue;
        }
        if (!in_def && s.mnemonic == "LBL") {
          std::string v = Trim(s.body);
          if (!v.empty() && std::all_of(v.begin(), v.end(), IsDigit) && v.size() < 6 &&
              std::stoi(v) == label) {
            return here;
          }
        }
      }
    }
    return std::nullopt;
  };
  auto hit = scan(f.at, f.span.end);
  if (!hit) hit = scan({f.span.begin, f.span.begin_line}, f.at.pos);
  if (!hit) Fail(col, fmt::format("Error -GTO label not found ({})", label));
  f.data.labels.Remember(label, *hit);
  f.at = *hit;
}

}  // namespace cell::interp::ktapl
