// KT-APL Type II statements (manual ch. 4, 7, 8): a table from mnemonic to handler; files and tools have
// their own files (interp_files.cpp, interp_tools.cpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::ktapl {

namespace {

// A mnemonic's three characters as one number: the table is searched by integer compares, not strings (a
// statement runs in most loops). 0 for any other length (no statement's key).
constexpr uint32_t StatementKey(std::string_view m) {
  if (m.size() != 3) return 0;
  return static_cast<uint32_t>(static_cast<unsigned char>(m[0])) << 16 |
         static_cast<uint32_t>(static_cast<unsigned char>(m[1])) << 8 | static_cast<unsigned char>(m[2]);
}

}  // namespace

const std::vector<std::pair<uint32_t, KtRun::StatementFn>>& KtRun::StatementTable() {
  static const std::vector<std::pair<uint32_t, StatementFn>> kTable = [] {
    std::vector<std::pair<uint32_t, StatementFn>> t = {
        {StatementKey("PAR"), &KtRun::StPar},       {StatementKey("IFT"), &KtRun::StIft},
        {StatementKey("GTO"), &KtRun::StGto},       {StatementKey("LBL"), &KtRun::StLbl},
        {StatementKey("END"), &KtRun::StEnd},       {StatementKey("CLS"), &KtRun::StCls},
        {StatementKey("DLP"), &KtRun::StDlp},       {StatementKey("NAM"), &KtRun::StHeading},
        {StatementKey("UTL"), &KtRun::StHeading},   {StatementKey("UCY"), &KtRun::StHeading},
        {StatementKey("ACP"), &KtRun::StRefused},   {StatementKey("SSA"), &KtRun::StSsa},
        {StatementKey("MSG"), &KtRun::StMsg},       {StatementKey("OIF"), &KtRun::StOif},
        {StatementKey("OPF"), &KtRun::StOpf},       {StatementKey("CLF"), &KtRun::StClf},
        {StatementKey("FWR"), &KtRun::StFwr},       {StatementKey("DAT"), &KtRun::StDat},
        {StatementKey("CPY"), &KtRun::StFileOp},    {StatementKey("DLF"), &KtRun::StFileOp},
        {StatementKey("PRT"), &KtRun::StFileOp},    {StatementKey("RCP"), &KtRun::StFileOp},
        {StatementKey("USF"), &KtRun::StFileOp},    {StatementKey("ULF"), &KtRun::StFileOp},
        {StatementKey("CER"), &KtRun::StErrorMode}, {StatementKey("SER"), &KtRun::StErrorMode},
        {StatementKey("SET"), &KtRun::StSetWai},    {StatementKey("WAI"), &KtRun::StSetWai},
        {StatementKey("TLD"), &KtRun::StTld},       {StatementKey("FXC"), &KtRun::StFxc},
        {StatementKey("UFX"), &KtRun::StFxc},       {StatementKey("ZTB"), &KtRun::StZtb},
        {StatementKey("MIR"), &KtRun::StMir},       {StatementKey("U88"), &KtRun::StU88},
        {StatementKey("UAT"), &KtRun::StUat},       {StatementKey("EVT"), &KtRun::StEvt},
    };
    std::sort(t.begin(), t.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    return t;
  }();
  return kTable;
}

void KtRun::ExecStatement(const Statement& st, BlockCtx& bc, bool in_ift) {
  if (st.body.size() > 73) Fail(st.col, "TYPE II STATEMENT EXCEEDS 73 CHARACTERS");
  const auto& table = StatementTable();
  const uint32_t key = StatementKey(st.mnemonic);
  auto it = std::lower_bound(table.begin(), table.end(), key,
                             [](const auto& e, uint32_t k) { return e.first < k; });
  if (it == table.end() || it->first != key) Fail(st.col, "TYPE II COMMAND SYNTAX ERROR");
  (this->*(it->second))(st, bc, in_ift);
}

void KtRun::StPar(const Statement& st, BlockCtx&, bool) {
  Par(st);
}

void KtRun::Par(const Statement& st) {
  // Views into the body: a PAR runs in most loops, and copying each field cost more than evaluating it.
  InlineVec<std::string_view, 13> parts;
  bool over = false;
  ForEachTopLevel(st.body, ',', false, [&](std::string_view f) { over = over || !parts.push_back(f); });
  if (over || parts.size() > 12) Fail(st.col, "Error - exceeds 12 assignments in PAR");
  for (std::string_view a : parts) {
    // Optional "description" after the expression.
    size_t q = a.find('"');
    if (q != std::string_view::npos) {
      size_t q2 = a.find('"', q + 1);
      if (q2 == std::string_view::npos) Fail(st.col, "MISSING \" IN PARAMETER DESCRIPTION");
      if (q2 - q - 1 > 20) Fail(st.col, "PARAMETER DESCRIPTION EXCEEDS 20 CHARACTERS");
      if (!TrimView(a.substr(q2 + 1)).empty()) Fail(st.col, "TEXT AFTER PARAMETER DESCRIPTION");
      a = a.substr(0, q);
    }
    size_t eq = std::string_view::npos;
    int depth = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      if (a[i] == '(') ++depth;
      if (a[i] == ')') --depth;
      if (a[i] == '=' && depth == 0) {
        eq = i;
        break;
      }
    }
    if (eq == std::string_view::npos) Fail(st.col, "PAR ASSIGNMENT NEEDS Ln = expression");
    int n = EvalParamRef(TrimView(a.substr(0, eq)), st.col);
    if (n > 2999) Fail(st.col, "Error L numbers range from 0..2999");
    double v = Eval(a.substr(eq + 1), st.col);
    SetParam(n, v, st.col);
  }
}

