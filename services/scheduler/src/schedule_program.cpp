#include "cell/scheduler/schedule_program.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include <fmt/format.h>

#include "cell/error/error.h"

namespace cell::scheduler::schedule {

struct Expr {
  enum class Kind { kNum, kCommon, kOther, kNeg, kAdd, kSub, kMul, kDiv };
  Kind kind = Kind::kNum;
  double num = 0;
  int var = 0;
  std::string name;  // kOther: the variable as written
  int col = 0;       // 1-based column in the block's line
  std::shared_ptr<const Expr> a, b;
};

namespace {

bool IsAlnum(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0;
}
bool IsDigit(char c) {
  return c >= '0' && c <= '9';
}
bool IsBlank(char c) {
  return c == ' ' || c == '\t';
}

struct ParseError {
  int col;
  std::string text;
};

// Recursive-descent expression parser over one block's text. With `stop_at_blank` (VSET), a blank outside
// brackets ends the expression.
class ExprParser {
 public:
  ExprParser(std::string_view s, std::size_t pos, bool stop_at_blank)
      : s_(s), pos_(pos), stop_at_blank_(stop_at_blank) {}

  std::shared_ptr<const Expr> Parse() {
    auto e = Sum();
    return e;
  }
  std::size_t pos() const { return pos_; }

 private:
  void Blanks() {
    if (stop_at_blank_ && depth_ == 0) return;
    while (pos_ < s_.size() && IsBlank(s_[pos_])) ++pos_;
  }
  char Peek() {
    Blanks();
    return pos_ < s_.size() ? s_[pos_] : '\0';
  }
  int Col() const { return static_cast<int>(pos_) + 1; }

  std::shared_ptr<const Expr> Binary(Expr::Kind k, std::shared_ptr<const Expr> a,
                                     std::shared_ptr<const Expr> b, int col) {
    auto e = std::make_shared<Expr>();
    e->kind = k;
    e->a = std::move(a);
    e->b = std::move(b);
    e->col = col;
    return e;
  }

  std::shared_ptr<const Expr> Sum() {
    auto left = Product();
    while (true) {
      const char c = Peek();
      if (c != '+' && c != '-') return left;
      const int col = Col();
      ++pos_;
      left = Binary(c == '+' ? Expr::Kind::kAdd : Expr::Kind::kSub, left, Product(), col);
    }
  }

  std::shared_ptr<const Expr> Product() {
    auto left = Unary();
    while (true) {
      const char c = Peek();
      if (c != '*' && c != '/') return left;
      const int col = Col();
      ++pos_;
      left = Binary(c == '*' ? Expr::Kind::kMul : Expr::Kind::kDiv, left, Unary(), col);
    }
  }

  std::shared_ptr<const Expr> Unary() {
    const char c = Peek();
    if (c == '-' || c == '+') {
      const int col = Col();
      ++pos_;
      auto inner = Unary();
      if (c == '+') return inner;
      auto e = std::make_shared<Expr>();
      e->kind = Expr::Kind::kNeg;
      e->a = inner;
      e->col = col;
      return e;
    }
    return Primary();
  }

  std::shared_ptr<const Expr> Primary() {
    const char c = Peek();
    const int col = Col();
    auto e = std::make_shared<Expr>();
    e->col = col;
    if (c == '[') {
      ++pos_;
      ++depth_;
      auto inner = Sum();
      if (Peek() != ']') throw ParseError{Col(), "expected ']'"};
      --depth_;
      ++pos_;
      return inner;
    }
    if (IsDigit(c) || c == '.') {
      const std::size_t start = pos_;
      int dots = 0, digits = 0;
      while (pos_ < s_.size() && (IsDigit(s_[pos_]) || s_[pos_] == '.')) {
        (s_[pos_] == '.' ? dots : digits)++;
        ++pos_;
      }
      if (dots > 1 || digits == 0) throw ParseError{col, "bad number"};
      e->kind = Expr::Kind::kNum;
      e->num = std::stod(std::string(s_.substr(start, pos_ - start)));
      return e;
    }
    if (std::isalpha(static_cast<unsigned char>(c))) {
      const std::size_t start = pos_;
      while (pos_ < s_.size() && IsAlnum(s_[pos_])) ++pos_;
      if (pos_ < s_.size() && s_[pos_] == '[') {  // indexed system / output variable: VDOUT[12]
        const std::size_t close = s_.find(']', pos_);
        if (close == std::string_view::npos) throw ParseError{col, "expected ']'"};
        pos_ = close + 1;
      }
      const std::string word(s_.substr(start, pos_ - start));
      if (word.size() >= 2 && word[0] == 'V' && std::all_of(word.begin() + 1, word.end(), IsDigit)) {
        const int n = word.size() <= 4 ? std::stoi(word.substr(1)) : 0;
        if (n < 1 || n > 200) throw ParseError{col, word + " is not a common variable (V1-V200)"};
        e->kind = Expr::Kind::kCommon;
        e->var = n;
        return e;
      }
      if (word.rfind("VDOUT", 0) == 0)
        throw ParseError{col, "output variable " + word + " on the right side"};
      e->kind = Expr::Kind::kOther;
      e->name = word;
      return e;
    }
    throw ParseError{col, c == '\0' ? "expression expected" : std::string("unexpected '") + c + "'"};
  }

