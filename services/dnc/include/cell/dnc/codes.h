// The controls' own character codes on a serial line (docs/dnc.md): EIA RS-244 (odd parity in channel 5,
// end of block in channel 8) and ISO 840 / ASCII / JIS 7-bit (parity in the eighth bit, or JIS 8-bit),
// per control, with the end-of-data codes and the NUL leader/trailer. The text side is the program store's
// text: one '\n' per end of block.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cell/error/error.h"

namespace cell::dnc {

enum class Control { kKtApl, kBalt, kEmco, kOkuma };
enum class Code { kEia, kIso };
enum class Parity { kNone, kEven, kOdd };
enum class End { kNul, kCtrlZ, kPercent };

// The control of a station's dialect ("ktapl", "balt", "emco", "okuma"). Throws Error(kInvalidArgument).
Control ControlOf(std::string_view dialect);
std::string_view ControlName(Control c);
std::string_view CodeName(Code c);      // "eia", "iso"
std::string_view ParityName(Parity p);  // "none", "even", "odd"
std::string_view EndName(End e);        // "nul", "ctrl-z", "%"

// What one transfer carries: the code, the parity in the eighth bit (ISO codes with 7 data bits; EIA's
// parity is channel 5 of the code itself and `parity` odd checks it, none does not), the end-of-data code
// and the number of NUL (blank tape) characters before and after.
struct Format {
  Control control = Control::kKtApl;
  Code code = Code::kIso;
  int data_bits = 7;
  Parity parity = Parity::kEven;
  End end = End::kNul;
  int leader = 50;
};

// One character of a control's table: the text character ('\n' for end of block), its code on the line
// without parity, and the manual line (or standard) that defines it.
struct CodeRow {
  char text;
  std::vector<uint8_t> wire;  // one byte, or CR LF for EMCO's end of block
  std::string_view source;
};

// Every character the format's control defines in its code, in table order (docs/dnc.md prints these).
std::vector<CodeRow> Table(const Format& f);

// The EIA RS-244 code for a list of tape channels 1-8 ("1 2 5" -> 0x13).
uint8_t Channels(std::string_view channels);

// The byte with the format's parity in the eighth bit (ISO, 7 data bits); EIA and 8-bit codes unchanged.
uint8_t WithParity(const Format& f, uint8_t code);

// A transfer's bytes: leader, the program in the control's code, the end-of-data code, trailer. Throws
// Error(kInvalidArgument) "line L column C: 'x' has no <code> code on <control>" for a character the
// control's table does not define.
std::vector<uint8_t> Encode(const Format& f, std::string_view text);

// Reads a transfer as it arrives: Feed the bytes in order; the text grows until the end-of-data code (or,
// for End::kNul, the first NUL after the program) completes it. Throws Error(kInvalidArgument) "byte N:
// parity error (0xHH)" or "byte N: 0xHH is not a <code> code on <control>", N counting from the first byte
// fed. Without the end code the transfer is incomplete (still under way, or cut).
class Decoder {
 public:
  explicit Decoder(Format f);
  // Consumes bytes up to the end code; returns how many it used (fewer than given once complete).
  size_t Feed(std::span<const uint8_t> bytes);
  bool complete() const { return complete_; }
  const std::string& text() const { return text_; }
  size_t offset() const { return offset_; }  // bytes consumed so far

 private:
  bool Take(uint8_t b);  // true when b completed the transfer
  uint8_t Checked(uint8_t b) const;
  [[noreturn]] void Bad(uint8_t b, std::string_view why) const;
  void Char(uint8_t c);
  void EndBlock();

  Format f_;
  std::string text_;
  size_t offset_ = 0;
  uint8_t raw_ = 0;  // the byte as it arrived, for messages
  bool complete_ = false;
  bool started_ = false;     // past the leader
  bool block_start_ = true;  // the next character begins a block
  bool first_block_ = true;
  bool comment_ = false;      // EMCO: between brackets
  bool pending_cr_ = false;   // EMCO: CR waiting for its LF
  bool pending_pct_ = false;  // KT-APL EIA: % at a block's start, '%' or '(' by what follows
  bool kt_open_ = false;      // KT-APL EIA: inside a Type II statement
};

// The whole transfer in `bytes` (Decoder over all of them).
struct Decoded {
  std::string text;
  bool complete = false;
  size_t consumed = 0;
};
Decoded Decode(const Format& f, std::span<const uint8_t> bytes);

}  // namespace cell::dnc
