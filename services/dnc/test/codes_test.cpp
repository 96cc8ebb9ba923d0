// The controls' codes (docs/dnc.md): every character each table defines round-trips, parity in the eighth
// bit, errors naming the byte offset, and the framing (leader, end of data, trailer).
#include "cell/dnc/codes.h"

#include <bit>
#include <set>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "cell/dnc/settings.h"

namespace cell::dnc {
namespace {

// Every control in each code it reads, with the parities and data bits its manual names.
std::vector<Format> AllFormats() {
  std::vector<Format> out;
  for (Control c : {Control::kKtApl, Control::kBalt, Control::kEmco, Control::kOkuma}) {
    Format iso = Defaults(c).format;
    out.push_back(iso);
    Format odd = iso;
    odd.parity = Parity::kOdd;  // EMCO O01 bit 5 low (ln 5529)
    out.push_back(odd);
    Format eight = iso;
    eight.data_bits = 8;  // Okuma JIS 8-bit (ln 8091), EMCO O01 bits 2/3 (ln 5533-5548)
    eight.parity = Parity::kNone;
    out.push_back(eight);
    if (c != Control::kEmco) {
      Format eia = iso;
      eia.code = Code::kEia;
      eia.data_bits = 8;
      eia.parity = Parity::kOdd;
      if (eia.end == End::kCtrlZ) eia.end = End::kNul;
      out.push_back(eia);
    }
  }
  return out;
}

std::string Name(const Format& f) {
  return fmt::format("{} {} {}{} end {}", ControlName(f.control), CodeName(f.code), f.data_bits,
                     ParityName(f.parity), EndName(f.end));
}

std::string Expected(const Format& f, const std::string& text) {
  return f.end == End::kPercent ? text + "%\n" : text;
}

TEST(DncCodes, EveryCharacterOfEveryTableRoundTrips) {
  for (const Format& f : AllFormats()) {
    auto rows = Table(f);
    ASSERT_FALSE(rows.empty()) << Name(f);
    for (const auto& row : rows) {
      bool kt_eia_paren =
          f.code == Code::kEia && f.control == Control::kKtApl && (row.text == '(' || row.text == ')');
      std::string text = kt_eia_paren ? "N1(MIR,X1Y1)\n" : fmt::format("N1{}\n", row.text);
      if (row.text == '\n') text = "N1\n\n";
      bool kt_eia_percent = f.code == Code::kEia && f.control == Control::kKtApl && row.text == '%';
      if (kt_eia_percent) text = "N1\n%\n";  // a rewind stop stands alone on its block
      auto bytes = Encode(f, text);
      // Leader, 'N', '1', then the row's code with the format's parity.
      ASSERT_GT(bytes.size(), static_cast<size_t>(f.leader + 2));
      if (!kt_eia_paren && !kt_eia_percent) {
        EXPECT_EQ(bytes[f.leader + 2], WithParity(f, row.wire[0])) << Name(f) << " '" << row.text << "'";
      }
      auto d = Decode(f, bytes);
      EXPECT_TRUE(d.complete) << Name(f) << " '" << row.text << "'";
      EXPECT_EQ(d.text, Expected(f, text)) << Name(f) << " '" << row.text << "'";
      // What follows the end code is trailer (and, after %, its end of block).
      for (size_t i = d.consumed; i < bytes.size(); ++i) {
        EXPECT_TRUE(bytes[i] == 0 || f.end == End::kPercent) << Name(f) << " byte " << i;
      }
    }
  }
}

TEST(DncCodes, ParityIsInTheEighthBit) {
  for (const Format& f : AllFormats()) {
    for (const auto& row : Table(f)) {
      for (uint8_t w : row.wire) {
        uint8_t b = WithParity(f, w);
        int ones = std::popcount(static_cast<unsigned>(b));
        if (f.code == Code::kEia) {
          EXPECT_EQ(ones % 2, 1) << Name(f) << " '" << row.text << "' 0x" << std::hex << int(b);
        } else if (f.data_bits == 7 && f.parity == Parity::kEven) {
          EXPECT_EQ(ones % 2, 0) << Name(f);
        } else if (f.data_bits == 7 && f.parity == Parity::kOdd) {
          EXPECT_EQ(ones % 2, 1) << Name(f);
        } else {
          EXPECT_EQ(b, w) << Name(f);
        }
      }
    }
  }
}

TEST(DncCodes, EiaCodesAreDistinctAndMatchRs244) {
  Format f = Defaults(Control::kBalt).format;
  f.code = Code::kEia;
  f.data_bits = 8;
  f.parity = Parity::kOdd;
  std::set<std::vector<uint8_t>> seen;
  for (const auto& row : Table(f)) EXPECT_TRUE(seen.insert(row.wire).second) << row.text;
  // RS-244 spot checks: 0 in channel 6, X in 1 2 3 5 6, EOB in channel 8, % (rewind stop) in 1 2 4.
  EXPECT_EQ(Channels("6"), 0x20);
  auto b = Encode(f, "X0\n");
  EXPECT_EQ(b[50], 0x37);
  EXPECT_EQ(b[51], 0x20);
  EXPECT_EQ(b[52], 0x80);
  EXPECT_EQ(Encode(f, "%\n")[50], 0x0B);
}

}  // namespace
}  // namespace cell::dnc

