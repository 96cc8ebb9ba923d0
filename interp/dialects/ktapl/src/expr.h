// KT-APL arithmetic expressions and IFT conditions (manual ch. 4 PAR/IFT, ch. 8, App. A).
#pragma once

#include <string>
#include <string_view>

namespace cell::interp::ktapl {

// Thrown by the evaluator; `offset` is the 0-based position in the parsed text.
struct ExprError {
  std::string text;
  size_t offset = 0;
};

class ExprContext {
 public:
  virtual ~ExprContext() = default;
  // Value of parameter n; throws ExprError("Error L number NOT in table") when undefined.
  virtual double Param(int n) = 0;
  virtual bool ParamDefined(int n) = 0;
  // Letter address value (A B C E F I J K P Q R S T U V W X Y Z).
  virtual double Letter(char c) = 0;
  // True when G (or M) code `code` is in force.
  virtual bool ActiveCode(char gm, int code) = 0;
};

class ExprParser {
 public:
  ExprParser(std::string_view text, ExprContext& ctx) : s_(text), ctx_(ctx) {}

  // value := term (('+'|'-') term)*
  double Value();
  // Full IFT condition.
  bool Condition();
  // Parameter reference "Ln" or "L(expr)" at the current position; returns the number.
  int ParamRef();

  void SkipSpaces();
  bool AtEnd();
  size_t pos() const { return pos_; }
  void set_pos(size_t p) { pos_ = p; }
  char Peek();
  bool Accept(char c);
  // Case-insensitive keyword at the current position (after spaces); consumes it when present.
  bool AcceptWord(std::string_view w);

 private:
  double Term();
  double Unary();
  double Primary();
  bool OrCond();
  bool AndCond();
  bool NotCond();
  bool Atom();
  [[noreturn]] void Fail(const std::string& text);
  double Check(double v);

  std::string_view s_;
  ExprContext& ctx_;
  size_t pos_ = 0;
  int depth_ = 0;
};

// Evaluates a complete expression (the whole text must be consumed).
double EvalValue(std::string_view text, ExprContext& ctx);
bool EvalCondition(std::string_view text, ExprContext& ctx);

}  // namespace cell::interp::ktapl
