// The KT-APL executor: tape/block format, modal state, motion, parameters, control flow, subroutines and
// defined cycles. Blocks are read one at a time from the program text (nothing is pre-parsed), so memory
// does not grow with program length.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cell/error/error.h"
#include "cell/interp/ktapl.h"
#include "cutter_comp.h"
#include "expr.h"
#include "util.h"

namespace cell::interp {
namespace ktapl {
namespace {

constexpr double kInch = 25.4;
constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxLevels = 4;  // main + 3 nested calls
constexpr int kMaxDefinitions = 20;

struct RunError {
  std::string alarm;
  std::string text;
  int col = 1;
};

[[noreturn]] void Fail(int col, const std::string& text, const std::string& alarm = "") {
  throw RunError{alarm, text, col};
}

bool IsDigit(char c) {
  return std::isdigit(static_cast<unsigned char>(c)) != 0;
}
bool IsAlpha(char c) {
  return std::isalpha(static_cast<unsigned char>(c)) != 0;
}
int AxisOfLetter(char c) {
  switch (c) {
    case 'X':
      return kX;
    case 'Y':
      return kY;
    case 'Z':
      return kZ;
    case 'A':
      return kA;
    case 'B':
      return kB;
    case 'C':
      return kC;
    case 'U':
      return kU;
    case 'V':
      return kV;
    case 'W':
      return kW;
    default:
      return -1;
  }
}

// A number as written in a Type I word.
struct RawNum {
  bool neg = false;
  bool point = false;
  double as_written = 0;  // with the point where written, or the integer digits when there is none
};

enum class WordKind { kNumber, kParam, kNegParam, kExpr };

struct RawWord {
  char letter = 0;
  WordKind kind = WordKind::kNumber;
  RawNum num;
  int param = 0;
  std::string_view expr;  // into the block text, which outlives the block's execution
  int col = 1;
};

// At most 40 words fit in an 80-character block; 48 leaves room for IFT action words.
constexpr size_t kMaxWords = 48;
using RawWords = InlineVec<RawWord, kMaxWords>;

struct Word {
  char letter = 0;
  double v = 0;
  bool literal = false;  // written as a number (format scaling applied)
  bool neg_zero = false;
  int col = 1;
};

using Words = InlineVec<Word, kMaxWords>;

// A G code of the block and its column.
struct GWord {
  int first = 0;   // the code
  int second = 1;  // column
};

struct ParsedBlock {
  bool deleted = false;
  bool has_n = false;
  RawNum n;  // the sequence number as written (passed to G800-series cycles as L814)
  RawWords words;
  std::vector<Statement> stmts;
  std::string comment;
};

// Implied decimals of a letter when written without a point.
int ImpliedDecimals(char letter, bool metric, bool dwell, bool passing) {
  switch (letter) {
    case 'A':
    case 'B':
    case 'C':
      return 3;
    case 'U':
    case 'V':
    case 'W':
      return passing ? (metric ? 3 : 4) : 3;
    case 'F':
      return dwell ? 1 : (metric ? 0 : 1);
    case 'D':
    case 'O':
      return passing ? 4 : (metric ? 3 : 4);
    case 'N':
      return passing ? 4 : 0;
    case 'G':
    case 'H':
    case 'M':
    case 'P':
    case 'S':
    case 'T':
      return 0;
    default:
      return metric ? 3 : 4;  // E I J K Q R X Y Z
  }
}

bool IntegerLetter(char c) {
  return c == 'G' || c == 'H' || c == 'M' || c == 'P' || c == 'S' || c == 'T';
}

double ScaleLiteral(char letter, const RawNum& n, bool metric, bool dwell, bool passing) {
  static constexpr double kPow10[] = {1.0, 10.0, 100.0, 1000.0, 10000.0};
  double v = n.as_written;
  if (!n.point) v /= kPow10[ImpliedDecimals(letter, metric, dwell, passing)];
  return n.neg ? -v : v;
}

void AddWord(RawWords& words, const RawWord& w) {
  if (!words.push_back(w)) Fail(w.col, "TOO MANY WORDS IN THE BLOCK");
}

// Parses one block (or an IFT action fragment) into words and statements. Expression words view `s`.
ParsedBlock ParseBlock(std::string_view s, bool fragment) {
  ParsedBlock pb;
  size_t i = 0;
  auto skip = [&] {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  };
  skip();
  if (!fragment && i < s.size() && s[i] == '/') {
    pb.deleted = true;
    ++i;
    skip();
  }
  if (!fragment && i < s.size() && Up(s[i]) == 'N' && i + 1 < s.size() &&
      (IsDigit(s[i + 1]) || s[i + 1] == '.')) {
    pb.has_n = true;
    ++i;
    double v = 0, scale = 0;
    while (i < s.size() && (IsDigit(s[i]) || s[i] == '.')) {
      if (s[i] == '.') {
        if (pb.n.point) Fail(static_cast<int>(i) + 1, "ILLEGAL SEQUENCE NUMBER");
        pb.n.point = true;
        scale = 0.1;
      } else if (pb.n.point) {
        v += (s[i] - '0') * scale;
        scale /= 10;
      } else {
        v = v * 10 + (s[i] - '0');
      }
      ++i;
    }
    pb.n.as_written = v;
  }
  while (true) {
    skip();
    if (i >= s.size()) break;
    char c = s[i];
    if (c == '!') {
      pb.comment = Trim(s.substr(i + 1));
      break;
    }
    if (c == '(' || (c == '%' && i + 1 < s.size() && IsAlpha(s[i + 1]))) {
      std::string err;
      auto sts = FindStatements(s.substr(i), &err);
      if (sts.empty()) Fail(static_cast<int>(i) + 1, err.empty() ? "TYPE II COMMAND SYNTAX ERROR" : err);
      Statement st = sts[0];
      st.col += static_cast<int>(i);
      if (st.mnemonic.size() != 3) Fail(st.col, "TYPE II COMMAND SYNTAX ERROR");
      i += st.end;
      pb.stmts.push_back(std::move(st));
      continue;
    }
    if (c == '%') {  // stray rewind stop / EIA framing character
      ++i;
      continue;
    }
    if (!IsAlpha(c)) Fail(static_cast<int>(i) + 1, fmt::format("ILLEGAL CHARACTER '{}'", c));
    RawWord w;
    w.letter = Up(c);
    w.col = static_cast<int>(i) + 1;
    if (w.letter == 'N') Fail(w.col, "N WORD MUST BE THE FIRST WORD OF THE BLOCK");
    if (w.letter == 'L') Fail(w.col, "ILLEGAL ADDRESS L");
    ++i;
    skip();
    if (i < s.size() && s[i] == ',') {
      // Expression form: up to the next top-level comma, a comment, or the end of the block.
      ++i;
      size_t start = i;
      int depth = 0;
      while (i < s.size()) {
        char d = s[i];
        if (d == '(') ++depth;
        if (d == ')') {
          if (depth == 0) break;
          --depth;
        }
        if ((d == ',' || d == '!') && depth == 0) break;
        ++i;
      }
      w.kind = WordKind::kExpr;
      w.expr = s.substr(start, i - start);
      if (TrimView(w.expr).empty()) Fail(w.col, "EXPRESSION EXPECTED AFTER ','");
      if (i < s.size() && s[i] == ',') ++i;
      AddWord(pb.words, w);
      continue;
    }
    bool neg = false;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) {
      neg = s[i] == '-';
      ++i;
      skip();
    }
    if (i < s.size() && Up(s[i]) == 'L' && i + 1 < s.size() && IsDigit(s[i + 1])) {
      ++i;
      long n = 0;
      while (i < s.size() && IsDigit(s[i])) {
        n = n * 10 + (s[i] - '0');
        if (n > 99999) Fail(w.col, "Error L numbers range from 0..3999");
        ++i;
      }
      if (n > 3999) Fail(w.col, "Error L numbers range from 0..3999");
      w.kind = neg ? WordKind::kNegParam : WordKind::kParam;
      w.param = static_cast<int>(n);
      AddWord(pb.words, w);
      continue;
    }
    RawNum num;
    num.neg = neg;
    int digits = 0;
    double v = 0;
    while (i < s.size() && IsDigit(s[i])) {
      v = v * 10 + (s[i] - '0');
      ++digits;
      ++i;
    }
    if (i < s.size() && s[i] == '.') {
      num.point = true;
      ++i;
      double scale = 0.1;
      while (i < s.size() && IsDigit(s[i])) {
        v += (s[i] - '0') * scale;
        scale /= 10;
        ++digits;
        ++i;
      }
    }
    if (digits == 0) Fail(w.col, fmt::format("NUMBER EXPECTED AFTER {}", w.letter));
    if (digits > 9) Fail(w.col, fmt::format("TOO MANY DIGITS IN {} WORD", w.letter));
    num.as_written = v;
    w.num = num;
    AddWord(pb.words, w);
  }
  return pb;
}

struct Def {
  std::shared_ptr<const ProgramText> text;
  size_t begin = 0, end = 0;
  int begin_line = 1;
  bool report_own = true;
  bool is_cycle = false;
  std::string name;
};

struct Level {
  std::shared_ptr<const ProgramText> text;
  size_t begin = 0, end = 0;
  int begin_line = 1;
  size_t pos = 0;
  int line = 1;
  bool report_own = true;
  int call_line = 0;
  bool is_cycle = false;
  std::string name;
  std::map<int, double> locals;
  // label -> (block start, line), most recently used first (a vector: a deque allocates when constructed,
  // and a level is constructed at every call).
  std::vector<std::pair<int, std::pair<size_t, int>>> labels;
  bool jumped = false;  // a GTO has run here: blocks may run again
};

// Parsed blocks that run more than once (subroutine and cycle bodies, GTO loops) are kept in a small
// direct-mapped table keyed by (text, offset), so a loop parses each block once. The entry pins its text:
// expression words view it. Size is fixed, so memory does not grow with the program.
class BlockCache {
 public:
  const ParsedBlock* Find(const ProgramText* text, size_t off) const {
    const Entry& e = table_[Slot(text, off)];
    return (e.valid && e.text.get() == text && e.off == off) ? &e.pb : nullptr;
  }
  const ParsedBlock& Put(const std::shared_ptr<const ProgramText>& text, size_t off, ParsedBlock&& pb) {
    Entry& e = table_[Slot(text.get(), off)];
    e.valid = true;
    e.text = text;
    e.off = off;
    e.pb = std::move(pb);
    return e.pb;
  }

 private:
  static constexpr size_t kSlots = 256;
  struct Entry {
    bool valid = false;
    std::shared_ptr<const ProgramText> text;
    size_t off = 0;
    ParsedBlock pb;
  };
  static size_t Slot(const ProgramText* text, size_t off) {
    return (reinterpret_cast<uintptr_t>(text) / 16 + off * 2654435761u) % kSlots;
  }
  std::vector<Entry> table_ = std::vector<Entry>(kSlots);
};

// FIFO of commands produced by a block and not yet taken: a ring over a vector, because a deque of
// Canon (larger than a deque node) allocates and frees a node for every command.
class CanonQueue {
 public:
  bool empty() const { return size_ == 0; }
  Canon& front() { return ring_[head_]; }
  void pop_front() {
    head_ = (head_ + 1) % ring_.size();
    --size_;
  }
  void push_back(Canon c) { Slot() = std::move(c); }
  // A new last element to be filled in place (reset to the defaults; its strings keep their buffers).
  Canon& Slot() {
    if (size_ == ring_.size()) Grow();
    Canon& c = ring_[(head_ + size_) % ring_.size()];
    ++size_;
    c.Reset();
    return c;
  }
  void clear() { head_ = size_ = 0; }

 private:
  void Grow() {
    std::vector<Canon> bigger(ring_.empty() ? 16 : ring_.size() * 2);
    for (size_t i = 0; i < size_; ++i) bigger[i] = std::move(ring_[(head_ + i) % ring_.size()]);
    ring_.swap(bigger);
    head_ = 0;
  }
  std::vector<Canon> ring_;
  size_t head_ = 0, size_ = 0;
};

struct FixtureLine {
  bool set = false;
  bool has_i = false;
  double i = 0;
  std::array<double, kAxisCount> v{};
};

struct BlockCtx {
  RawWords words;
  std::optional<int> jump;
  int jump_col = 1;
  bool end = false;
  int end_col = 1;
  bool call = false;
  Def call_def;
  std::map<int, double> call_locals;
  int call_col = 1;
  int gto_count = 0;
  int items = 0;
};

class KtRun final : public Run, public ExprContext {
 public:
  explicit KtRun(const RunOptions& o);

  Step Next() override;
  void NextInto(Step& s) override;
  std::map<int, double> MachineParameters() const override { return machine_; }
  std::vector<ToolEntry> Tools() const override { return tools_; }

  // Tool-table files: applies G70/G71 and (TLD,...) of one line.
  void LoadToolLine(std::string_view line) {
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    std::string_view t = TrimView(line);
    if (t.empty() || t == "%") return;
    ParsedBlock pb = ParseBlock(line, false);
    for (const auto& w : pb.words) {
      if (w.letter == 'G' && w.kind == WordKind::kNumber && !w.num.point) {
        if (w.num.as_written == 70) metric_ = false;
        if (w.num.as_written == 71) metric_ = true;
      }
    }
    for (const auto& st : pb.stmts) {
      if (st.mnemonic == "TLD") Tld(st);
      if (st.mnemonic == "PAR") Par(st);
    }
    out_.clear();
  }