namespace cell::dnc {
namespace {

Format Fmt(Control c) {
  return Defaults(c).format;
}

TEST(DncCodes, AParityErrorNamesItsByteOffset) {
  for (const Format& f : AllFormats()) {
    if (f.parity == Parity::kNone) continue;
    auto bytes = Encode(f, "N10 G01 X5\n");
    size_t at = static_cast<size_t>(f.leader) + 4;  // the 'G'
    bytes[at] ^= 0x01;                              // one dropped bit: the parity no longer holds
    try {
      Decode(f, bytes);
      ADD_FAILURE() << Name(f) << ": no parity error";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind(fmt::format("byte {}: parity error", at), 0), 0u)
          << Name(f) << ": " << e.what();
    }
  }
}

TEST(DncCodes, AnUndefinedCodeNamesItsByteOffset) {
  Format f = Fmt(Control::kEmco);  // 'Q' has no ISO interpretation on the EMCOTRONIC (ln 5761)
  std::vector<uint8_t> bytes = {0, 0, WithParity(f, 'N'), WithParity(f, 'Q')};
  EXPECT_THROW(
      {
        try {
          Decode(f, bytes);
        } catch (const Error& e) {
          EXPECT_STREQ(e.what(), "byte 3: not a ISO (EMCO translating chart) code on EMCOTRONIC (0xD1)");
          throw;
        }
      },
      Error);
}

TEST(DncCodes, ACharacterWithoutACodeIsRefusedWithLineAndColumn) {
  Format eia = Fmt(Control::kBalt);
  eia.code = Code::kEia;
  eia.data_bits = 8;
  eia.parity = Parity::kOdd;
  try {
    Encode(eia, "N1 G0\nN2 X1=2\n");
    ADD_FAILURE() << "'=' sent in EIA on the Balt-System";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "line 2 column 6: '=' has no EIA RS-244 code on Balt-System");
  }
  EXPECT_THROW(Encode(eia, "N1 !note\n"), Error);
  EXPECT_THROW(Encode(Fmt(Control::kEmco), "N1 Q5\n"), Error);
}

TEST(DncCodes, KtAplEiaTypeTwoStatementsUsePercentAndTheEqualSignPunch) {
  Format f = Fmt(Control::kKtApl);
  f.code = Code::kEia;
  f.data_bits = 8;
  f.parity = Parity::kOdd;
  f.leader = 0;
  std::string text = "%\nN10(ACP, 12.5, 1 = 160)\n";
  auto b = Encode(f, text);
  // ln 3179: EIA = %ACP, XX.X, X = XXX%; ln 3187: = is channels 2 3 4 5 7.
  ASSERT_GE(b.size(), 8u);
  EXPECT_EQ(b[0], 0x0B);  // % rewind stop, alone on its block
  EXPECT_EQ(b[1], 0x80);
  EXPECT_EQ(b[5], 0x0B);  // control out
  EXPECT_NE(std::find(b.begin(), b.end(), 0x5E), b.end());
  auto d = Decode(f, b);
  EXPECT_TRUE(d.complete);
  EXPECT_EQ(d.text, text);
  EXPECT_THROW(Encode(f, "N1 X%5\n"), Error);  // a % inside a block would open a Type II statement
}

TEST(DncCodes, EmcoFramesWithLeaderCrLfCtrlZAndTrailer) {
  Format f = Fmt(Control::kEmco);  // O01 = 123, O00 bit 1: 50 NUL (ln 5521)
  std::string text = "%12\nN0000 G00 X20.000 (any text: [kept])\nM30\n";
  auto b = Encode(f, text);
  ASSERT_EQ(b.size(), 50u + text.size() + 3 + 1 + 50);  // a CR before each of 3 LFs, ctrl-Z
  for (int i = 0; i < 50; ++i) EXPECT_EQ(b[i], 0);
  EXPECT_EQ(b[50], 0xA5);             // '%' 0x25, three ones: even parity sets the eighth bit
  EXPECT_EQ(b[53], 0x8D);             // CR
  EXPECT_EQ(b[54], 0x0A);             // LF
  EXPECT_EQ(b[b.size() - 51], 0x9A);  // ctrl-Z with its parity bit
  auto d = Decode(f, b);
  EXPECT_TRUE(d.complete);
  EXPECT_EQ(d.text, text);
  EXPECT_EQ(d.consumed, b.size() - 50);
}