void KtRun::StIft(const Statement& st, BlockCtx& bc, bool in_ift) {
  if (in_ift) Fail(st.col, "IFT IS NOT ALLOWED AS AN IFT ACTION");
  auto parts = SplitTopLevel(st.body, ',');
  if (parts.size() < 2) Fail(st.col, "IFT NEEDS A CONDITION AND AN ACTION");
  std::string cond = parts[0];
  // A view into st.body: the action's expression words must outlive this branch (they run with the
  // block's Type I words).
  std::string_view action = std::string_view(st.body).substr(cond.size() + 1);
  if (!EvalCond(cond, st.col)) return;
  ParsedBlock ab;
  try {
    ParseBlock(action, true, ab);
  } catch (RunError& e) {
    e.col = st.col;
    throw;
  }
  for (auto& w : ab.words) w.col = st.col;
  for (const auto& s : ab.stmts) {
    if (s.mnemonic == "DFS" || s.mnemonic == "DFC" || s.mnemonic == "END" || s.mnemonic == "LBL" ||
        s.mnemonic == "IFT") {
      Fail(st.col, fmt::format("{} IS NOT ALLOWED AS AN IFT ACTION", s.mnemonic));
    }
    Statement inner = s;
    inner.col = st.col;
    ExecStatement(inner, bc, true);
  }
  for (auto& w : ab.words) AddWord(bc.words, w);
}

namespace {

// A GTO / LBL label: 1-9999.
int Label(const Statement& st, const char* what) {
  std::string v = Trim(st.body);
  if (v.empty() || v.size() > 4 || !std::all_of(v.begin(), v.end(), IsDigit) || std::stoi(v) < 1) {
    Fail(st.col, fmt::format("{} LABEL MUST BE 1-9999", what));
  }
  return std::stoi(v);
}

}  // namespace

void KtRun::StGto(const Statement& st, BlockCtx& bc, bool) {
  bc.jump = Label(st, "GTO");
  bc.jump_col = st.col;
  bc.gto_count++;
}

void KtRun::StLbl(const Statement& st, BlockCtx&, bool) {
  (void)Label(st, "LBL");
}