  // ExprContext
  double Param(int n) override;
  bool ParamDefined(int n) override;
  double Letter(char c) override;
  bool ActiveCode(char gm, int code) override;

 private:
  void StepOnce();
  void Finish(Step::Kind kind);
  void Emit(Canon c);
  Canon Base(Op op) const;
  // The next output command, filled in place by the caller (the motion hot path: no Canon copies).
  Canon& EmitSlot(Op op);
  int ReportLine() const { return cur_line_; }

  // Cutter diameter compensation (cutter_comp.h): while comp_ is engaged, commands are staged in
  // comp_stage_ and handed to it (its finished commands then go to out_).
  struct CompCodes {   // G40-G46 of the block being executed (comp_codes_; reset by CompPrepare)
    bool any = false;  // one of them is in the block
    bool g43 = false, g46 = false;
    int g = 0;  // G40/G41/G42
    int g_col = 1, g46_col = 1;
  };
  void CompPrepare(const Words& words, int motion_col, bool running_cycle, bool probe, bool g92);
  Canon& CompSlot(Op op);
  void CompCommit();
  void CompEndBlock(bool counts);
  void CompFinish();
  void CompDrain();
  [[noreturn]] void CompFail(const cc::CompError& e);

  // Blocks
  void ExecBlock(std::string_view text, int line_no, size_t start);
  void ExecStatement(const Statement& st, BlockCtx& bc, bool in_ift);
  void ExecTypeI(BlockCtx& bc, const ParsedBlock* pb);
  void Define(const Statement& st, size_t level_idx);
  void DoCall(const Def& d, std::map<int, double> locals, bool is_cycle);
  void DoEnd(int col);
  void DoJump(int label, int col);
  std::optional<Def> FindDef(const std::string& name);
  std::optional<Def> LoadLibrary(const std::string& name, const std::string& text);

  // Parameters
  void SetParam(int n, double v, int col);
  void DeleteParam(int n);
  int EvalParamRef(const std::string& text, int col);
  double Eval(std::string_view text, int col);
  // 1-based column in the current block of `offset` within `text`, or `col` when `text` is not found.
  int ExprCol(std::string_view text, size_t offset, int col) const;
  bool EvalCond(const std::string& text, int col);
  std::string ExpandName(const std::string& name, int col);

  // Motion and modes
  double Offset(int axis) const;
  double ToMm(double v) const { return metric_ ? v : v * kInch; }
  double FromMm(double v) const { return metric_ ? v : v / kInch; }
  void ResetAtEnd();
  void EmitMove(const std::array<double, kAxisCount>& target, uint32_t moved, bool rapid, double feed,
                FeedMode fm, bool exact, const std::array<double, kAxisCount>& travel, uint32_t travel_mask);
  void Arc(const Words& words, bool cw, int col, double feed, FeedMode fm);
  void ApplyTool();
  void SetUnits(bool metric);

  // Statements
  void Par(const Statement& st);
  void Cls(const Statement& st, BlockCtx& bc);
  void Fwr(const Statement& st);
  void Opf(const Statement& st);
  void Tld(const Statement& st);
  void Fxc(const Statement& st, bool ufx);
  void SetFlag(int n);

  RunOptions opt_;
  Environment default_env_;
  Environment* env_;
  std::vector<Level> levels_;
  CanonQueue out_;
  cc::Compensator comp_;
  Canon comp_stage_;
  bool comp_staged_ = false;
  CompCodes comp_codes_;  // written only by blocks that have the codes: nothing to set up per block
  int comp_g_ = 40;       // modal G40/G41/G42 as programmed (IFT tests it)
  int comp_col_ = 1, comp_g_col_ = 1;
  bool finished_ = false;
  Step final_;
  bool units_emitted_ = false;
  int cur_line_ = 1;
  bool cur_own_ = true;
  long idle_ = 0;
  long max_idle_ = 1000000;

  // Modal state.
  bool metric_ = false;
  bool basic_metric_ = false;
  bool g01_ = false;
  int plane_ = 17;
  bool g20_ = false, g21_ = false;
  bool incremental_ = false;
  bool inverse_time_ = false;
  std::optional<double> feed_;  // program units
  double speed_ = 0;
  int spindle_ = 5;  // 3, 4, 5, 19
  int coolant_ = 9;
  int aux_coolant_ = 0;
  int cycle_ = 80;
  bool g28_ = false, g36_ = false, g46_ = false, g47_ = false, g48_ = false;
  int adaptive_ = 50, count_mode_ = 60;
  bool m21_ = false, m27_ = false, m29_ = false, m49_ = false, m40_ = false, m24_ = true, m51_ = false,
       m52_ = false;
  std::array<double, kAxisCount> pos_{};
  uint32_t used_ = 0;
  std::array<double, kAxisCount> g98_{};
  std::array<FixtureLine, 33> fixtures_{};
  int active_h_ = 0;
  bool mir_x_ = false, mir_y_ = false;
  double u88_x_ = 0.254, u88_y_ = 0;  // mm
  std::array<double, 26> letters_{};
  std::vector<ToolEntry> tools_;
  std::string selected_tool_, active_tool_;
  int uat_ = 0;
  double tool_len_ = 0, tool_dia_ = 0;
  int pallet_ = 0;
  bool block_delete_ = false, optional_stop_ = false, b_index_ = true;
  bool file_open_ = false, cer_mas_ = false;
  std::string fwr_pending_;
  std::array<double, 8> probe_latch_{};
  std::array<double, 6> dat_{};

  std::map<int, double> program_;  // L100-L999
  std::map<int, double> machine_;  // L1000-L2999
  // Files written by this run (OPF/OIF + FWR/MSG): an NC file written and closed can be called with CLS
  // (manual Fig 7.28). The program store keeps the real files; this is the run's own view of them.
  struct MemFile {
    std::string type;
    std::string text;
  };
  std::map<std::string, MemFile> files_;
  std::string open_file_;
  void OpenFile(const std::string& name, const std::string& type, bool append, int col);
  void WriteFile(const std::string& line);
  void CloseFile();
  std::map<std::string, Def> defs_;
  std::map<std::string, Def> lib_cache_;
  BlockCache cache_;
  std::string_view block_;  // the block being executed (diagnostic columns)
  static constexpr size_t kReleaseStep = 1 << 20;
  size_t released_ = 0;  // main program bytes before this were released
  int local_defs_ = 0;
};

KtRun::KtRun(const RunOptions& o) : env_(o.env ? o.env : &default_env_) {
  // Everything but the program text (which may be large) is kept.
  opt_.dialect = o.dialect;
  opt_.program_name = o.program_name;
  opt_.library = o.library;
  opt_.save = o.save;
  opt_.params = o.params;
  opt_.env = o.env;
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
    } else if (key == "PALLET") {
      pallet_ = static_cast<int>(std::clamp(num(0), 0.0, 999.0));
    } else if (key == "B_AXIS") {
      b_index_ = val != "ROTARY";
    } else if (key == "MAX_IDLE_BLOCKS") {
      max_idle_ = std::max(1L, static_cast<long>(num(1000000)));
    } else if (key.size() > 1 && key.size() <= 5 && key[0] == 'L' &&
               std::all_of(key.begin() + 1, key.end(), IsDigit)) {
      int n = std::stoi(key.substr(1));
      double d = num(0);
      if (n >= 1000 && n <= 2999)
        machine_[n] = d;
      else if (n >= 100 && n <= 999)
        program_[n] = d;
    }
  }
  metric_ = basic_metric_;
  tools_ = o.tools;
  auto text = o.program ? o.program : ProgramText::FromString(o.program_text);
  Level main;
  main.text = text;
  main.begin = 0;
  main.end = text->view().size();
  main.pos = 0;
  main.line = 1;
  main.begin_line = 1;
  main.report_own = true;
  levels_.push_back(std::move(main));
}

Step KtRun::Next() {
  Step s;
  NextInto(s);
  return s;
}

void KtRun::NextInto(Step& s) {
  while (out_.empty() && !finished_) StepOnce();
  if (!out_.empty()) {
    s.kind = Step::kCanon;
    s.canon = std::move(out_.front());
    out_.pop_front();
    return;
  }
  s = final_;
}

void KtRun::Finish(Step::Kind kind) {
  if (kind == Step::kEnd && comp_.engaged()) CompFinish();
  if (!units_emitted_ && kind == Step::kEnd) {
    Canon u = Base(Op::kUnits);
    u.metric = metric_;
    units_emitted_ = true;
    out_.push_back(u);
  }
  finished_ = true;
  final_.kind = kind;
}

Canon KtRun::Base(Op op) const {
  Canon c;
  c.op = op;
  c.line = cur_line_;
  return c;
}

void KtRun::Emit(Canon c) {
  EmitSlot(c.op) = std::move(c);
}

Canon& KtRun::EmitSlot(Op op) {
  if (!units_emitted_) {
    Canon u = Base(Op::kUnits);
    u.metric = metric_;
    units_emitted_ = true;
    out_.push_back(u);
  }
  idle_ = 0;
  if (comp_.engaged()) [[unlikely]]
    return CompSlot(op);
  Canon& c = out_.Slot();
  c.op = op;
  c.line = cur_line_;
  return c;
}

void KtRun::SetUnits(bool metric) {
  if (metric == metric_) return;
  metric_ = metric;
  if (units_emitted_) {
    Canon u = Base(Op::kUnits);
    u.metric = metric_;
    if (comp_.engaged()) [[unlikely]] {
      CompSlot(Op::kUnits) = u;
      return;
    }
    out_.push_back(u);
  }
}

void KtRun::StepOnce() {
  size_t li = levels_.size() - 1;
  Level& lv = levels_[li];
  if (lv.pos >= lv.end) {
    if (li == 0) {
      Finish(Step::kEnd);
    } else {
      levels_.pop_back();  // a library body without (END): implicit return
    }
    return;
  }
  std::string_view text = lv.text->view();
  size_t start = lv.pos;
  size_t nl = text.find('\n', start);
  if (nl == std::string::npos || nl > lv.end) nl = lv.end;
  std::string_view block(text.data() + start, nl - start);
  int line_no = lv.line;
  lv.pos = nl < lv.end ? nl + 1 : lv.end;
  lv.line++;
  if (li == 0 && lv.pos - released_ >= kReleaseStep) {
    // The main program runs forward: give back what it has passed (a mapped file faults back in if a GTO
    // or a call returns there).
    lv.text->Release(released_, lv.pos);
    released_ = lv.pos;
  }
  cur_own_ = lv.report_own;
  cur_line_ = lv.report_own ? line_no : lv.call_line;
  try {
    if (++idle_ > max_idle_) {
      Fail(1, fmt::format("PROGRAM RAN {} BLOCKS WITHOUT MOTION OR OUTPUT (ENDLESS LOOP?)", max_idle_));
    }
    ExecBlock(block, line_no, start);
  } catch (const RunError& e) {
    Diagnostic d;
    d.program = opt_.program_name;
    d.line = cur_line_;
    d.col = cur_own_ ? e.col : 1;
    d.alarm = e.alarm;
    d.text = e.text;
    if (!cur_own_) {
      for (size_t i = levels_.size(); i-- > 0;) {
        if (!levels_[i].report_own) {
          d.text = fmt::format("{} (in {} line {})", e.text, levels_[i].name, line_no);
          break;
        }
      }
    }
    final_.diag = d;
    Finish(Step::kError);
  } catch (const ExprError& e) {
    Diagnostic d;
    d.program = opt_.program_name;
    d.line = cur_line_;
    d.col = 1;
    d.text = e.text;
    final_.diag = d;
    Finish(Step::kError);
  }
  block_ = {};  // the view is only valid while its block runs (diagnostic columns)
}

// ---------------------------------------------------------------------------------------------------------
// Parameters

double KtRun::Param(int n) {
  if (n >= 0 && n <= 99) {
    auto& loc = levels_.back().locals;
    auto it = loc.find(n);
    if (it == loc.end()) throw ExprError{fmt::format("Error L number NOT in table (L{})", n), 0};
    return it->second;
  }
  if (n >= 100 && n <= 999) {
    auto it = program_.find(n);
    if (it == program_.end()) throw ExprError{fmt::format("Error L number NOT in table (L{})", n), 0};
    return it->second;
  }
  if (n >= 1000 && n <= 2999) {
    auto it = machine_.find(n);
    if (it == machine_.end()) throw ExprError{fmt::format("Error L number NOT in table (L{})", n), 0};
    return it->second;
  }
  if (n >= 3000 && n <= 3999) {
    static const int kAxisOrder[8] = {kX, kY, kZ, kB, kA, kC, kU, kV};
    if (n <= 3007) {
      int a = kAxisOrder[n - 3000];
      return IsRotaryAxis(a) ? pos_[a] : FromMm(pos_[a]);
    }
    if (n >= 3008 && n <= 3012) {
      int a = kAxisOrder[n - 3008];
      double v = active_h_ ? fixtures_[active_h_].v[a] : 0;
      return IsRotaryAxis(a) ? v : FromMm(v);
    }
    if (n == 3016) return FromMm(u88_x_);
    if (n == 3017) return FromMm(u88_y_);
    if (n == 3018) return FromMm(tool_dia_);
    if (n == 3020) return pallet_;
    if (n == 3030) return active_tool_.empty() ? 0 : std::atof(active_tool_.c_str());
    if (n == 3033) return FromMm(tool_len_);
    if (n >= 3042 && n <= 3049) {
      int a = kAxisOrder[n - 3042];
      double v = probe_latch_[n - 3042];
      return IsRotaryAxis(a) ? v : FromMm(v);
    }
    if (n >= 3061 && n <= 3066) return dat_[n - 3061];
    if (n == 3070) return kPi;
    if (n == 3071) return std::exp(1.0);
    if (auto v = env_->SystemParameter(n)) return *v;
    return 0;
  }
  throw ExprError{"Error L numbers range from 0..3999", 0};
}