  std::string_view s_;
  std::size_t pos_;
  bool stop_at_blank_;
  int depth_ = 0;
};

struct AlarmError {
  int col;
  std::string text;
};

double Eval(const Expr& e, Variables& vars) {
  switch (e.kind) {
    case Expr::Kind::kNum:
      return e.num;
    case Expr::Kind::kCommon:
      return vars.Get(e.var);
    case Expr::Kind::kOther:
      // A schedule cannot set local variables (VSET takes common, system or output variables), so a local is
      // never defined here; system variables live in the station's CNC.
      throw AlarmError{
          e.col, "variable " + e.name + " is not available to a schedule run by the cell (only V1-V200)"};
    case Expr::Kind::kNeg:
      return -Eval(*e.a, vars);
    case Expr::Kind::kAdd:
      return Eval(*e.a, vars) + Eval(*e.b, vars);
    case Expr::Kind::kSub:
      return Eval(*e.a, vars) - Eval(*e.b, vars);
    case Expr::Kind::kMul:
      return Eval(*e.a, vars) * Eval(*e.b, vars);
    case Expr::Kind::kDiv: {
      const double d = Eval(*e.b, vars);
      if (d == 0) throw AlarmError{e.col, "division by zero"};
      return Eval(*e.a, vars) / d;
    }
  }
  return 0;
}

// "[dev:]name[.ext]" (seed 8808-8822).
FileSpec ParseFile(std::string_view f, int col, const char* default_name, const char* default_ext) {
  if (f.find_first_of("*?") != std::string_view::npos) {
    throw ParseError{col, "'*' or '?' in a file name"};
  }
  FileSpec spec;
  if (auto colon = f.find(':'); colon != std::string_view::npos) {
    spec.device = std::string(f.substr(0, colon));
    f.remove_prefix(colon + 1);
    if (spec.device.empty() || spec.device.size() > 3)
      throw ParseError{col, "device name of 1-3 characters expected"};
  }
  if (auto dot = f.find('.'); dot != std::string_view::npos) {
    spec.ext = std::string(f.substr(dot + 1));
    f = f.substr(0, dot);
    if (spec.ext.empty() || spec.ext.size() > 3)
      throw ParseError{col, "extension of 1-3 characters expected"};
  } else {
    spec.ext = default_ext;
  }
  spec.name = f.empty() ? default_name : std::string(f);
  if (spec.name.size() > 16) throw ParseError{col, "file name longer than 16 characters"};
  return spec;
}

std::string_view Trim(std::string_view s, std::size_t* lead = nullptr) {
  std::size_t a = 0;
  while (a < s.size() && IsBlank(s[a])) ++a;
  std::size_t b = s.size();
  while (b > a && IsBlank(s[b - 1])) --b;
  if (lead) *lead = a;
  return s.substr(a, b - a);
}

// A logical block: the text with comments blanked, its first line and where it starts.
struct RawBlock {
  std::string text;
  int line;
};

Block ParseBlock(const RawBlock& raw) {
  Block b;
  b.line = raw.line;
  const std::string_view s = raw.text;
  std::size_t p = 0;
  while (p < s.size() && IsBlank(s[p])) ++p;
  if (p < s.size() && s[p] == '/')
    throw ParseError{static_cast<int>(p) + 1, "block delete is not allowed in a schedule program"};
  if (p < s.size() && s[p] == 'N') {
    const std::size_t start = p;
    ++p;
    while (p < s.size() && IsAlnum(s[p])) ++p;
    b.seq = std::string(s.substr(start, p - start));
    if (b.seq.size() < 2 || b.seq.size() > 6)
      throw ParseError{static_cast<int>(start) + 1, "bad sequence name " + b.seq};
    if (p < s.size() && !IsBlank(s[p]))
      throw ParseError{static_cast<int>(p) + 1, "a blank must follow the sequence name"};
    while (p < s.size() && IsBlank(s[p])) ++p;
  }
  const std::size_t kw_start = p;
  while (p < s.size() && std::isalpha(static_cast<unsigned char>(s[p]))) ++p;
  const std::string kw(s.substr(kw_start, p - kw_start));
  const int kw_col = static_cast<int>(kw_start) + 1;
  const auto target = [&](std::size_t from) {
    std::size_t lead = 0;
    std::string_view t = Trim(s.substr(from), &lead);
    if (t.size() < 2 || t[0] != 'N' || !std::all_of(t.begin() + 1, t.end(), IsAlnum)) {
      throw ParseError{static_cast<int>(from + lead) + 1, "sequence name (Nxxxx) expected"};
    }
    return std::string(t);
  };
  if (kw == "END") {
    b.kind = Block::Kind::kEnd;
    if (!Trim(s.substr(p)).empty()) throw ParseError{static_cast<int>(p) + 1, "END takes no arguments"};
  } else if (kw == "GOTO") {
    b.kind = Block::Kind::kGoto;
    b.target = target(p);
  } else if (kw == "IF") {
    b.kind = Block::Kind::kIf;
    while (p < s.size() && IsBlank(s[p])) ++p;
    if (p >= s.size() || s[p] != '[')
      throw ParseError{static_cast<int>(p) + 1, "IF needs [expression op expression]"};
    ExprParser lhs(s, p + 1, false);
    b.lhs = lhs.Parse();
    std::size_t q = lhs.pos();
    while (q < s.size() && IsBlank(s[q])) ++q;
    const std::string op(s.substr(q, 2));
    static const char* kOps[] = {"LT", "LE", "EQ", "NE", "GE", "GT"};
    if (std::find(std::begin(kOps), std::end(kOps), op) == std::end(kOps)) {
      throw ParseError{static_cast<int>(q) + 1, "comparison operator LT, LE, EQ, NE, GE or GT expected"};
    }
    b.op = op;
    ExprParser rhs(s, q + 2, false);
    b.rhs = rhs.Parse();
    q = rhs.pos();
    while (q < s.size() && IsBlank(s[q])) ++q;
    if (q >= s.size() || s[q] != ']') throw ParseError{static_cast<int>(q) + 1, "expected ']'"};
    b.target = target(q + 1);
  } else if (kw == "VSET") {
    b.kind = Block::Kind::kVset;
    while (true) {
      while (p < s.size() && IsBlank(s[p])) ++p;
      if (p >= s.size()) break;
      const std::size_t vstart = p;
      while (p < s.size() && (IsAlnum(s[p]) || s[p] == '[' || s[p] == ']')) ++p;
      const std::string var(s.substr(vstart, p - vstart));
      const int vcol = static_cast<int>(vstart) + 1;
      if (var.size() >= 2 && var[0] == 'V' && std::all_of(var.begin() + 1, var.end(), IsDigit)) {
        const int n = var.size() <= 4 ? std::stoi(var.substr(1)) : 0;
        if (n < 1 || n > 200) throw ParseError{vcol, var + " is not a common variable (V1-V200)"};
        if (p >= s.size() || s[p] != '=')
          throw ParseError{static_cast<int>(p) + 1, "expected '=' after " + var};
        ExprParser value(s, p + 1, true);
        b.sets.emplace_back(n, value.Parse());
        p = value.pos();
        if (p < s.size() && !IsBlank(s[p]))
          throw ParseError{static_cast<int>(p) + 1, "unexpected text after expression"};
      } else if (!var.empty() && var[0] == 'V') {
        throw ParseError{vcol, "VSET of system or output variable " + var +
                                   " is not supported by the cell (common variables V1-V200 only)"};
      } else {
        throw ParseError{vcol,
                         "VSET needs a common, system or output variable on the left, not '" + var + "'"};
      }
    }
    if (b.sets.empty()) throw ParseError{kw_col, "VSET without an assignment"};
  } else if (kw == "PSELECT") {
    b.kind = Block::Kind::kPselect;
    if (p < s.size() && !IsBlank(s[p]))
      throw ParseError{static_cast<int>(p) + 1, "a blank must follow PSELECT"};
    // Up to four comma-separated fields.
    std::vector<std::pair<std::string_view, int>> fields;
    std::size_t f = p;
    while (true) {
      std::size_t comma = s.find(',', f);
      const std::size_t end = comma == std::string_view::npos ? s.size() : comma;
      std::size_t lead = 0;
      std::string_view field = Trim(s.substr(f, end - f), &lead);
      fields.emplace_back(field, static_cast<int>(f + lead) + 1);
      if (comma == std::string_view::npos) break;
      f = comma + 1;
    }
    if (fields.size() > 4) throw ParseError{fields[4].second, "PSELECT takes at most four items fm,pm,fs,n"};
    fields.resize(4, {std::string_view(), static_cast<int>(s.size()) + 1});
    // A count written in the third place (fs omitted without its comma) is accepted: a file name has no '='.
    if (!fields[2].first.empty() && fields[2].first[0] == 'Q' && fields[3].first.empty() &&
        (fields[2].first.size() == 1 || !IsAlnum(fields[2].first[1]) || IsDigit(fields[2].first[1]))) {
      std::swap(fields[2], fields[3]);
    }
    b.main_file = ParseFile(fields[0].first, fields[0].second, "A", "MIN");
    if (!fields[1].first.empty()) {
      const std::string_view pm = fields[1].first;
      if (pm[0] != 'O' || pm.size() < 2 || pm.size() > 5 || !std::all_of(pm.begin() + 1, pm.end(), IsAlnum)) {
        throw ParseError{fields[1].second, "program name O + up to 4 characters expected"};
      }
      b.program = std::string(pm);
    }
    if (!fields[2].first.empty()) {
      FileSpec sub = ParseFile(fields[2].first, fields[2].second, "", "SUB");
      if (sub.name.empty()) throw ParseError{fields[2].second, "subprogram file name missing"};
      b.sub_file = sub;
    }
    if (!fields[3].first.empty()) {
      const std::string_view n = fields[3].first;
      if (n[0] != 'Q') throw ParseError{fields[3].second, "repeat count Q=n expected"};
      std::size_t at = 1;
      if (at < n.size() && (n[at] == '=' || IsBlank(n[at]))) ++at;
      const auto base = static_cast<std::size_t>(fields[3].second - 1);
      ExprParser count(s, base + at, false);
      b.count = count.Parse();
      if (count.pos() < base + n.size()) {
        throw ParseError{static_cast<int>(count.pos()) + 1, "unexpected text after the repeat count"};
      }
    }
  } else {
    throw ParseError{
        kw_col, kw.empty() ? "illegal block in a schedule program (PSELECT, GOTO, IF, VSET or END expected)"
                           : "illegal block " + kw +
                                 " in a schedule program (PSELECT, GOTO, IF, VSET or END expected)"};
  }
  return b;
}

}  // namespace

Program Parse(std::string_view text, std::string_view name) {
  Program prog;
  prog.name = std::string(name);
  std::vector<RawBlock> raws;
  int line_no = 0;
  std::size_t start = 0;
  bool in_comment = false;
  while (start <= text.size()) {
    std::size_t eol = text.find('\n', start);
    if (eol == std::string_view::npos) eol = text.size();
    std::string line(text.substr(start, eol - start));
    if (!line.empty() && line.back() == '\r') line.pop_back();
    ++line_no;
    // Comments ( ... ) become blanks so that columns stay true.
    for (char& c : line) {
      if (c == '(') in_comment = true;
      if (in_comment) {
        if (c == ')') in_comment = false;
        c = ' ';
      }
    }
    in_comment = false;
    std::size_t lead = 0;
    const std::string_view body = Trim(line, &lead);
    if (!body.empty() && body[0] == '$' && !raws.empty()) {
      raws.back().text += " " + std::string(body.substr(1));  // continuation of the previous block
    } else if (!body.empty() && body != "%") {
      raws.push_back(RawBlock{line, line_no});
    }
    if (eol == text.size()) break;
    start = eol + 1;
  }
  for (const auto& raw : raws) {
    try {
      prog.blocks.push_back(ParseBlock(raw));
    } catch (const ParseError& e) {
      throw Error(Errc::kInvalidArgument, fmt::format("{}:{}:{}: error: {}", name, raw.line, e.col, e.text));
    }
    if (prog.blocks.back().kind == Block::Kind::kEnd) return prog;  // blocks after END are ignored
  }
  throw Error(Errc::kInvalidArgument,
              fmt::format("{}:{}:1: error: a schedule program must end with END", name, line_no));
}

Runner::Runner(std::shared_ptr<const Program> program, Position at)
    : program_(std::move(program)), pos_(at) {}

Step Runner::Next(Variables& vars) {
  const Program& p = *program_;
  Step step;
  const auto alarm = [&](const Block& b, int col, const std::string& text) {
    pos_.finished = true;
    step.kind = Step::Kind::kAlarm;
    step.alarm = fmt::format("{}:{}:{}: error: {}", p.name, b.line, col, text);
    return step;
  };
  for (int guard = 0; !pos_.finished; ++guard) {
    if (pos_.pc >= p.blocks.size()) break;
    const Block& b = p.blocks[pos_.pc];
    if (guard > 100000) return alarm(b, 1, "the schedule loops without selecting a program");
    const auto jump = [&]() -> bool {
      for (std::size_t i = 0; i < p.blocks.size(); ++i) {
        if (p.blocks[i].seq == b.target) {
          pos_.pc = i;
          return true;
        }
      }
      return false;
    };
    try {
      switch (b.kind) {
        case Block::Kind::kPselect: {
          if (pos_.count == 0) {
            const double q = b.count ? Eval(*b.count, vars) : 1.0;
            if (q != std::floor(q) || q < 1 || q > 9999) {
              return alarm(b, b.count ? b.count->col : 1, fmt::format("repeat count Q={} outside 1-9999", q));
            }
            pos_.count = static_cast<int>(q);
            pos_.done = 0;
          }
          if (pos_.done < pos_.count) {
            ++pos_.done;
            step.kind = Step::Kind::kRun;
            step.run = Run{b.main_file.Full(), b.program,  b.sub_file ? b.sub_file->Full() : std::string(),
                           pos_.done,          pos_.count, b.line};
            return step;
          }
          pos_.count = 0;
          pos_.done = 0;
          ++pos_.pc;
          break;
        }
        case Block::Kind::kGoto:
          if (!jump()) return alarm(b, 1, "sequence name " + b.target + " not found");
          break;
        case Block::Kind::kIf: {
          const double l = Eval(*b.lhs, vars), r = Eval(*b.rhs, vars);
          bool t = false;
          if (b.op == "LT") t = l < r;
          if (b.op == "LE") t = l <= r;
          if (b.op == "EQ") t = l == r;
          if (b.op == "NE") t = l != r;
          if (b.op == "GE") t = l >= r;
          if (b.op == "GT") t = l > r;
          if (!t) {
            ++pos_.pc;
          } else if (!jump()) {
            return alarm(b, 1, "sequence name " + b.target + " not found");
          }
          break;
        }
        case Block::Kind::kVset:
          for (const auto& [n, e] : b.sets) vars.Set(n, Eval(*e, vars));
          ++pos_.pc;
          break;
        case Block::Kind::kEnd:
          pos_.finished = true;
          break;
      }
    } catch (const AlarmError& e) {
      return alarm(b, e.col, e.text);
    }
  }
  pos_.finished = true;
  step.kind = Step::Kind::kEnd;
  return step;
}

std::string StationEntry(const Run& run) {
  auto bare = [](const std::string& f) { return f.substr(f.find(':') + 1); };
  std::string entry = bare(run.main_file);
  if (!run.program.empty() || !run.sub_file.empty()) entry += "," + run.program;
  if (!run.sub_file.empty()) entry += "," + bare(run.sub_file);
  return entry;
}

}  // namespace cell::scheduler::schedule