TEST(DncCodes, OkumaEndsAtPercentAndJis8CarriesNoParity) {
  Format f = Fmt(Control::kOkuma);
  std::string text = "%\nO1234\nN1 G00 X10\nM02\n%\n";
  auto b = Encode(f, text);
  auto d = Decode(f, b);
  EXPECT_TRUE(d.complete);
  EXPECT_EQ(d.text, text);
  // Without the closing % block the end code is added.
  EXPECT_EQ(Decode(f, Encode(f, "%\nN1\n")).text, "%\nN1\n%\n");
  Format j8 = f;
  j8.data_bits = 8;
  j8.parity = Parity::kNone;
  j8.end = End::kNul;
  auto b8 = Encode(j8, "N1 X\\5\n");
  EXPECT_EQ(b8[j8.leader + 3], 'X');
  EXPECT_EQ(Decode(j8, b8).text, "N1 X\\5\n");
  EXPECT_THROW(Decode(j8, std::vector<uint8_t>{'N', 0xB1, 0}), Error);  // katakana: not carried
}

TEST(DncCodes, ACutTransferIsIncomplete) {
  for (const Format& f : AllFormats()) {
    auto b = Encode(f, "N1 X5\nN2 Y6\n");
    b.resize(static_cast<size_t>(f.leader) + 5);
    auto d = Decode(f, b);
    EXPECT_FALSE(d.complete) << Name(f);
  }
}

TEST(DncCodes, DecoderTakesTheBytesInAnyPieces) {
  Format f = Fmt(Control::kEmco);
  std::string text = "%1\nN0010 G01 X5.000\nM30\n";
  auto b = Encode(f, text);
  Decoder d(f);
  for (uint8_t x : b) d.Feed(std::span(&x, 1));
  EXPECT_TRUE(d.complete());
  EXPECT_EQ(d.text(), text);
}

// The controls' memories (docs/dnc.md "Memory"): Balt-System 64,000 characters (ln 223, the program store's
// kMemoryCapacity), EMCOTRONIC 20 kB = 20 x 1024 = 20,480 (ln 608), OSP-E100L 320 m of tape at 10 characters
// an inch = 320,000 mm / 2.54 mm = 125,984 (ln 717-721); KT-APL none given (no check). A program of exactly
// the memory fits; one character more is refused naming the size and the limit; `memory = 0` turns it off.
TEST(DncSettings, ASendLongerThanTheControlsMemoryIsRefused) {
  EXPECT_EQ(Defaults(Control::kBalt).memory, 64000);
  EXPECT_EQ(Defaults(Control::kEmco).memory, 20480);
  EXPECT_EQ(Defaults(Control::kOkuma).memory, 125984);
  EXPECT_EQ(Defaults(Control::kKtApl).memory, 0);
  const Serial balt = Defaults(Control::kBalt);
  EXPECT_EQ(MemoryRefusal(balt, 64000), "");
  EXPECT_EQ(MemoryRefusal(balt, 64001),
            "64001 characters, more than the Balt-System memory holds (64000 characters, [serial] memory)");
  EXPECT_EQ(MemoryRefusal(Defaults(Control::kKtApl), 10000000), "");
  config::SerialTable k;
  k.device = "/dev/ttyS0";
  k.memory = 128 * 1024;  // an EMCOTRONIC with DC 5.00's 128 kB extension (ln 205-215)
  EXPECT_EQ(MemoryRefusal(Resolve(Control::kEmco, k), 100000), "");
  k.memory = 0;
  EXPECT_EQ(MemoryRefusal(Resolve(Control::kBalt, k), 1000000), "");
}

TEST(DncSettings, DefaultsAndRefusals) {
  EXPECT_EQ(Defaults(Control::kEmco).baud, 2400);
  EXPECT_EQ(Defaults(Control::kBalt).baud, 9600);
  EXPECT_EQ(Defaults(Control::kOkuma).format.end, End::kPercent);
  config::SerialTable k;
  k.device = "/dev/ttyS0";
  k.baud = 4800;
  EXPECT_EQ(Resolve(Control::kEmco, k).baud, 4800);
  k.baud = 9600;
  try {
    Resolve(Control::kEmco, k);
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "[serial] baud = 9600: EMCOTRONIC D00 accepts 150-4800 (ln 5315, alarm 870 ln 7225)");
  }
  config::SerialTable eia;
  eia.device = "/dev/ttyS1";
  eia.code = "eia";
  Serial s = Resolve(Control::kKtApl, eia);
  EXPECT_EQ(s.format.data_bits, 8);
  EXPECT_EQ(s.format.parity, Parity::kOdd);
  eia.parity = "even";
  EXPECT_THROW(Resolve(Control::kKtApl, eia), Error);
  config::SerialTable bad;
  bad.device = "/dev/ttyS0";
  bad.flow = "dtr";
  try {
    Resolve(Control::kBalt, bad);
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "[serial] flow = \"dtr\": one of xonxoff | rtscts | none");
  }
  EXPECT_THROW(Resolve(Control::kBalt, config::SerialTable{}), Error);  // no device
}

}  // namespace
}  // namespace cell::dnc
