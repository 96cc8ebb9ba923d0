// One Okuma block as the tape format gives it (manual SECTION 1 "Program format", seed ln 508-715,
// 7414-7472): an optional block delete "/", a sequence name "N...." followed by a blank, then either a
// control statement (GOTO IF CALL RTS MODIN MODOUT READ WRITE GET PUT; PSELECT VSET END belong to schedule
// programs), a program-name block "O....", or words and assignments in the order written. Parsing happens
// once per block text (interp_read.cpp); execution evaluates the expressions each time the block runs.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "expr.h"

namespace cell::interp::okuma {

// An address: one letter ('X') or an extended address of two ('S' | 'B' << 8 for SB).
using Addr = uint16_t;
constexpr Addr MakeAddr(char a, char b = 0) {
  return static_cast<Addr>(static_cast<unsigned char>(a) | (static_cast<unsigned char>(b) << 8));
}
std::string AddrName(Addr a);

struct Word {
  Addr addr = 0;
  bool expr = false;   // addr=expression (or the lenient X100+V1 form)
  bool point = false;  // a literal written with a decimal point
  int digits = 0;      // digits written (the 8-digit rule)
  double num = 0;      // a literal as written, sign included
  int32_t node = -1;   // expression root
  int col = 1;
};

// The left side of an assignment.
enum class VarKind : uint8_t { kCommon, kLocal, kSystem };
struct Assign {
  VarKind kind = VarKind::kLocal;
  int common = 0;      // V1-V200
  uint64_t name = 0;   // local or system variable name
  int32_t index = -1;  // system variable suffix [expr]
  int32_t value = -1;  // the expression
  bool is_string = false;
  std::string text;  // a character string (VUACM), decoded
  int col = 1;
};

// An item of a block in the order written: a word or an assignment.
struct Item {
  bool assign = false;
  uint16_t i = 0;
};

enum class Stmt : uint8_t {
  kNone,
  kProgramName,
  kGoto,
  kIf,
  kCall,
  kRts,
  kModin,
  kModout,
  kRead,
  kWrite,
  kGet,
  kPut,
  kSchedule,  // PSELECT, VSET, END: schedule programs only
};

// A piece of a logical block that came from one physical line (continuation lines start with '$').
struct Segment {
  size_t offset = 0;  // where it starts in the joined block text
  int line = 1;
  int col0 = 1;  // column of its first character in the physical line
};

struct Block {
  std::string text;               // the logical block (continuation lines joined)
  std::vector<Segment> segments;  // only when continued
  bool deleted = false;
  std::string seq;  // sequence name with its N ("N100", "NAT01"); empty if none
  int seq_col = 1;
  bool noex = false;
  Stmt stmt = Stmt::kNone;
  int stmt_col = 1;
  std::string stmt_word;  // PSELECT / VSET / END
  std::vector<Word> words;
  std::vector<Assign> assigns;
  std::vector<Item> items;
  std::vector<Node> pool;
  // A sequence name given as an argument (G85-G88 NAT01, GOTO/IF targets).
  std::string label;
  int label_col = 1;
  // CALL / MODIN / program name
  std::string program;
  int program_col = 1;
  int repeat = 1;  // CALL ... Q n: runs of the subprogram (judgement 48)
  // IF
  int32_t cond = -1;
  std::string defined;  // IF name: a local variable name
  // READ / WRITE channel, GET / PUT
  int channel = 0;
  bool has_var = false;  // GET/PUT: assigns[0] is the variable
  int32_t count = -1;    // GET/PUT ",c" expression
  bool put_text = false;
  std::string put;  // PUT 'text' / ^'text' / $hex, decoded
  bool calrg = false;
  int calrg_col = 1;

  void Clear();
  bool Empty() const { return stmt == Stmt::kNone && items.empty() && seq.empty(); }
  // 1-based line and column in the program of a column of the (joined) block text.
  void Locate(int col, int first_line, int* line, int* out_col) const;
};

// Parses a logical block (without its end of block) into `b` (cleared first by the caller). PSELECT, VSET and
// END are recognised as schedule statements (the executor of part programs refuses them). Throws RunError.
void ParseBlock(std::string_view s, Block& b);

// "O" + 1-4 letters/digits, all digits or beginning with a letter (ln 488-506): the name, or "".
std::string ProgramNameOf(std::string_view block);

}  // namespace cell::interp::okuma
