// The controls' codes (docs/dnc.md "Codes"). A table maps each text character to its code without parity;
// Encode and Decode add and check the parity and frame the program with leader, end code and trailer.
#include "cell/dnc/codes.h"

#include <array>
#include <bit>
#include <optional>

#include <fmt/format.h>

namespace cell::dnc {
namespace {

constexpr uint8_t kNul = 0x00;
constexpr uint8_t kLf = 0x0A;
constexpr uint8_t kCr = 0x0D;
constexpr uint8_t kCtrlZ = 0x1A;
constexpr uint8_t kEiaEob = 0x80;  // channel 8
constexpr uint8_t kEiaPercent = 0x0B;

// EIA RS-244: digits and letters (the letter's text is upper case; the standard's tape has one case).
struct EiaRow {
  char text;
  std::string_view channels;
};
constexpr std::array<EiaRow, 49> kEia = {{
    {'0', "6"},         {'1', "1"},          {'2', "2"},         {'3', "1 2 5"},     {'4', "3"},
    {'5', "1 3 5"},     {'6', "2 3 5"},      {'7', "1 2 3"},     {'8', "4"},         {'9', "1 4 5"},
    {'A', "1 6 7"},     {'B', "2 6 7"},      {'C', "1 2 5 6 7"}, {'D', "3 6 7"},     {'E', "1 3 5 6 7"},
    {'F', "2 3 5 6 7"}, {'G', "1 2 3 6 7"},  {'H', "4 6 7"},     {'I', "1 4 5 6 7"}, {'J', "1 5 7"},
    {'K', "2 5 7"},     {'L', "1 2 7"},      {'M', "3 5 7"},     {'N', "1 3 7"},     {'O', "2 3 7"},
    {'P', "1 2 3 5 7"}, {'Q', "4 5 7"},      {'R', "1 4 7"},     {'S', "2 5 6"},     {'T', "1 2 6"},
    {'U', "3 5 6"},     {'V', "1 3 6"},      {'W', "2 3 6"},     {'X', "1 2 3 5 6"}, {'Y', "4 5 6"},
    {'Z', "1 4 6"},     {' ', "5"},          {'+', "5 6 7"},     {'-', "7"},         {'.', "1 2 4 6 7"},
    {',', "1 2 4 5 6"}, {'/', "1 5 6"},      {'%', "1 2 4"},     {'(', "2 4 5"},     {')', "2 4 7"},
    {'\b', "2 4 6"},    {'\t', "2 3 4 5 6"}, {'\n', "8"},        {'=', "2 3 4 5 7"},
}};

bool IsEmcoProgramChar(char c) {
  // The translating chart's characters with an ISO interpretation (ln 5704-5781), either case for letters
  // (41,61 ...), and '=' of the program format (ln 5659-5661).
  static constexpr std::string_view kChars = " %()-./0123456789DFGIJKLMNOPRSTUVWXYZ=";
  char up = (c >= 'a' && c <= 'z') ? static_cast<char>(c - 32) : c;
  return kChars.find(up) != std::string_view::npos &&
         (up == c || std::isalpha(static_cast<unsigned char>(c)));
}

std::string_view CodeTitle(const Format& f) {
  if (f.code == Code::kEia) return "EIA RS-244";
  if (f.control == Control::kOkuma) return f.data_bits == 8 ? "JIS 8-bit" : "JIS 7-bit";
  if (f.control == Control::kEmco) return "ISO (EMCO translating chart)";
  return f.control == Control::kKtApl ? "ASCII RS-358" : "ISO 840";
}

// The code of one text character without parity, or nullopt. `in_comment` widens EMCO's set (the control
// drops what is between brackets, ln 5634).
std::optional<uint8_t> CodeOf(const Format& f, char c, bool in_comment) {
  if (f.code == Code::kEia) {
    if (c == '=' && f.control != Control::kKtApl) return std::nullopt;               // KT-APL only, ln 3187
    if ((c == '(' || c == ')') && f.control == Control::kKtApl) return kEiaPercent;  // ln 3115-3126
    for (const auto& r : kEia)
      if (r.text == c) return Channels(r.channels);
    return std::nullopt;
  }
  auto u = static_cast<unsigned char>(c);
  if (c == '\n') return kLf;
  bool printable = u >= 0x20 && u <= 0x7E;
  if (f.control == Control::kEmco) {
    if (printable && (in_comment || IsEmcoProgramChar(c))) return u;
    return std::nullopt;
  }
  if (printable || c == '\t') return u;
  return std::nullopt;
}

}  // namespace

Control ControlOf(std::string_view dialect) {
  if (dialect == "ktapl") return Control::kKtApl;
  if (dialect == "balt") return Control::kBalt;
  if (dialect == "emco") return Control::kEmco;
  if (dialect == "okuma") return Control::kOkuma;
  throw Error(Errc::kInvalidArgument,
              fmt::format("dialect '{}' has no DNC code (ktapl, balt, emco, okuma)", dialect));
}

std::string_view ControlName(Control c) {
  switch (c) {
    case Control::kKtApl:
      return "KT-APL";
    case Control::kBalt:
      return "Balt-System";
    case Control::kEmco:
      return "EMCOTRONIC";
    case Control::kOkuma:
      return "OSP-E100L";
  }
  return "?";
}

std::string_view CodeName(Code c) {
  return c == Code::kEia ? "eia" : "iso";
}

std::string_view ParityName(Parity p) {
  switch (p) {
    case Parity::kNone:
      return "none";
    case Parity::kEven:
      return "even";
    case Parity::kOdd:
      return "odd";
  }
  return "?";
}

std::string_view EndName(End e) {
  switch (e) {
    case End::kNul:
      return "nul";
    case End::kCtrlZ:
      return "ctrl-z";
    case End::kPercent:
      return "%";
  }
  return "?";
}

uint8_t Channels(std::string_view channels) {
  uint8_t b = 0;
  for (char c : channels)
    if (c >= '1' && c <= '8') b |= static_cast<uint8_t>(1u << (c - '1'));
  return b;
}

uint8_t WithParity(const Format& f, uint8_t code) {
  if (f.code == Code::kEia || f.data_bits == 8 || f.parity == Parity::kNone) return code;
  bool odd_ones = std::popcount(static_cast<unsigned>(code & 0x7F)) % 2 == 1;
  bool set = f.parity == Parity::kEven ? odd_ones : !odd_ones;
  return static_cast<uint8_t>((code & 0x7F) | (set ? 0x80 : 0));
}

namespace {

std::vector<uint8_t> Eob(const Format& f) {
  if (f.code == Code::kEia) return {kEiaEob};
  if (f.control == Control::kEmco) return {kCr, kLf};  // "crlf", ln 5659-5661
  return {kLf};                                        // Okuma ISO "LF", ln 544-546
}

std::string_view Source(const Format& f, char c) {
  if (f.code == Code::kEia) {
    if (c == '=') return "KT-APL ln 3187 (channels 2 3 4 5 7)";
    if ((c == '(' || c == ')') && f.control == Control::kKtApl) return "KT-APL ln 3115-3126 (% in EIA)";
    if (c == '\n') return f.control == Control::kOkuma ? "RS-244 EOB; OSP ln 544-546" : "RS-244 EOB";
    return "RS-244";
  }
  if (c == '\n')
    return f.control == Control::kEmco ? "EMCO ln 5659-5661 (crlf)" : "ISO 840 LF; OSP ln 544-546";
  if (f.control == Control::kEmco) return "EMCO ln 5704-5781";
  if (f.control == Control::kOkuma) return "OSP ln 8091-8094 (JIS X 0201 roman)";
  return f.control == Control::kKtApl ? "KT-APL ln 3115 (RS-358)" : "Balt ln 348 (ISO 840)";
}

}  // namespace

std::vector<CodeRow> Table(const Format& f) {
  std::vector<CodeRow> rows;
  auto add = [&](char c) {
    if (c == '\n') {
      rows.push_back({c, Eob(f), Source(f, c)});
    } else if (auto code = CodeOf(f, c, false)) {
      rows.push_back({c, {*code}, Source(f, c)});
    }
  };
  if (f.code == Code::kEia) {
    for (const auto& r : kEia) add(r.text);
  } else {
    add('\t');
    for (int c = 0x20; c <= 0x7E; ++c) add(static_cast<char>(c));
    add('\n');
  }
  return rows;
}

namespace {

[[noreturn]] void RefuseChar(const Format& f, std::string_view text, size_t at, std::string_view why = {}) {
  size_t line = 1, col = 1;
  for (size_t i = 0; i < at; ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  auto u = static_cast<unsigned char>(text[at]);
  std::string shown = u >= 0x20 && u < 0x7F ? fmt::format("'{}'", text[at]) : fmt::format("0x{:02X}", u);
  throw Error(Errc::kInvalidArgument, fmt::format("line {} column {}: {} has no {} code on {}{}", line, col,
                                                  shown, CodeTitle(f), ControlName(f.control), why));
}

// The program without a closing "%" block (End::kPercent sends its own), ending in an end of block.
std::string_view BodyOf(const Format& f, std::string_view text) {
  if (f.end != End::kPercent) return text;
  std::string_view t = text;
  if (t.ends_with("\n%\n"))
    t.remove_suffix(2);
  else if (t.ends_with("\n%"))
    t.remove_suffix(1);
  return t;
}

void AppendBody(const Format& f, std::string_view text, std::vector<uint8_t>& out) {
  bool comment = false;
  bool kt_eia = f.code == Code::kEia && f.control == Control::kKtApl;
  for (size_t i = 0; i < text.size(); ++i) {
    char c = text[i];
    if (c == '\n') {
      for (uint8_t b : Eob(f)) out.push_back(WithParity(f, b));
      comment = false;
      continue;
    }
    bool alone = (i == 0 || text[i - 1] == '\n') && (i + 1 == text.size() || text[i + 1] == '\n');
    if (kt_eia && c == '%' && !alone)
      RefuseChar(f, text, i, " inside a block (EIA % is control out/in, ln 5344)");
    if (f.end == End::kPercent && c == '%' && alone && i != 0) {
      RefuseChar(f, text, i, " before the end (it would end the transfer)");
    }
    auto code = CodeOf(f, c, comment);
    if (!code) RefuseChar(f, text, i);
    out.push_back(WithParity(f, *code));
    if (c == '(') comment = true;
    if (c == ')') comment = false;
  }
}

}  // namespace

std::vector<uint8_t> Encode(const Format& f, std::string_view text) {
  if (f.code == Code::kEia && f.end == End::kCtrlZ) {
    throw Error(Errc::kInvalidArgument, "EIA RS-244 has no ctrl-Z end of data: use nul or %");
  }
  std::vector<uint8_t> out(static_cast<size_t>(f.leader), kNul);
  std::string_view body = BodyOf(f, text);
  AppendBody(f, body, out);
  if (f.end == End::kPercent) {
    if (!body.empty() && !body.ends_with('\n')) {
      for (uint8_t b : Eob(f)) out.push_back(WithParity(f, b));
    }
    out.push_back(f.code == Code::kEia ? kEiaPercent : WithParity(f, '%'));
    for (uint8_t b : Eob(f)) out.push_back(WithParity(f, b));
  } else if (f.end == End::kCtrlZ) {
    out.push_back(WithParity(f, kCtrlZ));
  }
  out.insert(out.end(), static_cast<size_t>(std::max(f.leader, f.end == End::kNul ? 1 : 0)), kNul);
  return out;
}

Decoder::Decoder(Format f) : f_(f) {}

size_t Decoder::Feed(std::span<const uint8_t> bytes) {
  size_t used = 0;
  while (used < bytes.size() && !complete_) {
    complete_ = Take(bytes[used]);
    ++used;
    ++offset_;
  }
  return used;
}

void Decoder::Bad(uint8_t b, std::string_view why) const {
  throw Error(Errc::kInvalidArgument, fmt::format("byte {}: {} (0x{:02X})", offset_, why, b));
}

uint8_t Decoder::Checked(uint8_t b) const {
  if (f_.code == Code::kEia) {
    // Blank tape (NUL) has no holes; every character has an odd number (channel 5).
    if (f_.parity != Parity::kNone && std::popcount(static_cast<unsigned>(b)) % 2 == 0)
      Bad(b, "parity error");
    return b;
  }
  if (f_.data_bits == 8) return b;  // the UART checks a ninth bit; nothing in the byte to check
  if (f_.parity != Parity::kNone && WithParity(f_, b & 0x7F) != b) Bad(b, "parity error");
  return b & 0x7F;
}

bool Decoder::Take(uint8_t b) {
  if (!started_) {
    if (b == kNul) return false;  // leader
    started_ = true;
  }
  if (b == kNul) {
    if (f_.end != End::kNul) Bad(b, "NUL inside the program");
    if (pending_cr_) Bad(b, "CR without LF");
    if (pending_pct_) text_ += '%';
    return true;
  }
  raw_ = b;
  uint8_t c = Checked(b);
  if (pending_cr_) {
    pending_cr_ = false;
    if (c != kLf) Bad(b, "CR without LF (the end of block is CR LF)");
    EndBlock();
    return false;
  }
  if (pending_pct_) {
    pending_pct_ = false;
    if (c == kEiaEob) {
      text_ += '%';
    } else {
      text_ += '(';
      kt_open_ = true;
    }
  }
  if (f_.end == End::kCtrlZ && c == kCtrlZ) return true;
  uint8_t pct = f_.code == Code::kEia ? kEiaPercent : '%';
  if (f_.end == End::kPercent && block_start_ && !first_block_ && c == pct) {
    text_ += "%\n";
    return true;
  }
  Char(c);
  return false;
}

void Decoder::EndBlock() {
  text_ += '\n';
  block_start_ = true;
  first_block_ = false;
  comment_ = false;
  kt_open_ = false;
}

void Decoder::Char(uint8_t c) {
  bool eob = f_.code == Code::kEia ? c == kEiaEob : c == kLf;
  if (f_.control == Control::kEmco && f_.code == Code::kIso && c == kCr) {
    pending_cr_ = true;
    return;
  }
  if (eob && f_.control == Control::kEmco && f_.code == Code::kIso) Bad(raw_, "LF without CR");
  if (eob) {
    EndBlock();
    return;
  }
  if (f_.code == Code::kEia && f_.control == Control::kKtApl && c == kEiaPercent) {
    if (block_start_ && !kt_open_) {
      pending_pct_ = true;
    } else {
      text_ += kt_open_ ? ')' : '(';
      kt_open_ = !kt_open_;
    }
    block_start_ = false;
    return;
  }
  std::optional<char> ch;
  if (f_.code == Code::kEia) {
    for (const auto& r : kEia)
      if (CodeOf(f_, r.text, false) == c) ch = r.text;
  } else if (CodeOf(f_, static_cast<char>(c), comment_) == c) {
    ch = static_cast<char>(c);
  }
  if (!ch) Bad(raw_, fmt::format("not a {} code on {}", CodeTitle(f_), ControlName(f_.control)));
  text_ += *ch;
  if (*ch == '(') comment_ = true;
  if (*ch == ')') comment_ = false;
  block_start_ = false;
}

Decoded Decode(const Format& f, std::span<const uint8_t> bytes) {
  Decoder d(f);
  d.Feed(bytes);
  return {d.text(), d.complete(), d.offset()};
}

}  // namespace cell::dnc