void KtRun::StEnd(const Statement& st, BlockCtx& bc, bool) {
  bc.end = true;
  bc.end_col = st.col;
}

void KtRun::StCls(const Statement& st, BlockCtx& bc, bool) {
  if (RunningCycle()) Fail(st.col, "A RUNNING DEFINED CYCLE CANNOT CALL A SUBROUTINE");
  // Views into the body, as PAR's (a call in a loop).
  InlineVec<std::string_view, 14> parts;
  bool over = false;
  ForEachTopLevel(st.body, ',', true, [&](std::string_view f) { over = over || !parts.push_back(f); });
  std::string name = Upper(ExpandName(TrimView(parts[0]), st.col));
  if (name.empty()) Fail(st.col, "CLS NEEDS A SUBROUTINE NAME");
  if (over || parts.size() - 1 > 12) Fail(st.col, "Error - exceeds 12 L's");
  std::map<int, double> locals;
  std::optional<double> literal_count;
  for (size_t i = 1; i < parts.size(); ++i) {
    std::string_view f = TrimView(parts[i]);
    if (i == 1 && !f.empty() && (IsDigit(f[0]) || f[0] == '.')) {
      try {
        literal_count = Eval(f, st.col);
      } catch (...) {
        Fail(st.col, "CLS RUN COUNT MUST BE A NUMBER");
      }
      continue;
    }
    size_t q = f.find('"');
    if (q != std::string_view::npos) f = f.substr(0, q);
    size_t eq = std::string_view::npos;
    int depth = 0;
    for (size_t k = 0; k < f.size(); ++k) {
      if (f[k] == '(') ++depth;
      if (f[k] == ')') --depth;
      if (f[k] == '=' && depth == 0) {
        eq = k;
        break;
      }
    }
    if (eq == std::string_view::npos) Fail(st.col, "CLS PARAMETER NEEDS Ln = expression");
    int n = EvalParamRef(TrimView(f.substr(0, eq)), st.col);
    double v = Eval(f.substr(eq + 1), st.col);  // evaluated at the caller's level
    if (n > 2999) Fail(st.col, "Error L numbers range from 0..2999");
    if (n <= 99) {
      locals[n] = v;
    } else {
      SetParam(n, v, st.col);
    }
  }
  if (literal_count) locals[0] = *literal_count;
  auto d = FindDef(name);
  if (!d || d->is_cycle) Fail(st.col, "Error - Subroutine or Defined Cycle Not Found (" + name + ")");
  BlockCtx::Call& call = bc.call.emplace();
  call.def = std::move(*d);
  call.def.name = std::move(name);
  call.locals = std::move(locals);
  call.col = st.col;
}

void KtRun::StDlp(const Statement& st, BlockCtx&, bool) {
  for (const auto& f : SplitTopLevel(st.body, ',')) {
    std::string r = Trim(f);
    if (r.empty()) continue;
    DeleteParam(EvalParamRef(r, st.col));
  }
}

void KtRun::StHeading(const Statement&, BlockCtx&, bool) {
  // Heading / option data: no effect on the run (read by the program store and the scheduler).
}

// ln 3171-3226: ACP sets the target horsepower of adaptive control, which the cell cannot measure (G51).
void KtRun::StRefused(const Statement& st, BlockCtx&, bool) {
  Fail(st.col, st.mnemonic +
                   " IS NOT AVAILABLE: ADAPTIVE CONTROL NEEDS SPINDLE HORSEPOWER, WHICH THE CELL "
                   "CANNOT MEASURE");
}

// ln 7253: (SSA,angle) "must be given while the G33 is modal"; the threads after it start that many
// degrees from the first lead's start (a multiple-lead thread). It holds until another SSA or the end of G33
// (judgement call 89).
void KtRun::StSsa(const Statement& st, BlockCtx&, bool) {
  if (!mode_.threading) Fail(st.col, "SSA MUST BE GIVEN WHILE G33 IS MODAL");
  thread_angle_ = Eval(Trim(st.body), st.col);
}