bool KtRun::ParamDefined(int n) {
  if (n >= 0 && n <= 99) return levels_.back().locals.count(n) > 0;
  if (n >= 100 && n <= 999) return program_.count(n) > 0;
  if (n >= 1000 && n <= 2999) return machine_.count(n) > 0;
  return n >= 3000 && n <= 3999;
}

void KtRun::SetParam(int n, double v, int col) {
  if (n < 0 || n > 2999) Fail(col, "Error L numbers range from 0..2999");
  if (!std::isfinite(v) || v < -99999999.0 - 1e-6 || v > 999999999.0 + 1e-6) {
    Fail(col, fmt::format("PARAMETER VALUE OUT OF RANGE (L{})", n));
  }
  if (n <= 99) {
    levels_.back().locals[n] = v;
  } else if (n <= 999) {
    program_[n] = v;
  } else {
    machine_[n] = v;
  }
}

void KtRun::DeleteParam(int n) {
  if (n <= 99) {
    levels_.back().locals.erase(n);
  } else if (n <= 999) {
    program_.erase(n);
  } else if (n <= 2999) {
    machine_.erase(n);
  }
}

double KtRun::Letter(char c) {
  int a = AxisOfLetter(c);
  if (a >= 0) {
    double v = pos_[a] - (IsRotaryAxis(a) ? 0 : Offset(a));
    return IsRotaryAxis(a) ? v : FromMm(v);
  }
  switch (c) {
    case 'F':
      return feed_.value_or(0);
    case 'S':
      return speed_;
    case 'T':
      return selected_tool_.empty() ? 0 : std::atof(selected_tool_.c_str());
    default:
      return letters_[c - 'A'];
  }
}

bool KtRun::ActiveCode(char gm, int code) {
  if (gm == 'G') {
    switch (code) {
      case 0:
        return !g01_;
      case 1:
        return g01_;
      case 17:
      case 18:
      case 19:
        return plane_ == code;
      case 20:
        return g20_;
      case 21:
        return g21_;
      case 28:
        return g28_;
      case 29:
        return !g28_;
      case 36:
        return g36_;
      case 37:
        return !g36_;
      case 39:
        return !g47_;
      case 47:
        return g47_;
      case 40:
      case 41:
      case 42:
        return comp_g_ == code;
      case 46:
        return g46_;
      case 48:
        return g48_;
      case 49:
        return !g48_;
      case 50:
      case 51:
      case 53:
        return adaptive_ == code;
      case 60:
      case 61:
      case 62:
        return count_mode_ == code;
      case 70:
        return !metric_;
      case 71:
        return metric_;
      case 90:
        return !incremental_;
      case 91:
        return incremental_;
      case 93:
        return inverse_time_;
      case 94:
        return !inverse_time_;
      case 98: {
        for (double v : g98_) {
          if (v != 0) return true;
        }
        return false;
      }
      case 99: {
        for (double v : g98_) {
          if (v != 0) return false;
        }
        return true;
      }
      default:
        return cycle_ == code;
    }
  }
  switch (code) {
    case 3:
    case 4:
    case 5:
    case 19:
      return spindle_ == code;
    case 7:
    case 8:
    case 9:
      return coolant_ == code;
    case 57:
    case 58:
    case 59:
      return aux_coolant_ == code;
    case 20:
      return !m21_;
    case 21:
      return m21_;
    case 23:
      return !m24_;
    case 24:
      return m24_;
    case 26:
      return !m27_;
    case 27:
      return m27_;
    case 28:
      return !m29_;
    case 29:
      return m29_;
    case 40:
      return m40_;
    case 48:
      return !m49_;
    case 49:
      return m49_;
    case 51:
      return m51_;
    case 52:
      return m52_;
    default:
      return false;
  }
}

int KtRun::ExprCol(std::string_view text, size_t offset, int col) const {
  // Expression texts are views into the block or verbatim copies of part of it (statement bodies, PAR
  // fields): find them to point the diagnostic at the failing token rather than at the statement.
  if (block_.empty() || text.empty()) return col;
  const char* b = block_.data();
  size_t at = std::string_view::npos;
  if (text.data() >= b && text.data() + text.size() <= b + block_.size()) {
    at = static_cast<size_t>(text.data() - b);
  } else {
    at = block_.find(text, col > 0 ? static_cast<size_t>(col - 1) : 0);
  }
  if (at == std::string_view::npos) return col;
  return static_cast<int>(at + std::min(offset, text.size())) + 1;
}

double KtRun::Eval(std::string_view text, int col) {
  try {
    return EvalValue(text, *this);
  } catch (const ExprError& e) {
    Fail(ExprCol(text, e.offset, col), e.text);
  }
}

bool KtRun::EvalCond(const std::string& text, int col) {
  try {
    return EvalCondition(text, *this);
  } catch (const ExprError& e) {
    Fail(ExprCol(text, e.offset, col), e.text);
  }
}

int KtRun::EvalParamRef(const std::string& text, int col) {
  try {
    ExprParser p(text, *this);
    int n = p.ParamRef();
    if (!p.AtEnd()) Fail(col, "PARAMETER REFERENCE EXPECTED");
    return n;
  } catch (const ExprError& e) {
    Fail(ExprCol(text, e.offset, col), e.text);
  }
}