void KtRun::StDat(const Statement&, BlockCtx&, bool) {
  auto now = env_->Now();
  for (int i = 0; i < 6; ++i) dat_[i] = now[i];
}

void KtRun::StErrorMode(const Statement& st, BlockCtx&, bool) {
  for (const auto& f : SplitTopLevel(st.body, ',')) {
    std::string k = Upper(Trim(f));
    if (k != "MAS" && k != "SEQ" && k != "REM") Fail(st.col, "TYPE II COMMAND SYNTAX ERROR");
    const int device = k == "MAS" ? kDeviceMas : k == "SEQ" ? kDeviceSeq : kDeviceRem;
    if (st.mnemonic == "CER") {
      cer_ |= device;
    } else {
      cer_ &= ~device;
    }
  }
}

void KtRun::StSetWai(const Statement& st, BlockCtx&, bool) {
  const bool wai = st.mnemonic == "WAI";
  auto parts = SplitTopLevel(st.body, ',');
  int bits = 0;
  for (const auto& p : parts) bits += Trim(p).find('=') != std::string::npos ? 1 : 0;
  if (bits > 8) Fail(st.col, fmt::format("{} ALLOWS AT MOST 8 BITS", st.mnemonic));
  std::string spec;
  for (char ch : st.body) {
    if (ch != ' ') spec += Up(ch);
  }
  if (!st.has_body) spec = "SAVE";
  if (wai) {
    Out<WaitInputOp>().spec = spec;
    env_->WaitInputs(spec);
  } else {
    Out<OutputOp>().spec = spec;
  }
}

void KtRun::StMir(const Statement& st, BlockCtx& bc, bool in_ift) {
  // ln 5369, 5380: "The Axis Inversion command must be programmed in a data block by itself" (a label may
  // share it, ln 9106; as an IFT action it is the action's only item).
  if (!in_ift && bc.own_words > 0) Fail(st.col, "MIR MUST BE PROGRAMMED IN A DATA BLOCK BY ITSELF");
  std::string b = Upper(st.body);
  b.erase(std::remove(b.begin(), b.end(), ' '), b.end());
  size_t xi = b.find('X'), yi = b.find('Y');
  auto flag = [&](size_t at) -> int {
    if (at == std::string::npos || at + 1 >= b.size()) return -1;
    return b[at + 1] == '1' ? 1 : (b[at + 1] == '0' ? 0 : -1);
  };
  int fx = flag(xi), fy = flag(yi);
  if ((xi != std::string::npos && fx < 0) || (yi != std::string::npos && fy < 0) ||
      (xi == std::string::npos && yi == std::string::npos)) {
    Fail(st.col, "MIR FORMAT IS (MIR,XnYn) WITH n 0 OR 1");
  }
  if (fx >= 0) mir_x_ = fx == 1;
  if (fy >= 0) mir_y_ = fy == 1;
}

void KtRun::StU88(const Statement& st, BlockCtx&, bool) {
  std::string b = Upper(st.body);
  b.erase(std::remove(b.begin(), b.end(), ','), b.end());
  ParsedBlock pb;
  ParseBlock(b, true, pb);
  for (const auto& w : pb.words) {
    double v = w.kind == WordKind::kNumber
                   ? ScaleLiteral(w.letter, w.num, metric_, false, false)
                   : (w.kind == WordKind::kExpr ? Eval(w.expr, st.col)
                                                : Param(w.param) * (w.kind == WordKind::kNegParam ? -1 : 1));
    if (w.letter == 'X') {
      u88_x_ = ToMm(v);
    } else if (w.letter == 'Y') {
      u88_y_ = ToMm(v);
    } else {
      Fail(st.col, "U88 TAKES X AND Y");
    }
  }
}

void KtRun::StEvt(const Statement& st, BlockCtx&, bool) {
  Out<EventOp>().text = Trim(st.body);
}

}  // namespace cell::interp::ktapl