// <Ln>, <LnI> (truncated), <LnR> (rounded) in names.
std::string KtRun::ExpandName(const std::string& name, int col) {
  std::string out;
  for (size_t i = 0; i < name.size(); ++i) {
    if (name[i] != '<') {
      out += name[i];
      continue;
    }
    size_t close = name.find('>', i);
    if (close == std::string::npos) Fail(col, "MISSING > IN NAME");
    std::string inner = Upper(Trim(name.substr(i + 1, close - i - 1)));
    char mode = 0;
    if (!inner.empty() && (inner.back() == 'I' || inner.back() == 'R')) {
      mode = inner.back();
      inner.pop_back();
    }
    double v;
    try {
      ExprParser p(inner, *this);
      v = Param(p.ParamRef());
      if (!p.AtEnd()) Fail(col, "PARAMETER REFERENCE EXPECTED IN <>");
    } catch (const ExprError& e) {
      Fail(col, e.text);
    }
    if (mode == 'I') {
      out += fmt::format("{}", static_cast<long long>(std::trunc(v)));
    } else if (mode == 'R') {
      out += fmt::format("{}", static_cast<long long>(std::floor(v + 0.5)));
    } else {
      out += FormatKtNumber(v);
    }
    i = close;
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------------
// Blocks

void KtRun::ExecBlock(std::string_view text, int line_no, size_t start) {
  (void)line_no;
  if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
  if (text.size() + 1 > 80) Fail(80, "BLOCK EXCEEDS 80 CHARACTERS");
  block_ = text;
  std::string_view t = TrimView(text);
  if (t.empty() || t == "%") return;
  size_t li = levels_.size() - 1;
  Level& lv = levels_[li];
  ParsedBlock fresh;
  const ParsedBlock* cached = nullptr;
  bool repeats = li > 0 || lv.jumped;
  if (repeats) cached = cache_.Find(lv.text.get(), start);
  if (!cached) {
    fresh = ParseBlock(text, false);
    if (repeats) cached = &cache_.Put(lv.text, start, std::move(fresh));
  }
  const ParsedBlock& pb = cached ? *cached : fresh;
  if (pb.deleted && block_delete_) return;
  for (const auto& st : pb.stmts) {
    if (st.mnemonic == "DFS" || st.mnemonic == "DFC") {
      Define(st, li);
      return;
    }
  }
  BlockCtx bc;
  bc.words = pb.words;
  bc.items = static_cast<int>(pb.words.size() + pb.stmts.size());
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
  if (comp_.engaged()) [[unlikely]]
    CompEndBlock(!pb.words.empty() || !pb.stmts.empty());
  if (bc.jump) DoJump(*bc.jump, bc.jump_col);
  if (bc.call) DoCall(bc.call_def, bc.call_locals, false);
  if (bc.end) DoEnd(bc.end_col);
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
  Level& lv = levels_[li];
  Def d;
  d.text = lv.text;
  d.begin = lv.pos;
  d.begin_line = lv.line;
  d.report_own = lv.report_own;
  d.is_cycle = is_cycle;
  d.name = name;
  size_t def_start = lv.pos;
  // Skip to the block holding (END).
  std::string_view text = lv.text->view();
  size_t p = lv.pos;
  int line = lv.line;
  bool found = false;
  while (p < lv.end) {
    size_t nl = text.find('\n', p);
    if (nl == std::string::npos || nl > lv.end) nl = lv.end;
    std::string_view b(text.data() + p, nl - p);
    p = nl < lv.end ? nl + 1 : lv.end;
    ++line;
    for (const auto& s : FindStatements(b, nullptr)) {
      if (s.mnemonic == "END") found = true;
      if (s.mnemonic == "DFS" || s.mnemonic == "DFC") {
        Fail(st.col, "DEFINITIONS MAY NOT BE NESTED (MISSING (END)?)");
      }
    }
    if (found) break;
  }
  if (!found) Fail(st.col, fmt::format("{} {} HAS NO (END)", st.mnemonic, name));
  d.end = p;
  lv.pos = p;
  lv.line = line;
  if (!defs_.count(name)) ++local_defs_;
  defs_[name] = d;
  if (save && opt_.save) opt_.save(name, std::string(text.substr(def_start, p - def_start)));
}

std::optional<Def> KtRun::LoadLibrary(const std::string& name, const std::string& body) {
  auto text = ProgramText::FromString(body);
  Def d;
  d.text = text;
  d.report_own = false;
  d.name = name;
  d.is_cycle = name.size() > 1 && name[0] == 'G' && IsDigit(name[1]);
  // Find the (DFS,name) / (DFC,name) header; without one the whole text is the body.
  size_t p = 0;
  int line = 1;
  d.begin = 0;
  std::string_view all = text->view();
  d.end = all.size();
  while (p < all.size()) {
    size_t nl = all.find('\n', p);
    if (nl == std::string::npos) nl = all.size();
    std::string_view b(all.data() + p, nl - p);
    p = nl < all.size() ? nl + 1 : all.size();
    ++line;
    for (const auto& s : FindStatements(b, nullptr)) {
      if ((s.mnemonic == "DFS" || s.mnemonic == "DFC") &&
          Upper(Trim(SplitTopLevel(s.body, ',')[0])) == name) {
        d.begin = p;
        d.begin_line = line;
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

void KtRun::DoCall(const Def& d, std::map<int, double> locals, bool is_cycle) {
  if (static_cast<int>(levels_.size()) >= kMaxLevels) {
    Fail(1, "Error - subroutine nesting exceeds 3 levels");
  }
  Level nl;
  nl.text = d.text;
  nl.begin = d.begin;
  nl.end = d.end;
  nl.begin_line = d.begin_line;
  nl.pos = d.begin;
  nl.line = d.begin_line;
  nl.report_own = d.report_own && cur_own_ && !is_cycle;  // cycles report the calling block's line
  nl.call_line = cur_line_;
  nl.is_cycle = is_cycle;
  nl.name = d.name;
  if (!locals.count(0)) locals[0] = 1;
  nl.locals = std::move(locals);
  levels_.push_back(std::move(nl));
}

void KtRun::DoEnd(int col) {
  if (levels_.size() <= 1) Fail(col, "(END) WITHOUT A SUBROUTINE OR CYCLE");
  Level& lv = levels_.back();
  double count = lv.locals.count(0) ? lv.locals[0] - 1 : 0;
  if (count > 0) {
    lv.locals[0] = count;
    lv.pos = lv.begin;
    lv.line = lv.begin_line;
    return;
  }
  levels_.pop_back();
}

void KtRun::DoJump(int label, int col) {
  Level& lv = levels_.back();
  lv.jumped = true;
  for (auto it = lv.labels.begin(); it != lv.labels.end(); ++it) {
    if (it->first == label) {
      auto entry = *it;
      lv.labels.erase(it);
      lv.labels.insert(lv.labels.begin(), entry);
      lv.pos = entry.second.first;
      lv.line = entry.second.second;
      return;
    }
  }
  std::string_view text = lv.text->view();
  auto scan = [&](size_t from, int from_line, size_t to) -> std::optional<std::pair<size_t, int>> {
    size_t p = from;
    int line = from_line;
    bool in_def = false;
    while (p < to) {
      size_t nl = text.find('\n', p);
      if (nl == std::string::npos || nl > lv.end) nl = lv.end;
      std::string_view b(text.data() + p, nl - p);
      size_t bstart = p;
      int bline = line;
      p = nl < lv.end ? nl + 1 : lv.end;
      ++line;
      bool maybe = false;
      for (size_t k = 0; k + 2 < b.size(); ++k) {
        if (Up(b[k]) == 'L' && Up(b[k + 1]) == 'B' && Up(b[k + 2]) == 'L') maybe = true;
        if (Up(b[k]) == 'D' && Up(b[k + 1]) == 'F') maybe = true;
        if (Up(b[k]) == 'E' && Up(b[k + 1]) == 'N' && Up(b[k + 2]) == 'D') maybe = true;
      }
      if (!maybe) continue;
      for (const auto& s : FindStatements(b, nullptr)) {
        if (s.mnemonic == "DFS" || s.mnemonic == "DFC") in_def = true;
        if (s.mnemonic == "END" && in_def) {
          in_def = false;
          continue;
        }
        if (!in_def && s.mnemonic == "LBL") {
          std::string v = Trim(s.body);
          if (!v.empty() && std::all_of(v.begin(), v.end(), IsDigit) && v.size() < 6 &&
              std::stoi(v) == label) {
            return std::make_pair(bstart, bline);
          }
        }
      }
    }
    return std::nullopt;
  };
  auto hit = scan(lv.pos, lv.line, lv.end);
  if (!hit) hit = scan(lv.begin, lv.begin_line, lv.pos);
  if (!hit) Fail(col, fmt::format("Error -GTO label not found ({})", label));
  lv.labels.insert(lv.labels.begin(), {label, *hit});
  if (lv.labels.size() > 10) lv.labels.pop_back();
  lv.pos = hit->first;
  lv.line = hit->second;
}

void KtRun::SetFlag(int n) {
  if (ParamDefined(n)) machine_[n] = 1.0;
}

void KtRun::ExecStatement(const Statement& st, BlockCtx& bc, bool in_ift) {
  std::string_view m = st.mnemonic;  // compared with literals: no strlen
  if (st.body.size() > 73) Fail(st.col, "TYPE II STATEMENT EXCEEDS 73 CHARACTERS");
  if (m == "PAR") {
    Par(st);
  } else if (m == "IFT") {
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
      ab = ParseBlock(action, true);
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
  } else if (m == "GTO") {
    std::string v = Trim(st.body);
    if (v.empty() || v.size() > 4 || !std::all_of(v.begin(), v.end(), IsDigit) || std::stoi(v) < 1) {
      Fail(st.col, "GTO LABEL MUST BE 1-9999");
    }
    bc.jump = std::stoi(v);
    bc.jump_col = st.col;
    bc.gto_count++;
  } else if (m == "LBL") {
    std::string v = Trim(st.body);
    if (v.empty() || v.size() > 4 || !std::all_of(v.begin(), v.end(), IsDigit) || std::stoi(v) < 1) {
      Fail(st.col, "LBL LABEL MUST BE 1-9999");
    }
  } else if (m == "END") {
    bc.end = true;
    bc.end_col = st.col;
  } else if (m == "CLS") {
    Cls(st, bc);
  } else if (m == "DLP") {
    for (const auto& f : SplitTopLevel(st.body, ',')) {
      std::string r = Trim(f);
      if (r.empty()) continue;
      DeleteParam(EvalParamRef(r, st.col));
    }
  } else if (m == "NAM" || m == "UTL" || m == "UCY" || m == "ACP" || m == "SSA") {
    // Heading / option data: no effect on the run (read by the program store and scheduler).
  } else if (m == "MSG") {
    std::string body = st.body;
    auto parts = SplitTopLevel(body, ',');
    if (parts.size() >= 2 && Upper(Trim(parts[0])) == "NAM") {
      if (!g36_) Fail(st.col, "(MSG,NAM,...) NEEDS G36");
      Canon c = Base(Op::kFileOpen);
      c.text = ExpandName(Trim(body.substr(parts[0].size() + 1)), st.col);
      c.text2 = "AS";
      c.code = 1;
      OpenFile(c.text, "AS", false, st.col);
      file_open_ = true;
      Emit(std::move(c));
      return;
    }
    Canon c = Base(Op::kMessage);
    c.text = Trim(body);
    Emit(c);  // copied: the file write below repeats the text
    if (file_open_) {
      Canon w = Base(Op::kFileWrite);
      w.text = c.text.substr(0, 80);
      WriteFile(w.text);
      Emit(w);
      w.text = "";
      WriteFile(w.text);
      Emit(w);
    }
  } else if (m == "OIF") {
    if (!g36_) Fail(st.col, "OIF NEEDS G36 IN THE BLOCK BEFORE");
    Canon c = Base(Op::kFileOpen);
    c.text = ExpandName(Trim(st.body), st.col);
    if (c.text.empty() || c.text.size() > 32) Fail(st.col, "FILE NAME MUST HAVE 1-32 CHARACTERS");
    c.text2 = "AS";
    c.code = 1;
    OpenFile(c.text, "AS", false, st.col);
    file_open_ = true;
    Emit(std::move(c));
  } else if (m == "OPF") {
    Opf(st);
  } else if (m == "CLF") {
    if (file_open_) Emit(Base(Op::kFileClose));
    file_open_ = false;
    CloseFile();
    SetFlag(1050);
  } else if (m == "FWR") {
    Fwr(st);
  } else if (m == "DAT") {
    auto now = env_->Now();
    for (int i = 0; i < 6; ++i) dat_[i] = now[i];
  } else if (m == "CPY" || m == "DLF" || m == "PRT" || m == "RCP" || m == "USF" || m == "ULF") {
    Canon c = Base(Op::kFileOp);
    c.text2 = Upper(m);
    std::string args = st.body;
    if (m == "USF" || m == "ULF") {
      std::string name = ExpandName(Trim(args), st.col);
      if (name.empty()) name = fmt::format("PALLET{:02d}", pallet_);
      if (name.size() > 28) Fail(st.col, "FIXTURE TABLE FILE NAME EXCEEDS 28 CHARACTERS");
      args = name + ";FXT";
    } else {
      auto parts = SplitTopLevel(args, ',', true);
      args.clear();
      for (size_t i = 0; i < parts.size(); ++i) {
        if (i) args += ',';
        args += ExpandName(Trim(parts[i]), st.col);
      }
    }
    c.text = args;
    Emit(c);  // copied: the environment is asked about the same operation
    bool done = env_->FileOperation(c);
    if (done) {
      if (m == "DLF") {
        files_.erase(Upper(Trim(SplitTopLevel(args, '/')[0])));
        SetFlag(1051);
      }
      if (m == "PRT") SetFlag(1052);
      if (m == "CPY") SetFlag(1053);
      if (m == "RCP") SetFlag(1054);
    }
  } else if (m == "CER" || m == "SER") {
    for (const auto& f : SplitTopLevel(st.body, ',')) {
      std::string k = Upper(Trim(f));
      if (k != "MAS" && k != "SEQ" && k != "REM") Fail(st.col, "TYPE II COMMAND SYNTAX ERROR");
      if (k == "MAS") cer_mas_ = (m == "CER");
    }
  } else if (m == "SET" || m == "WAI") {
    auto parts = SplitTopLevel(st.body, ',');
    int bits = 0;
    for (const auto& p : parts) bits += Trim(p).find('=') != std::string::npos ? 1 : 0;
    if (bits > 8) Fail(st.col, fmt::format("{} ALLOWS AT MOST 8 BITS", m));
    Canon c = Base(m == "SET" ? Op::kOutput : Op::kWaitInput);
    std::string spec;
    for (char ch : st.body) {
      if (ch != ' ') spec += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    }
    c.text = st.has_body ? spec : "SAVE";
    Emit(c);  // copied: the wait below still reads the spec
    if (m == "WAI") env_->WaitInputs(c.text);
  } else if (m == "TLD") {
    Tld(st);
  } else if (m == "FXC" || m == "UFX") {
    Fxc(st, m == "UFX");
  } else if (m == "ZTB") {
    if (!st.has_body) Fail(st.col, "ZTB NEEDS A COMMA AND T AND/OR H");
    for (const auto& f : SplitTopLevel(st.body, ',')) {
      std::string k = Upper(Trim(f));
      if (k == "T") {
        tools_.clear();
        Canon c = Base(Op::kToolData);
        c.text = "*";
        Emit(std::move(c));
      } else if (k == "H") {
        fixtures_ = {};
        active_h_ = 0;
      } else {
        Fail(st.col, "ZTB TABLES ARE T AND H");
      }
    }
  } else if (m == "MIR") {
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
  } else if (m == "U88") {
    std::string b = Upper(st.body);
    b.erase(std::remove(b.begin(), b.end(), ','), b.end());
    ParsedBlock pb = ParseBlock(b, true);
    for (const auto& w : pb.words) {
      double v =
          w.kind == WordKind::kNumber
              ? ScaleLiteral(w.letter, w.num, metric_, false, false)
              : (w.kind == WordKind::kExpr ? Eval(w.expr, st.col)
                                           : Param(w.param) * (w.kind == WordKind::kNegParam ? -1 : 1));
      if (w.letter == 'X')
        u88_x_ = ToMm(v);
      else if (w.letter == 'Y')
        u88_y_ = ToMm(v);
      else
        Fail(st.col, "U88 TAKES X AND Y");
    }
  } else if (m == "UAT") {
    std::string v = Trim(st.body);
    if (v.size() != 1 || v[0] < '0' || v[0] > '7') Fail(st.col, "UAT SUFFIX MUST BE 0-7");
    // ln 6179: G40 must be modal to invoke a suffix compensation.
    if (comp_g_ != 40) Fail(st.col, "G40 must be modal in order to invoke a Suffix Compensation (UAT)");
    uat_ = v[0] - '0';
    ApplyTool();
  } else if (m == "EVT") {
    Canon c = Base(Op::kEvent);
    c.text = Trim(st.body);
    Emit(std::move(c));
  } else {
    Fail(st.col, "TYPE II COMMAND SYNTAX ERROR");
  }
}

void KtRun::OpenFile(const std::string& name, const std::string& type, bool append, int col) {
  std::string key = Upper(name);
  CloseFile();
  auto it = files_.find(key);
  if (it != files_.end() && it->second.type != type) Fail(col, "FILE ALREADY EXISTS");
  MemFile& f = files_[key];
  f.type = type;
  if (!append) f.text.clear();
  open_file_ = key;
}

void KtRun::WriteFile(const std::string& line) {
  if (open_file_.empty()) return;
  files_[open_file_].text += line + "\n";
}

void KtRun::CloseFile() {
  open_file_.clear();
}

void KtRun::Par(const Statement& st) {
  auto parts = SplitTopLevel(st.body, ',');
  if (parts.size() > 12) Fail(st.col, "Error - exceeds 12 assignments in PAR");
  for (const auto& raw : parts) {
    std::string a = raw;
    // Optional "description" after the expression.
    size_t q = a.find('"');
    if (q != std::string::npos) {
      size_t q2 = a.find('"', q + 1);
      if (q2 == std::string::npos) Fail(st.col, "MISSING \" IN PARAMETER DESCRIPTION");
      if (q2 - q - 1 > 20) Fail(st.col, "PARAMETER DESCRIPTION EXCEEDS 20 CHARACTERS");
      if (!Trim(a.substr(q2 + 1)).empty()) Fail(st.col, "TEXT AFTER PARAMETER DESCRIPTION");
      a = a.substr(0, q);
    }
    size_t eq = std::string::npos;
    int depth = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      if (a[i] == '(') ++depth;
      if (a[i] == ')') --depth;
      if (a[i] == '=' && depth == 0) {
        eq = i;
        break;
      }
    }
    if (eq == std::string::npos) Fail(st.col, "PAR ASSIGNMENT NEEDS Ln = expression");
    int n = EvalParamRef(Trim(a.substr(0, eq)), st.col);
    if (n > 2999) Fail(st.col, "Error L numbers range from 0..2999");
    double v = Eval(a.substr(eq + 1), st.col);
    SetParam(n, v, st.col);
  }
}

void KtRun::Cls(const Statement& st, BlockCtx& bc) {
  for (const auto& l : levels_) {
    if (l.is_cycle) Fail(st.col, "A RUNNING DEFINED CYCLE CANNOT CALL A SUBROUTINE");
  }
  auto parts = SplitTopLevel(st.body, ',', true);
  std::string name = Upper(ExpandName(Trim(parts[0]), st.col));
  if (name.empty()) Fail(st.col, "CLS NEEDS A SUBROUTINE NAME");
  if (parts.size() - 1 > 12) Fail(st.col, "Error - exceeds 12 L's");
  std::map<int, double> locals;
  std::optional<double> literal_count;
  for (size_t i = 1; i < parts.size(); ++i) {
    std::string f = Trim(parts[i]);
    if (i == 1 && !f.empty() && (IsDigit(f[0]) || f[0] == '.')) {
      try {
        literal_count = Eval(f, st.col);
      } catch (...) {
        Fail(st.col, "CLS RUN COUNT MUST BE A NUMBER");
      }
      continue;
    }
    size_t q = f.find('"');
    if (q != std::string::npos) f = f.substr(0, q);
    size_t eq = std::string::npos;
    int depth = 0;
    for (size_t k = 0; k < f.size(); ++k) {
      if (f[k] == '(') ++depth;
      if (f[k] == ')') --depth;
      if (f[k] == '=' && depth == 0) {
        eq = k;
        break;
      }
    }
    if (eq == std::string::npos) Fail(st.col, "CLS PARAMETER NEEDS Ln = expression");
    int n = EvalParamRef(Trim(f.substr(0, eq)), st.col);
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
  bc.call = true;
  bc.call_def = *d;
  bc.call_def.name = name;
  bc.call_locals = std::move(locals);
  bc.call_col = st.col;
}

void KtRun::Opf(const Statement& st) {
  auto parts = SplitTopLevel(st.body, ',', true);
  std::string name = Trim(parts[0]);
  std::string type = "AS";
  bool append = false;
  auto take_type = [&](std::string& s) {
    size_t slash = s.rfind('/');
    if (slash != std::string::npos && s.find('>', slash) == std::string::npos) {
      type = Upper(Trim(s.substr(slash + 1)));
      s = Trim(s.substr(0, slash));
    }
  };
  take_type(name);
  for (size_t i = 1; i < parts.size(); ++i) {
    std::string f = Upper(Trim(parts[i]));
    if (!f.empty() && f[0] == 'A' && (f.size() == 1 || f[1] == '/')) {
      append = true;
      if (f.size() > 1) type = Trim(f.substr(2));
    } else if (f == "AS" || f == "NC" || f == "ASCII") {
      type = f;
    } else {
      type = f;
    }
  }
  if (type == "ASCII") type = "AS";
  if (type != "AS" && type != "NC") Fail(st.col, "ERROR - MUST BE EITHER NC prog OR ASCII");
  Canon c = Base(Op::kFileOpen);
  c.text = ExpandName(name, st.col);
  if (c.text.empty() || c.text.size() > 32) Fail(st.col, "FILE NAME MUST HAVE 1-32 CHARACTERS");
  c.text2 = type;
  c.flag = append;
  OpenFile(c.text, type, append, st.col);
  file_open_ = true;
  Emit(std::move(c));
}

void KtRun::Fwr(const Statement& st) {
  if (!file_open_) {
    if (cer_mas_) return;
    Fail(st.col, "PROCESS INSPECTION FILE NOT NAMED");
  }
  std::string body = st.body;
  bool cont = false;
  std::string tb = Trim(body);
  if (!tb.empty() && tb.back() == ';') {
    cont = true;
    tb.pop_back();
  }
  std::string line = fwr_pending_;
  // Fields: "text", Ln / LnI / LnR, or an axis letter; separated by commas (or simply adjacent).
  size_t i = 0;
  while (i < tb.size()) {
    char c = tb[i];
    if (c == ' ' || c == ',') {
      ++i;
      continue;
    }
    if (c == '"') {
      ++i;
      while (i < tb.size()) {
        if (tb[i] == '"') {
          if (i + 1 < tb.size() && tb[i + 1] == '"') {
            line += '"';
            i += 2;
            continue;
          }
          break;
        }
        line += tb[i++];
      }
      if (i >= tb.size()) Fail(st.col, "MISSING \" IN FWR TEXT");
      ++i;
      continue;
    }
    char u = Up(c);
    if (u == 'L' && i + 1 < tb.size() && (IsDigit(tb[i + 1]) || tb[i + 1] == '(')) {
      size_t j = i + 1;
      if (tb[j] == '(') {
        int depth = 0;
        for (; j < tb.size(); ++j) {
          if (tb[j] == '(') ++depth;
          if (tb[j] == ')' && --depth == 0) {
            ++j;
            break;
          }
        }
      } else {
        while (j < tb.size() && IsDigit(tb[j])) ++j;
      }
      int n = EvalParamRef(tb.substr(i, j - i), st.col);
      double v;
      try {
        v = Param(n);
      } catch (const ExprError& e) {
        Fail(st.col, e.text);
      }
      char mode = j < tb.size() ? Up(tb[j]) : 0;
      if (mode == 'I') {
        line += fmt::format("{}", static_cast<long long>(std::trunc(v)));
        ++j;
      } else if (mode == 'R') {
        line += fmt::format("{}", static_cast<long long>(std::floor(v + 0.5)));
        ++j;
      } else {
        line += FormatKtNumber(v);
      }
      i = j;
      continue;
    }
    if (AxisOfLetter(u) >= 0) {
      line += FormatKtNumber(Letter(u));
      ++i;
      continue;
    }
    Fail(st.col, "FWR FIELD MUST BE \"text\", A PARAMETER OR AN AXIS LETTER");
  }
  if (cont) {
    fwr_pending_ = line;
    return;
  }
  fwr_pending_.clear();
  Canon w = Base(Op::kFileWrite);
  w.text = line.substr(0, 80);
  WriteFile(w.text);
  Emit(w);
}

std::string ToolName(double v) {
  double ip = std::trunc(v + (v >= 0 ? 1e-9 : -1e-9));
  int suffix = static_cast<int>(std::floor((v - ip) * 10 + 0.5));
  if (suffix <= 0) return fmt::format("{}", static_cast<long long>(ip));
  return fmt::format("{}.{}", static_cast<long long>(ip), suffix);
}

void KtRun::Tld(const Statement& st) {
  std::string b = st.body;
  b.erase(std::remove(b.begin(), b.end(), ' '), b.end());
  ToolEntry e;
  bool have_t = false, has_p = false, has_d = false, has_s = false, has_l = false, has_h = false;
  size_t i = 0;
  auto number = [&](char letter, bool allow_param) -> double {
    bool neg = false;
    if (i < b.size() && (b[i] == '-' || b[i] == '+')) neg = b[i++] == '-';
    if (i < b.size() && Up(b[i]) == 'L') {
      if (!allow_param) Fail(st.col, "Input Source Error");
      size_t j = i + 1;
      while (j < b.size() && IsDigit(b[j])) ++j;
      int n = EvalParamRef(b.substr(i, j - i), st.col);
      i = j;
      double v;
      try {
        v = Param(n);
      } catch (const ExprError& er) {
        Fail(st.col, er.text);
      }
      return neg ? -v : v;
    }
    RawNum r;
    r.neg = neg;
    double v = 0;
    int digits = 0;
    while (i < b.size() && IsDigit(b[i])) {
      v = v * 10 + (b[i++] - '0');
      ++digits;
    }
    if (i < b.size() && b[i] == '.') {
      r.point = true;
      ++i;
      double sc = 0.1;
      while (i < b.size() && IsDigit(b[i])) {
        v += (b[i++] - '0') * sc;
        sc /= 10;
        ++digits;
      }
    }
    if (digits == 0) Fail(st.col, fmt::format("TLD: NUMBER EXPECTED AFTER {}", letter));
    if (digits > 9) Fail(st.col, fmt::format("TLD: TOO MANY DIGITS AFTER {}", letter));
    r.as_written = v;
    if (letter == 'P' || letter == 'D') return ScaleLiteral('X', r, metric_, false, false);
    return neg ? -v : v;
  };
  while (i < b.size()) {
    char c = Up(b[i++]);
    switch (c) {
      case 'S':
        e.socket = static_cast<int>(number('S', false));
        has_s = true;
        break;
      case 'T': {
        double v = number('T', true);
        e.tool = ToolName(v);
        have_t = true;
        break;
      }
      case 'C':
        e.check = true;
        break;
      case 'M':
        e.manual = true;
        break;
      case 'B':
        e.broken = true;
        break;
      case 'E':
        e.worn = true;
        break;
      case 'W':
        e.pallet = static_cast<int>(number('W', false));
        break;
      case 'P':
        e.length = ToMm(number('P', true));
        has_p = true;
        break;
      case 'D':
        e.diameter = ToMm(number('D', true));
        has_d = true;
        break;
      case 'L': {
        int hhmm = static_cast<int>(number('L', false));
        if (hhmm % 100 > 59 || hhmm > 9959) Fail(st.col, "TLD TOOL LIFE IS hhmm (MINUTES <= 59)");
        e.life_min = (hhmm / 100) * 60 + hhmm % 100;
        has_l = true;
        break;
      }
      case 'H':
        e.max_hp = number('H', false);
        has_h = true;
        break;
      default:
        Fail(st.col, fmt::format("Input Source Error (TLD letter {})", c));
    }
  }
  if (!have_t) Fail(st.col, "TLD NEEDS A T WORD");
  auto it = std::find_if(tools_.begin(), tools_.end(),
                         [&](const ToolEntry& t) { return t.tool == e.tool && t.pallet == e.pallet; });
  if (e.pallet) {
    bool primary = std::any_of(tools_.begin(), tools_.end(),
                               [&](const ToolEntry& t) { return t.tool == e.tool && t.pallet == 0; });
    if (!primary) Fail(st.col, "PROCESS COMPENSATION NEEDS A PRIMARY OR SUFFIX ENTRY FIRST");
  }
  if (it == tools_.end()) {
    tools_.push_back(e);
    it = tools_.end() - 1;
  } else {
    if (has_s) it->socket = e.socket;
    if (has_p) it->length = e.length;
    if (has_d) it->diameter = e.diameter;
    if (has_l) it->life_min = e.life_min;
    if (has_h) it->max_hp = e.max_hp;
    it->check = it->check || e.check;
    it->manual = it->manual || e.manual;
    it->broken = it->broken || e.broken;
    it->worn = it->worn || e.worn;
  }
  Canon c = Base(Op::kToolData);
  c.text = it->tool;
  c.value = it->length;
  c.value2 = it->diameter;
  Emit(std::move(c));
  ApplyTool();
}

void KtRun::ApplyTool() {
  tool_len_ = tool_dia_ = 0;
  if (active_tool_.empty()) return;
  std::string key = active_tool_;
  if (uat_ > 0) key += "." + std::to_string(uat_);
  for (const auto& t : tools_) {
    if (t.tool == key && t.pallet == 0) {
      tool_len_ = t.length;
      tool_dia_ = t.diameter;
    }
  }
  for (const auto& t : tools_) {
    if (t.tool == key && t.pallet != 0 && t.pallet == pallet_) {
      tool_len_ += t.length;
      tool_dia_ += t.diameter;
    }
  }
}

void KtRun::Fxc(const Statement& st, bool ufx) {
  std::string b = Upper(st.body);
  b.erase(std::remove(b.begin(), b.end(), ' '), b.end());
  b.erase(std::remove(b.begin(), b.end(), ','), b.end());
  ParsedBlock pb;
  try {
    pb = ParseBlock(b, true);
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

// ---------------------------------------------------------------------------------------------------------
// Type I execution

double KtRun::Offset(int axis) const {
  double o = g98_[axis];
  if (active_h_ > 0) o += fixtures_[active_h_].v[axis];
  if (axis == kZ) o += tool_len_;
  return o;
}

void KtRun::ResetAtEnd() {
  g01_ = false;
  plane_ = 17;
  g20_ = g21_ = false;
  incremental_ = false;
  inverse_time_ = false;
  g46_ = g47_ = false;
  comp_g_ = 40;
  m21_ = m27_ = m29_ = m51_ = m52_ = false;
  coolant_ = 9;
  aux_coolant_ = 0;
  spindle_ = 5;
  u88_x_ = 0.254;
  u88_y_ = 0;
  cycle_ = 80;
  program_.clear();
  for (auto& l : levels_) l.locals.clear();
}

void KtRun::EmitMove(const std::array<double, kAxisCount>& target, uint32_t moved, bool rapid, double feed,
                     FeedMode fm, bool exact, const std::array<double, kAxisCount>& travel,
                     uint32_t travel_mask) {
  used_ |= moved;
  bool change = false;
  for (int a = 0; a < kAxisCount; ++a) {
    if ((moved & (1u << a)) && std::fabs(target[a] - pos_[a]) > 1e-9) change = true;
  }
  if (travel_mask) change = true;
  if (!change) return;
  for (int a = 0; a < kAxisCount; ++a) {
    if (moved & (1u << a)) pos_[a] = target[a];
  }
  Canon& c = EmitSlot(rapid ? Op::kRapid : Op::kLinear);
  c.pos = pos_;
  c.used = used_;
  c.travel = travel;
  c.travel_mask = travel_mask;
  if (!rapid) {
    c.feed = feed;
    c.f_mode = fm;
    c.exact_stop = exact;
  }
}

// ---------------------------------------------------------------------------------------------------------
// Cutter diameter compensation G40/G41/G42/G43/G46 (manual ln 1599-1676, 6437-6696): the geometry and the
// one-block look-ahead are in cutter_comp.h; here the block's codes are checked and handed over.

void KtRun::CompPrepare(const Words& words, int motion_col, bool running_cycle, bool probe, bool g92) {
  const CompCodes k = comp_codes_;
  comp_codes_ = CompCodes();
  comp_col_ = motion_col;
  comp_g_col_ = k.g ? k.g_col : 1;
  bool set = k.g == 41 || k.g == 42;
  // G46 goes in the G41/G42 block and lasts until the next G41/G42 unless repeated there (ln 1658-1676).
  if (k.g46 && !set) Fail(k.g46_col, "G46 MUST BE ENTERED IN THE SAME BLOCK AS G41 OR G42");
  if (set) {
    g46_ = k.g46;
    comp_.SetBypass(g46_);
  }
  // The plane's axes as in Arc (App. H: G18 is Z, X; G20/G21 substitute the co-axes).
  int p1 = plane_ == 17 ? kX : (plane_ == 18 ? kZ : kY);
  int p2 = plane_ == 17 ? kY : (plane_ == 18 ? kX : kZ);
  auto coaxis = [](int a) { return a == kX ? kU : (a == kY ? kV : kW); };
  if (g20_) p1 = coaxis(p1);
  if (g21_) p2 = coaxis(p2);
  if (set || (comp_.on() && k.g != 40)) {
    // Compensation is in effect through this block.
    if (comp_.on() && (p1 != comp_.p1() || p2 != comp_.p2())) {
      Fail(1, "THE PLANE CANNOT CHANGE WITH G41/G42 IN EFFECT");
    }
    if (cycle_ != 80 && !running_cycle) Fail(1, "FIXED CYCLES ARE NOT ALLOWED WITH G41/G42 IN EFFECT");
    if (probe) Fail(1, "PROBE MOVES ARE NOT ALLOWED WITH G41/G42 IN EFFECT");
    if (g92) Fail(1, "G92 IS NOT ALLOWED WITH G41/G42 IN EFFECT");
    for (const auto& w : words) {
      if (w.letter != 'M') continue;
      // ln 6523: G40 must precede the next tool change.
      if (w.v == 6) Fail(w.col, "An automatic tool change cannot be programmed with G41 or G42 in effect");
      if (w.v != 25) continue;
      for (const auto& a : words) {
        int ax = AxisOfLetter(a.letter);
        if (ax == p1 || ax == p2)
          Fail(w.col, "M25 MAY NOT MOVE THE COMPENSATION PLANE WITH G41/G42 IN EFFECT");
      }
    }
  }
  if (set) {
    int side = k.g == 41 ? cc::kLeft : cc::kRight;
    // Inverting exactly one axis of the plane swaps G41 and G42 (ln 5354-5355).
    if (((p1 == kX || p2 == kX) && mir_x_) != ((p1 == kY || p2 == kY) && mir_y_)) side = -side;
    double r = tool_dia_ / 2;
    if (r < 0) {  // preset tooling, a smaller cutter than programmed (ln 6447): the other side
      r = -r;
      side = -side;
    }
    if (comp_.on()) {
      comp_.SetSide(side, k.g);
    } else {
      cc::Compensator::Setup s;
      s.p1 = p1;
      s.p2 = p2;
      s.radius = r;
      s.side = side;
      s.pos = pos_;
      s.min_move = metric_ ? 0.001 : 0.0001 * kInch;  // ln 1617, 6466
      s.g = k.g;
      used_ |= (1u << p1) | (1u << p2);  // the offset moves both axes of the plane
      comp_.RampOn(s);
    }
    comp_g_ = k.g;
  } else if (k.g == 40) {
    comp_.Cancel();
    comp_g_ = 40;
  }
  if (k.g43) comp_.Perpendicular();
}

Canon& KtRun::CompSlot(Op op) {
  if (comp_staged_) CompCommit();
  comp_stage_.Reset();
  comp_stage_.op = op;
  comp_stage_.line = cur_line_;
  comp_staged_ = true;
  return comp_stage_;
}

void KtRun::CompCommit() {
  comp_staged_ = false;
  try {
    comp_.Take(std::move(comp_stage_));
  } catch (const cc::CompError& e) {
    CompFail(e);
  }
  CompDrain();
}

void KtRun::CompEndBlock(bool counts) {
  if (comp_staged_) CompCommit();
  try {
    comp_.EndBlock(counts);
  } catch (const cc::CompError& e) {
    CompFail(e);
  }
  CompDrain();
  comp_col_ = comp_g_col_ = 1;
}

void KtRun::CompFinish() {
  if (comp_staged_) CompCommit();
  comp_.Finish();
  CompDrain();
}

void KtRun::CompDrain() {
  auto& ready = comp_.Ready();
  for (auto& c : ready) out_.push_back(std::move(c));
  ready.clear();
}

void KtRun::CompFail(const cc::CompError& e) {
  int col = e.at == cc::CompError::kAtCode ? comp_g_col_ : (e.at == cc::CompError::kAtMotion ? comp_col_ : 1);
  Fail(col, e.text, e.alarm);
}

void KtRun::ExecTypeI(BlockCtx& bc, const ParsedBlock* pb) {
  const auto& raw = bc.words;
  if (raw.empty()) return;
  bool g78 = false;
  for (const auto& w : raw) {
    if (w.letter == 'G' && w.kind == WordKind::kNumber && !w.num.point && w.num.as_written == 78) g78 = true;
  }
  auto eval_raw = [&](const RawWord& w, bool dwell, bool passing, bool& dropped) -> Word {
    Word r;
    r.letter = w.letter;
    r.col = w.col;
    dropped = false;
    try {
      switch (w.kind) {
        case WordKind::kNumber:
          r.literal = true;
          r.v = ScaleLiteral(w.letter, w.num, metric_, dwell, passing);
          r.neg_zero = w.num.neg && w.num.as_written == 0;
          return r;
        case WordKind::kParam:
          r.v = Param(w.param);
          break;
        case WordKind::kNegParam:
          r.v = -Param(w.param);
          break;
        case WordKind::kExpr:
          r.v = EvalValue(w.expr, *this);
          break;
      }
    } catch (const ExprError& e) {
      if (g78 && e.text.rfind("Error L number NOT in table", 0) == 0) {
        dropped = true;
        return r;
      }
      Fail(w.kind == WordKind::kExpr ? ExprCol(w.expr, e.offset, w.col) : w.col, e.text);
    }
    if (IntegerLetter(w.letter)) r.v = std::floor(r.v + 0.5);
    return r;
  };

  // G codes first: they decide the units and the cycle mode of the block.
  InlineVec<GWord, kMaxWords> gs;  // fits: one per raw word
  for (const auto& w : raw) {
    if (w.letter != 'G') continue;
    bool dropped;
    Word g = eval_raw(w, false, false, dropped);
    if (dropped) continue;
    if (g.v < 0 || g.v > 999) Fail(w.col, "ILLEGAL G CODE");
    gs.push_back({static_cast<int>(g.v), w.col});
  }
  bool has70 = false, has71 = false;
  for (auto [g, col] : gs) {
    has70 |= g == 70;
    has71 |= g == 71;
    (void)col;
  }
  if (has70 && has71) Fail(gs.front().second, "G70 AND G71 CANNOT BE IN THE SAME BLOCK");
  if (has70) SetUnits(false);
  if (has71) SetUnits(true);
  if (!units_emitted_) {
    // The run's unit mode at start: the basic state, or the G70/G71 of the first Type I block.
    Canon u = Base(Op::kUnits);
    u.metric = metric_;
    units_emitted_ = true;
    out_.push_back(u);
  }

  bool running_cycle = std::any_of(levels_.begin(), levels_.end(), [](const Level& l) { return l.is_cycle; });
  // Does this block run in G800-series passing mode?
  int new_cycle = cycle_;
  for (auto [g, col] : gs) {
    (void)col;
    if (g == 80 || g == 800) new_cycle = 80;
    if ((g >= 81 && g <= 89) || (g >= 801 && g <= 899)) new_cycle = g;
  }
  bool g77 = std::any_of(gs.begin(), gs.end(), [](auto p) { return p.first == 77; });
  bool pass800 = !running_cycle && !g77 && new_cycle >= 801;

  bool dwell = std::any_of(gs.begin(), gs.end(), [](auto p) { return p.first == 4; });
  Words words;
  for (const auto& w : raw) {
    if (w.letter == 'G') continue;
    bool dropped;
    Word r = eval_raw(w, dwell, false, dropped);
    if (!dropped) words.push_back(r);
  }

  // Apply G codes.
  int arc = 0, arc_col = 1;
  bool g92 = false, g98 = false, g99 = false, probe = false;
  int probe_g = 0, probe_cycle = 0;
  bool plane_set = false, b20 = false, b21 = false;
  InlineVec<GWord, kMaxWords> passed_g;
  for (auto [g, col] : gs) {
    if (pass800 && !(g == 77 || g == 78 || g == 70 || g == 71 || g == 80 || g == 800 ||
                     (g >= 801 && g <= 899) || (g >= 81 && g <= 89))) {
      passed_g.push_back({g, col});
      continue;
    }
    switch (g) {
      case 0:
        g01_ = false;
        break;
      case 1:
        g01_ = true;
        break;
      case 2:
      case 3:
        arc = g;
        arc_col = col;
        break;
      case 4:
        break;
      case 17:
      case 18:
      case 19:
        plane_ = g;
        plane_set = true;
        break;
      case 20:
        b20 = true;
        break;
      case 21:
        b21 = true;
        break;
      case 22:
      case 23:
        probe = true;
        probe_g = g;
        break;
      case 24:
      case 25:
      case 26:
      case 27:
        probe_cycle = g;
        break;
      case 28:
        g28_ = true;
        break;
      case 29:
        g28_ = false;
        break;
      case 36:
        g36_ = true;
        break;
      case 37:
        if (file_open_) Emit(Base(Op::kFileClose));
        file_open_ = false;
        CloseFile();
        g36_ = false;
        break;
      case 38: {
        Canon c = Base(Op::kProbe);
        c.code = 38;
        c.pos = pos_;
        c.used = used_;
        c.text = "tool_ok";
        Emit(std::move(c));
        break;
      }
      case 39:
        g47_ = false;
        break;
      case 47:
        g47_ = true;
        break;
      case 40:
      case 41:
      case 42:
        if (comp_codes_.g && comp_codes_.g != g) Fail(col, "G40, G41 AND G42 CANNOT BE IN THE SAME BLOCK");
        comp_codes_.any = true;
        comp_codes_.g = g;
        comp_codes_.g_col = col;
        break;
      case 43:
        comp_codes_.any = comp_codes_.g43 = true;
        break;
      case 44:
        break;
      case 46:
        comp_codes_.any = comp_codes_.g46 = true;
        comp_codes_.g46_col = col;
        break;
      case 48:
        g48_ = true;
        break;
      case 49:
        g48_ = false;
        break;
      case 50:
      case 51:
      case 53:
        adaptive_ = g;
        break;
      case 52:
      case 79:
        break;
      case 60:
      case 61:
      case 62:
        count_mode_ = g;
        if (g != 60) machine_[1022] = 0;
        break;
      case 70:
      case 71:
      case 77:
      case 78:
        break;
      case 80:
      case 800:
        cycle_ = 80;
        for (auto it = program_.lower_bound(800); it != program_.end() && it->first <= 899;) {
          it = program_.erase(it);
        }
        break;
      case 90:
        incremental_ = false;
        break;
      case 91:
        incremental_ = true;
        break;
      case 92:
        g92 = true;
        break;
      case 93:
        inverse_time_ = true;
        break;
      case 94:
        inverse_time_ = false;
        break;
      case 98:
        g98 = true;
        break;
      case 99:
        g99 = true;
        break;
      default:
        if ((g >= 81 && g <= 89) || (g >= 801 && g <= 899)) {
          if (running_cycle) Fail(col, "A RUNNING DEFINED CYCLE CANNOT CALL ANOTHER CYCLE");
          if (plane_ != 17 && g <= 89) Fail(col, "FIXED CYCLES WORK ONLY IN G17");
          cycle_ = g;
          break;
        }
        Fail(col, fmt::format("ILLEGAL G CODE G{}", g));
    }
  }
  if (plane_set) {
    g20_ = b20;
    g21_ = b21;
  } else {
    if (b20) g20_ = true;
    if (b21) g21_ = true;
  }

  // Collect the other words.
  auto find = [&](char l) -> const Word* {
    const Word* r = nullptr;
    for (const auto& w : words) {
      if (w.letter == l) r = &w;
    }
    return r;
  };
  std::vector<const Word*> ms;
  uint32_t axis_mask = 0;
  for (const auto& w : words) {
    if (w.letter == 'M') ms.push_back(&w);
    int a = AxisOfLetter(w.letter);
    if (a >= 0) axis_mask |= 1u << a;
    if (w.letter == 'E' || w.letter == 'I' || w.letter == 'J' || w.letter == 'K' || w.letter == 'P' ||
        w.letter == 'Q' || w.letter == 'R' || w.letter == 'H' || w.letter == 'D') {
      letters_[w.letter - 'A'] = w.v;
    }
  }
  int motion_col = 1;
  for (const auto& w : words) {
    if (AxisOfLetter(w.letter) >= 0) {
      motion_col = w.col;
      break;
    }
  }
  if (comp_codes_.any || comp_.engaged()) [[unlikely]] {
    CompPrepare(words, motion_col, running_cycle, probe || probe_cycle != 0, g92);
  }
  const uint32_t cycle_axes = (1u << kX) | (1u << kY) | (1u << kZ) | (1u << kA) | (1u << kB) | (1u << kC);

  // Cycle parameter passing (manual ch. 8: letters A-Z -> L801-L826).
  bool trigger = false;
  // M25 / M06 blocks move in machine coordinates and never run a pending cycle.
  bool machine_block = std::any_of(words.begin(), words.end(),
                                   [](const Word& w) { return w.letter == 'M' && (w.v == 25 || w.v == 6); });
  if (cycle_ != 80 && !running_cycle && !g77 && !machine_block) {
    bool series800 = cycle_ >= 801;
    for (const auto& rw : raw) {
      char l = rw.letter;
      if (l == 'G') continue;
      if (!series800 && !(l == 'A' || l == 'B' || l == 'C' || l == 'E' || l == 'F' || l == 'R' || l == 'X' ||
                          l == 'Y' || l == 'Z')) {
        continue;
      }
      bool dropped;
      Word w = eval_raw(rw, false, true, dropped);
      if (dropped) continue;
      if (w.literal && w.neg_zero && (l == 'A' || l == 'B' || l == 'C')) w.v = -360.0;
      SetParam(800 + (l - 'A') + 1, w.v, rw.col);
    }
    if (series800 && !passed_g.empty()) SetParam(807, passed_g.back().first, passed_g.back().second);
    if (series800 && pb && pb->has_n) SetParam(814, ScaleLiteral('N', pb->n, metric_, false, true), 1);
    trigger = (axis_mask & cycle_axes) != 0;
    if (series800) {
      if (trigger) {
        auto d = FindDef(fmt::format("G{}", cycle_));
        if (!d) Fail(1, fmt::format("Error - Subroutine or Defined Cycle Not Found (G{})", cycle_));
        DoCall(*d, {}, true);
        levels_.back().name = fmt::format("G{}", cycle_);
        return;  // nothing of a triggering G800-series block is executed by the control
      }
      // A block without X Y Z A B C only passes its letters; its M, S, T and F still act (so that, for
      // example, M30 ends the program while a G800-series cycle is pending). Axis words do not move.
      words.erase(std::remove_if(words.begin(), words.end(),
                                 [](const Word& w) { return AxisOfLetter(w.letter) >= 0; }),
                  words.end());
      ms.clear();
      for (const auto& w : words) {
        if (w.letter == 'M') ms.push_back(&w);
      }
      axis_mask = 0;
    }
  }

  // T, S and immediate M codes.
  bool m06 = false, m25 = false, m19 = false, m99 = false;
  int after_m = -1, after_col = 1;
  for (const Word* m : ms) {
    int code = static_cast<int>(m->v);
    switch (code) {
      case 0:
      case 1:
      case 2:
      case 5:
      case 6:
      case 9:
      case 23:
      case 24:
      case 30:
      case 60:
        if (after_m >= 0) Fail(m->col, "ONLY ONE AFTER-TYPE M CODE IS ALLOWED PER BLOCK");
        after_m = code;
        after_col = m->col;
        if (code == 6) m06 = true;
        break;
      case 19:
        m19 = true;
        break;
      case 25:
        m25 = true;
        break;
      case 99:
        m99 = true;
        break;
      case 3:
      case 4:
      case 7:
      case 8:
      case 20:
      case 21:
      case 26:
      case 27:
      case 28:
      case 29:
      case 40:
      case 48:
      case 49:
      case 51:
      case 52:
      case 57:
      case 58:
      case 59:
        break;
      default:
        Fail(m->col, fmt::format("ILLEGAL M CODE M{}", code));
    }
  }
  if (trigger && after_m >= 0) Fail(after_col, "AFTER-TYPE M CODES ARE NOT ALLOWED IN A CYCLE BLOCK");
  if (const Word* t = find('T')) {
    if (t->v < 0 || t->v > 9999999) Fail(t->col, "T WORD OUT OF RANGE 1-9999999");
    selected_tool_ = ToolName(t->v);
    Canon c = Base(Op::kToolSelect);
    c.text = selected_tool_;
    Emit(std::move(c));
  }
  bool spindle_cmd = false;
  const Word* s = find('S');
  if (s && !m19) {
    if (s->v < 0 || s->v > 99999) Fail(s->col, "S WORD OUT OF RANGE 0-99999");
    bool changed = s->v != speed_;
    speed_ = s->v;
    m40_ = false;
    if (changed && (spindle_ == 3 || spindle_ == 4)) spindle_cmd = true;
  }
  bool spindle_dir_given = false;
  for (const Word* m : ms) {
    int code = static_cast<int>(m->v);
    Canon c;
    switch (code) {
      case 3:
      case 4:
        spindle_ = code;
        spindle_dir_given = true;
        c = Base(Op::kSpindle);
        c.text = code == 3 ? "cw" : "ccw";
        c.value = speed_;
        Emit(std::move(c));
        break;
      case 19:
        spindle_ = 19;
        c = Base(Op::kSpindle);
        c.text = "orient";
        c.value = speed_;
        c.value2 = s ? s->v : 0;
        Emit(std::move(c));
        break;
      case 7:
      case 8:
      case 51:
      case 52:
      case 57:
      case 58:
      case 59: {
        c = Base(Op::kCoolant);
        c.code = code;
        static const std::map<int, const char*> kModes = {
            {7, "mist"},      {8, "flood"},      {51, "wash_flood"}, {52, "wash_air"},
            {57, "aux_mist"}, {58, "aux_flood"}, {59, "aux_pulse"}};
        c.text = kModes.at(code);
        if (code == 7 || code == 8) coolant_ = code, aux_coolant_ = 0;
        if (code >= 57) aux_coolant_ = code, coolant_ = coolant_ == 9 ? 9 : coolant_;
        if (code == 51) m51_ = true, m52_ = false;
        if (code == 52) m52_ = true, m51_ = false;
        Emit(std::move(c));
        break;
      }
      case 20:
      case 21:
      case 26:
      case 27:
      case 28:
      case 29:
      case 40:
      case 48:
      case 49:
        if (code == 20) m21_ = false;
        if (code == 21) m21_ = true;
        if (code == 26) m27_ = false;
        if (code == 27) m27_ = true;
        if (code == 28) m29_ = false;
        if (code == 29) m29_ = true;
        if (code == 40) m40_ = true;
        if (code == 48) m49_ = false;
        if (code == 49) m49_ = true;
        c = Base(Op::kAux);
        c.code = code;
        Emit(std::move(c));
        break;
      case 99:
        c = Base(Op::kAlarm);
        c.text = "M99 alarm - see MAIN display";
        Emit(std::move(c));
        break;
      default:
        break;
    }
  }
  if (spindle_cmd && !spindle_dir_given) {
    Canon c = Base(Op::kSpindle);
    c.text = spindle_ == 3 ? "cw" : "ccw";
    c.value = speed_;
    Emit(std::move(c));
  }

  // Feed.
  const Word* f = find('F');
  std::optional<double> block_feed;
  if (f && !dwell && !m06 && !m25) {
    if (f->v < 0) Fail(f->col, "FEEDRATE MAY NOT BE NEGATIVE");
    if (inverse_time_) {
      block_feed = f->v;
    } else {
      feed_ = f->v;
    }
  }

  if (trigger) {
    // G80-series: everything but the passed letters has been executed; run the cycle body.
    auto d = FindDef(fmt::format("G{}", cycle_));
    if (!d) Fail(1, fmt::format("Error - Subroutine or Defined Cycle Not Found (G{})", cycle_));
    DoCall(*d, {}, true);
    levels_.back().name = fmt::format("G{}", cycle_);
    return;
  }

  if (probe_cycle) {
    if (running_cycle) Fail(1, "PROBE CYCLES CANNOT BE CALLED FROM A CYCLE");
    for (const auto& rw : raw) {
      if (rw.letter == 'G') continue;
      bool dropped;
      Word w = eval_raw(rw, false, true, dropped);
      if (!dropped) SetParam(800 + (rw.letter - 'A') + 1, w.v, rw.col);
    }
    auto d = FindDef(fmt::format("G{}", probe_cycle));
    if (!d) Fail(1, fmt::format("Error - Subroutine or Defined Cycle Not Found (G{})", probe_cycle));
    DoCall(*d, {}, true);
    levels_.back().name = fmt::format("G{}", probe_cycle);
    return;
  }

  // H word: fixture offsets.
  if (const Word* h = find('H')) {
    int hv = static_cast<int>(h->v);
    if (hv < 0 || hv > 32) Fail(h->col, "H WORD OUT OF RANGE 0-32");
    if (hv != 0 && !g48_) Fail(h->col, "H WORD NOT ALLOWED IN G49 (IMPLICIT FIXTURE OFFSET) MODE");
    active_h_ = hv;
  }

  uint32_t rotary_mask = (1u << kA) | (1u << kB) | (1u << kC);
  if (dwell) {
    if (axis_mask) Fail(motion_col, "NO AXIS WORDS ALLOWED IN A G04 BLOCK");
    if (!f) Fail(1, "G04 NEEDS F (DWELL SECONDS)");
    double secs = std::floor(f->v * 10 + 1e-6) / 10;  // F format 5.1
    if (secs < 0.1 || secs > 99999.9) Fail(f->col, "G04 DWELL MUST BE F.1-F99999.9 SECONDS");
    Canon c = Base(Op::kDwell);
    c.value = secs;
    Emit(std::move(c));
  } else if (g92) {
    Canon c = Base(Op::kRegrid);
    for (const auto& w : words) {
      int a = AxisOfLetter(w.letter);
      if (a < 0) continue;
      pos_[a] = IsRotaryAxis(a) ? w.v : ToMm(w.v);
      used_ |= 1u << a;
    }
    c.pos = pos_;
    c.used = used_;
    Emit(std::move(c));
  } else if (g98 || g99) {
    if (g99) g98_ = {};
    if (g98) {
      for (const auto& w : words) {
        int a = AxisOfLetter(w.letter);
        if (a < 0) Fail(w.col, "G98 BLOCK MAY CONTAIN ONLY AXIS WORDS");
        double v = IsRotaryAxis(a) ? w.v : ToMm(w.v);
        if (a == kX && mir_x_) v = -v;
        if (a == kY && mir_y_) v = -v;
        g98_[a] = 0;
        g98_[a] = pos_[a] - Offset(a) - v;
        used_ |= 1u << a;
      }
    }
  } else if (m06) {
    if (selected_tool_.empty()) Fail(after_col, "M06 NEEDS A SELECTED TOOL (T WORD)");
    // Axis words of the M06 block are ignored (the slides go to the tool change position).
  } else if (axis_mask || arc) {
    std::optional<double> eff = inverse_time_ ? block_feed : feed_;
    if (inverse_time_ && !block_feed && !m25)
      Fail(arc ? arc_col : motion_col, "F MUST BE PROGRAMMED IN EVERY G93 MOTION BLOCK");
    if (arc) {
      if (axis_mask & rotary_mask) Fail(arc_col, "ROTARY AXIS WORDS ARE NOT ALLOWED IN A CIRCULAR BLOCK");
      if (m25) Fail(arc_col, "M25 IS NOT ALLOWED IN A CIRCULAR BLOCK");
      if (!eff) Fail(arc_col, "NO FEEDRATE PROGRAMMED");
      if (*eff == 0) Fail(f ? f->col : arc_col, "F0 IS NOT ALLOWED IN A CIRCULAR BLOCK");
      bool cw = arc == 2;
      if (mir_x_ != mir_y_) cw = !cw;
      double feed = inverse_time_ ? *eff : ToMm(*eff);
      Arc(words, cw, arc_col, feed, inverse_time_ ? FeedMode::kInverseTime : FeedMode::kPerMinute);
    } else {
      std::array<double, kAxisCount> target = pos_;
      std::array<double, kAxisCount> travel{};
      uint32_t travel_mask = 0;
      bool b_moves = false;
      for (const auto& w : words) {
        int a = AxisOfLetter(w.letter);
        if (a < 0) continue;
        if (IsRotaryAxis(a)) {
          if (a == kB && b_index_ && std::fabs(w.v - std::round(w.v)) > 1e-9) {
            Fail(w.col, "INDEX TABLE POSITIONS ARE WHOLE DEGREES");
          }
          double cur = pos_[a];
          double t, tr;
          if (incremental_ && !m25) {
            tr = w.v;
            t = std::fmod(cur + tr, 360.0);
            if (t < 0) t += 360.0;
          } else {
            t = std::fmod(std::fabs(w.v), 360.0);
            bool ccw = w.v < 0 || w.neg_zero;
            tr = ccw ? -std::fmod(cur - t + 360.0, 360.0) : std::fmod(t - cur + 360.0, 360.0);
            if (std::fabs(tr) < 1e-9 || std::fabs(std::fabs(tr) - 360.0) < 1e-9) tr = 0;
          }
          target[a] = t;
          if (std::fabs(tr) > 1e-9) {
            travel[a] = tr;
            travel_mask |= 1u << a;
            if (a == kB) b_moves = true;
          }
          continue;
        }
        double v = ToMm(w.v);
        if (m25) {
          target[a] = v;
          continue;
        }
        if ((a == kX && mir_x_) || (a == kY && mir_y_)) v = -v;
        double off = Offset(a);
        double prog = pos_[a] - off;
        target[a] = (incremental_ ? prog + v : v) + off;
      }
      // G49 implicit fixture offsets follow a G90 G00 move of B to a listed position.
      if (!g48_ && !incremental_ && !g01_ && (axis_mask & (1u << kB)) && !m25) {
        int hit = 0;
        for (int h = 1; h <= 32; ++h) {
          if (fixtures_[h].set && fixtures_[h].has_i && std::fabs(fixtures_[h].i - target[kB]) < 1e-6)
            hit = h;
        }
        if (hit != active_h_) {
          // Linear targets in this block are re-based on the new offsets.
          for (int a : {kX, kY, kZ}) {
            if (!(axis_mask & (1u << a))) continue;
            double old_off = Offset(a);
            double prog = target[a] - old_off;
            int save = active_h_;
            active_h_ = hit;
            target[a] = prog + Offset(a);
            active_h_ = save;
          }
          active_h_ = hit;
        }
      }
      bool rapid = m25 || (eff && *eff == 0);
      uint32_t linear_mask = axis_mask & ~rotary_mask;
      if (b_index_ && (axis_mask & (1u << kB)) && !rapid) {
        if (linear_mask || (axis_mask & ((1u << kA) | (1u << kC)))) {
          Fail(find('B')->col, "INDEX TABLE MOVES WITH OTHER AXES REQUIRE F0");
        }
        rapid = true;  // an index-only block is forced to F0 for the block
      }
      if (!rapid && !eff) Fail(motion_col, "NO FEEDRATE PROGRAMMED");
      double feed = 0;
      FeedMode fm = FeedMode::kPerMinute;
      if (!rapid) {
        bool linear_moves = false;
        for (int a = 0; a < kAxisCount; ++a) {
          if (!IsRotaryAxis(a) && (linear_mask & (1u << a)) && std::fabs(target[a] - pos_[a]) > 1e-9) {
            linear_moves = true;
          }
        }
        if (inverse_time_) {
          fm = FeedMode::kInverseTime;
          feed = *eff;
        } else if (!linear_moves && travel_mask) {
          fm = FeedMode::kDegPerMinute;
          feed = *eff;
        } else {
          feed = ToMm(*eff);
        }
      }
      bool exact = !g01_;
      if (probe) {
        // G22 (stop on contact) / G23 (stop on break): a queue buster, answered by the Environment.
        ProbeResult pr = env_->Probe(probe_g == 22, pos_, target);
        Canon c = Base(Op::kProbe);
        c.code = probe_g;
        c.feed = rapid ? 0 : feed;
        c.f_mode = fm;
        if (pr.already) {
          machine_[1021] = 1;
          c.text = "already";
        } else if (pr.event) {
          machine_[1021] = 8;
          c.text = probe_g == 22 ? "contact" : "break";
          static const int kOrder[8] = {kX, kY, kZ, kB, kA, kC, kU, kV};
          for (int k = 0; k < 8; ++k) probe_latch_[k] = pr.at[kOrder[k]];
          for (int a = 0; a < kAxisCount; ++a) {
            if (axis_mask & (1u << a)) pos_[a] = pr.at[a];
          }
          if (count_mode_ == 61 && probe_g == 22) machine_[1022] += 1;
          if (count_mode_ == 62 && probe_g == 23) machine_[1022] += 1;
        } else {
          machine_[1021] = 2;
          c.text = "none";
          for (int a = 0; a < kAxisCount; ++a) {
            if (axis_mask & (1u << a)) pos_[a] = target[a];
          }
        }
        machine_[1020] = 1;
        used_ |= axis_mask;
        c.pos = pos_;
        c.used = used_;
        Emit(std::move(c));
      } else if (b_moves && b_index_ && (axis_mask & (1u << kZ)) && std::fabs(target[kZ] - pos_[kZ]) > 1e-9) {
        // Index B (with X, Y) first, then Z.
        std::array<double, kAxisCount> first = target;
        first[kZ] = pos_[kZ];
        EmitMove(first, axis_mask & ~(1u << kZ), rapid, feed, fm, exact, travel, travel_mask);
        EmitMove(target, 1u << kZ, rapid, feed, fm, exact, {}, 0);
      } else {
        EmitMove(target, axis_mask, rapid, feed, fm, exact, travel, travel_mask);
      }
    }
  }
  (void)probe_g;

  // After-type M codes.
  if (after_m >= 0) {
    Canon c;
    switch (after_m) {
      case 0:
      case 1:
        if (after_m == 1 && !optional_stop_) break;
        c = Base(Op::kStop);
        c.code = after_m;
        c.flag = after_m == 1;
        Emit(std::move(c));
        if (spindle_ == 3 || spindle_ == 4) spindle_ = 5;
        coolant_ = 9;
        aux_coolant_ = 0;
        break;
      case 5:
        spindle_ = 5;
        c = Base(Op::kSpindle);
        c.text = "stop";
        c.value = speed_;
        Emit(std::move(c));
        break;
      case 6:
        c = Base(Op::kToolChange);
        c.text = selected_tool_;
        Emit(std::move(c));
        active_tool_ = selected_tool_;
        uat_ = 0;
        ApplyTool();
        if (spindle_ == 3 || spindle_ == 4) spindle_ = 5;
        m49_ = false;
        break;
      case 9:
        coolant_ = 9;
        aux_coolant_ = 0;
        m51_ = m52_ = false;
        c = Base(Op::kCoolant);
        c.code = 9;
        c.text = "off";
        Emit(std::move(c));
        break;
      case 23:
      case 24:
        m24_ = after_m == 24;
        c = Base(Op::kAux);
        c.code = after_m;
        Emit(std::move(c));
        break;
      case 60:
        c = Base(Op::kPallet);
        c.code = 60;
        Emit(std::move(c));
        g01_ = false;
        u88_x_ = 0.254;
        u88_y_ = 0;
        break;
      case 2:
      case 30:
        c = Base(Op::kEnd);
        c.code = after_m;
        c.flag = after_m == 30;
        Emit(std::move(c));
        ResetAtEnd();
        Finish(Step::kEnd);
        break;
      default:
        break;
    }
  }
  if (m99 && after_m == 0) {
    Fail(1, "M99 alarm - see MAIN display (program stopped by M99 M00)", "M99");
  }
}

void KtRun::Arc(const Words& words, bool cw, int col, double feed, FeedMode fm) {
  // Plane axes (first, second, normal); App. H: G18 is (Z, X), G20/G21 substitute the co-axes.
  int p1, p2, pn;
  if (plane_ == 17) {
    p1 = kX, p2 = kY, pn = kZ;
  } else if (plane_ == 18) {
    p1 = kZ, p2 = kX, pn = kY;
  } else {
    p1 = kY, p2 = kZ, pn = kX;
  }
  auto coaxis = [](int a) { return a == kX ? kU : (a == kY ? kV : kW); };
  if (g20_) p1 = coaxis(p1);
  if (g21_) p2 = coaxis(p2);
  auto centre_letter = [](int a) { return (a == kX || a == kU) ? 'I' : ((a == kY || a == kV) ? 'J' : 'K'); };
  const Word* w1 = nullptr;
  const Word* w2 = nullptr;
  const Word* wn = nullptr;
  const Word* c1 = nullptr;
  const Word* c2 = nullptr;
  const Word* r = nullptr;
  for (const auto& w : words) {
    int a = AxisOfLetter(w.letter);
    if (a == p1) w1 = &w;
    if (a == p2) w2 = &w;
    if (a == pn) wn = &w;
    if (a >= 0 && a != p1 && a != p2 && a != pn) Fail(w.col, "AXIS WORD NOT IN THE ARC PLANE");
    if (w.letter == centre_letter(p1)) c1 = &w;
    if (w.letter == centre_letter(p2)) c2 = &w;
    if (w.letter == 'R') r = &w;
  }
  auto target_of = [&](int a, const Word* w) {
    if (!w) return pos_[a];
    double v = ToMm(w->v);
    if ((a == kX && mir_x_) || (a == kY && mir_y_)) v = -v;
    double off = Offset(a);
    return (incremental_ ? pos_[a] - off + v : v) + off;
  };
  double s1 = pos_[p1], s2 = pos_[p2];
  double e1 = target_of(p1, w1), e2 = target_of(p2, w2), en = target_of(pn, wn);
  double cc1, cc2;
  double sweep;  // degrees, positive
  if (r) {
    if (incremental_ || plane_ != 17 || g20_ || g21_) {
      if (!(plane_ == 18 && g21_ && !incremental_)) Fail(r->col, "R CIRCLES ARE ALLOWED ONLY IN G90 G17");
    }
    double rad = ToMm(std::fabs(r->v));
    double d1 = e1 - s1, d2 = e2 - s2;
    double chord = std::hypot(d1, d2);
    if (chord < 1e-9) Fail(r->col, "R CIRCLES CANNOT BE FULL CIRCLES");
    if (rad < 0.001) Fail(r->col, "ARC RADIUS BELOW THE MINIMUM");
    double half = chord / 2;
    double h2 = rad * rad - half * half;
    if (h2 < -1e-4 * rad) Fail(r->col, "ARC RADIUS TOO SMALL FOR THE END POINT");
    double h = std::sqrt(std::max(0.0, h2));
    double m1 = (s1 + e1) / 2, m2 = (s2 + e2) / 2;
    double n1 = -d2 / chord, n2 = d1 / chord;
    bool want_major = r->v < 0;
    double best1 = 0, best2 = 0, best_sweep = -1;
    for (int sgn : {1, -1}) {
      double k1 = m1 + sgn * h * n1, k2 = m2 + sgn * h * n2;
      double a0 = std::atan2(s2 - k2, s1 - k1), a1 = std::atan2(e2 - k2, e1 - k1);
      double ccw = (a1 - a0) * 180.0 / kPi;
      while (ccw <= 0) ccw += 360.0;
      while (ccw > 360.0) ccw -= 360.0;
      double sw = cw ? 360.0 - ccw : ccw;
      bool major = sw > 180.0 + 1e-9;
      if (major == want_major || best_sweep < 0) {
        if (best_sweep < 0 || major == want_major) {
          best1 = k1, best2 = k2, best_sweep = sw;
          if (major == want_major) break;
        }
      }
    }
    cc1 = best1, cc2 = best2, sweep = best_sweep;
  } else {
    if (!c1 && !c2) Fail(col, "ARC NEEDS I/J/K CENTRE WORDS OR R");
    auto centre = [&](int a, const Word* c) {
      if (!c) return pos_[a];
      double v = ToMm(c->v);
      if ((a == kX && mir_x_) || (a == kY && mir_y_)) v = -v;
      if (incremental_) return pos_[a] + v;
      return v + Offset(a);
    };
    cc1 = centre(p1, c1);
    cc2 = centre(p2, c2);
    double rs = std::hypot(s1 - cc1, s2 - cc2), re = std::hypot(e1 - cc1, e2 - cc2);
    if (rs < 0.001) Fail(col, "ARC RADIUS BELOW THE MINIMUM");
    if (std::fabs(rs - re) > 0.013) {
      Fail(col, fmt::format("ARC START AND END RADIUS DIFFER ({:.4f} / {:.4f})", FromMm(rs), FromMm(re)));
    }
    double a0 = std::atan2(s2 - cc2, s1 - cc1), a1 = std::atan2(e2 - cc2, e1 - cc1);
    double ccw = (a1 - a0) * 180.0 / kPi;
    while (ccw < 0) ccw += 360.0;
    while (ccw >= 360.0) ccw -= 360.0;
    if (std::hypot(e1 - s1, e2 - s2) < 1e-6) {
      sweep = 360.0;
    } else {
      sweep = cw ? 360.0 - ccw : ccw;
      if (sweep <= 0) sweep += 360.0;
    }
  }
  std::array<double, kAxisCount> target = pos_;
  target[p1] = e1;
  target[p2] = e2;
  target[pn] = en;
  used_ |= (1u << p1) | (1u << p2);
  if (wn) used_ |= 1u << pn;
  Canon c = Base(Op::kArc);
  std::array<double, kAxisCount> centre = pos_;
  centre[p1] = cc1;
  centre[p2] = cc2;
  c.center = {centre[kX] + 0 * centre[kU], centre[kY], centre[kZ]};
  if (p1 == kU || p2 == kU) c.center[0] = centre[kU];
  if (p1 == kV || p2 == kV) c.center[1] = centre[kV];
  if (p1 == kW || p2 == kW) c.center[2] = centre[kW];
  pos_ = target;
  c.pos = pos_;
  c.used = used_;
  c.feed = feed;
  c.f_mode = fm;
  c.exact_stop = !g01_;
  c.cw = cw;
  c.plane.assign({AxisName(p1)[0], AxisName(p2)[0]});
  c.turns = sweep;
  Emit(std::move(c));
}

}  // namespace
}  // namespace ktapl

std::vector<ToolEntry> ParseKtaplToolTable(std::string_view text) {
  // Only G70/G71 and (TLD,...) matter; the text is not run (it could loop or move).
  RunOptions o;
  o.program_name = "tools";
  ktapl::KtRun run(o);
  int line = 0;
  size_t p = 0;
  while (p < text.size()) {
    size_t nl = text.find('\n', p);
    if (nl == std::string_view::npos) nl = text.size();
    std::string_view b = text.substr(p, nl - p);
    p = nl + 1;
    ++line;
    try {
      run.LoadToolLine(b);
    } catch (const ktapl::RunError& e) {
      throw Error(Errc::kInvalidArgument, fmt::format("{}: {}", line, e.text));
    } catch (const ktapl::ExprError& e) {
      throw Error(Errc::kInvalidArgument, fmt::format("{}: {}", line, e.text));
    }
  }
  return run.Tools();
}

std::unique_ptr<Run> StartKtaplRun(const RunOptions& options) {
  return std::make_unique<ktapl::KtRun>(options);
}

}  // namespace cell::interp
