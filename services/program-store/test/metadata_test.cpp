#include "cell/program_store/metadata.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

#include "cell/error/error.h"

namespace cell::program_store {
namespace {

const Dialect kNone = nullptr;
const Dialect kKtapl = interp::FindDialect("ktapl");
const Dialect kOkuma = interp::FindDialect("okuma");
const Dialect kEmco = interp::FindDialect("emco");
const Dialect kBalt = interp::FindDialect("balt");

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

// Runs `fn`, expecting a cell::Error with `code` whose message contains `needle`.
template <typename Fn>
void ExpectError(Fn fn, Errc code, const std::string& needle) {
  try {
    fn();
    ADD_FAILURE() << "expected an error containing '" << needle << "'";
  } catch (const cell::Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_THAT(e.what(), HasSubstr(needle));
  }
}

ExtractOptions Opts(std::optional<Dialect> dialect, std::optional<FileType> type, std::string name) {
  ExtractOptions o;
  o.dialect = dialect;
  o.type = type;
  o.name = std::move(name);
  return o;
}

std::string Joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += x + "\n";
  return s;
}

constexpr const char* kFmsProgram =
    "%\n"
    "(NAM, GEAR HOUSING)\n"
    "(UTL,12,T3,4567)\n"
    "(UCY,840)\n"
    "N10 G0 G90 XL1500 Y10. S400 F0 M3\n"
    "N20 (PAR, L25 = 123.456) ! set a parameter\n"
    "N30 M30\n";

TEST(Ktapl, FmsHeadingIsExtracted) {
  Metadata md = ExtractMetadata(kFmsProgram, {});
  EXPECT_EQ(md.dialect, kKtapl);
  EXPECT_TRUE(md.dialect_detected);
  EXPECT_EQ(md.type, FileType::kPartProgram);
  EXPECT_EQ(md.nam, "GEAR HOUSING");
  EXPECT_THAT(md.utl, ElementsAre("12", "3", "4567"));
  ASSERT_TRUE(md.ucy_s.has_value());
  EXPECT_DOUBLE_EQ(*md.ucy_s, 840);
  EXPECT_EQ(md.lines, 7u);
  EXPECT_EQ(md.size, std::string(kFmsProgram).size());
  EXPECT_THAT(md.warnings, IsEmpty()) << Joined(md.warnings);
}

// The heading rules themselves are cell_ktapl_meta's (ktapl_meta_test); the store keeps every warning as a
// line of text and asks for the part-program rule only for part programs.
TEST(Ktapl, HeadingWarningsAreKeptAsLines) {
  Metadata md = ExtractMetadata("%\n(UTL,12,X7)\n(UCY,30.5)\nN1 M30\n", {});
  EXPECT_THAT(md.utl, ElementsAre("12"));
  EXPECT_DOUBLE_EQ(md.ucy_s.value_or(0), 30.5);
  EXPECT_THAT(
      md.warnings,
      ElementsAre(
          "line 2: UTL entry 'X7' is not a tool number (up to 7 digits, optionally prefixed with T)"));

  md = ExtractMetadata("(UTL,1)\n(UCY,2)\nN7 M30\n", {});
  EXPECT_THAT(md.warnings,
              ElementsAre(HasSubstr("line 1: (UTL,...) must come right after %"),
                          "the FMS heading must start with a % line (rewind stop) before NAM, UTL and UCY"));

  // UTL without UCY in a part program, not in a library.
  md = ExtractMetadata("%\n(UTL,1)\nN1 M30\n", {});
  EXPECT_EQ(md.type, FileType::kPartProgram);
  EXPECT_THAT(Joined(md.warnings), HasSubstr("line 2: (UTL,...) without (UCY,...)"));
  md = ExtractMetadata("%\n(UTL,1)\nN1 M30\n", Opts(kKtapl, FileType::kLibrary, ""));
  EXPECT_THAT(md.warnings, IsEmpty()) << Joined(md.warnings);
}

TEST(Ktapl, ToolTableAndLibraryTypes) {
  Metadata tools = ExtractMetadata("(TLD,T12,L5.5,D.5)\n(TLD,T13,L6.,D1.)\n", {});
  EXPECT_EQ(tools.dialect, kKtapl);
  EXPECT_EQ(tools.type, FileType::kToolTable);
  Metadata lib = ExtractMetadata("N60 (DFC,G881) !An example\nN70 G1 Z-1. F10.\nN80 (END)\n", {});
  EXPECT_EQ(lib.type, FileType::kLibrary);
  // Definitions followed by blocks that use them (even without M30) make a part program.
  Metadata uses =
      ExtractMetadata("(DFS,B.C.,SAVE)\n(LBL,1)G0 X1.\n(LBL,2)(END)\nN10 G0 X10. F0\nN20 (CLS,B.C.)\n", {});
  EXPECT_EQ(uses.type, FileType::kPartProgram);
  Metadata two = ExtractMetadata("(DFS,A)\nG0 X1.\n(END)\n! between\n(DFC,G881)\nG1 Z-1.\n(END)\n", {});
  EXPECT_EQ(two.type, FileType::kLibrary);
}

TEST(Okuma, ProgramNamesAndTypes) {
  Metadata md =
      ExtractMetadata("$A.MIN%\nO1234\nN1 G00 X100 Z100\nNAT01 G81\nN2 M02\nOPP1 (SECOND)\nN3 M02\n", {});
  EXPECT_EQ(md.dialect, kOkuma);
  EXPECT_EQ(md.type, FileType::kPartProgram);
  EXPECT_THAT(md.program_names, ElementsAre("O1234", "OPP1"));

  Metadata sub = ExtractMetadata("O1000\nN1000 CALL O1234 XP1=150\nN1010 RTS\n", {});
  EXPECT_EQ(sub.type, FileType::kLibrary);
  EXPECT_THAT(sub.program_names, ElementsAre("O1000"));

  Metadata sched = ExtractMetadata("N010 PSELECT A.MIN,O100,,Q=20\nN020 VSET V1=V1+1\nEND\n", {});
  EXPECT_EQ(sched.dialect, kOkuma);
  EXPECT_EQ(sched.type, FileType::kSchedule);

  Metadata dup = ExtractMetadata("O100\nVSET V1=1\nM02\nO100\nM02\n", {});
  EXPECT_THAT(Joined(dup.warnings), HasSubstr("program name O100 appears again"));
}

TEST(Okuma, ScheduleByNameIsOkumaAndOtherDialectsAreRefused) {
  Metadata md =
      ExtractMetadata("PSELECT A.MIN,O100,,Q=2\nEND\n", Opts(std::nullopt, std::nullopt, "SHAFT-1.SDF"));
  EXPECT_EQ(md.type, FileType::kSchedule);
  EXPECT_EQ(md.dialect, kOkuma);
  ExpectError([] { ExtractMetadata("END\n", Opts(kKtapl, FileType::kSchedule, "")); }, Errc::kInvalidArgument,
              "schedule files are Okuma OSP-E100L files, not ktapl");
}

TEST(Emco, PercentAndFourDigitBlocksWithCycles) {
  Metadata md = ExtractMetadata(
      "%\nO0010\nN0000 G54\nN0010 G00 X32.000 Z2.000\nN0020 G84 X20.000 Z-30.000 D3=500 F0.2\nN0030 M30\n",
      {});
  EXPECT_EQ(md.dialect, kEmco);
  EXPECT_EQ(md.type, FileType::kPartProgram);
  EXPECT_THAT(md.program_names, ElementsAre("O0010"));
  // Without D parameters: the 4-digit block structure with a lathe cycle is enough.
  Metadata plain =
      ExtractMetadata("%\nN0000 G00 X32 Z2\nN0010 G84 X20 Z-30 F0.2\nN0020 G00 X40\nN0030 M30\n", {});
  EXPECT_EQ(plain.dialect, kEmco);
  // A program may also begin with its O number instead of %.
  Metadata o_first = ExtractMetadata("O0020\nN0000 G00 X32 Z2\nN0010 G86 X20 Z-30 F0.2\nN0020 M30\n", {});
  EXPECT_EQ(o_first.dialect, kEmco);
  EXPECT_THAT(o_first.program_names, ElementsAre("O0020"));
  // Mixed block-number widths are not EMCO's N4 format.
  ExpectError(
      [] { ExtractMetadata("%\nN0000 G00 X32 Z2\nN10 G84 X20 Z-30 F0.2\nN0020 G0 X1\nN30 M30\n", {}); },
      Errc::kInvalidArgument, "cannot tell the dialect");
  Metadata sub = ExtractMetadata("%\nN0000 G01 X10 Z-2 P0 = 10.000\nN0010 M17\n", {});
  EXPECT_EQ(sub.type, FileType::kLibrary);
}

TEST(Balt, ProgramHeaderAndStatements) {
  Metadata md = ExtractMetadata(
      "%:V1ISO\n;VIRTUALIZATION 1 IN ISO PROGR.\nT0.1M6\nE40=110*180/(3.14159*800)\n(UAV, 1, XC, PW, "
      "E40)\nM30\n%\n",
      {});
  EXPECT_EQ(md.dialect, kBalt);
  EXPECT_THAT(md.program_names, ElementsAre("V1ISO"));
  Metadata dis = ExtractMetadata("%\nN1 (DIS,\"TWIST DRILL D6\")\nN2 T1.1 M6 S800\nN237 M30\n%\n", {});
  EXPECT_EQ(dis.dialect, kBalt);
}

TEST(Detection, AmbiguousAndUnknownGiveClearErrors) {
  ExpectError(
      [] { ExtractMetadata("%\n(NAM,MIXED)\nN10 VSET V1=2\nN20 M30\n", {}); }, Errc::kInvalidArgument,
      "cannot tell the dialect: the content fits more than one: ktapl ((NAM,...) statement on line 2); "
      "okuma (VSET statement on line 3)");
  ExpectError([] { ExtractMetadata("G0 X0 Y0\nG1 X10 F100\nM30\n", {}); }, Errc::kInvalidArgument,
              "looks like an NC program but has no dialect-specific statement");
  ExpectError([] { ExtractMetadata("hello\n", Opts(std::nullopt, FileType::kPartProgram, "")); },
              Errc::kInvalidArgument, "declare it (--dialect");
  Detection det = DetectDialect("%\n(NAM,MIXED)\nN10 VSET V1=2\n");
  EXPECT_TRUE(det.ambiguous);
  EXPECT_EQ(det.dialect, kNone);
}

TEST(Detection, DeclaredDialectWinsButMismatchWarns) {
  Metadata md = ExtractMetadata(kFmsProgram, Opts(kOkuma, std::nullopt, ""));
  EXPECT_EQ(md.dialect, kOkuma);
  EXPECT_FALSE(md.dialect_detected);
  EXPECT_THAT(Joined(md.warnings), HasSubstr("declared dialect okuma, but the content looks like ktapl"));
  // A plain G-code file is fine once the dialect is declared.
  Metadata plain = ExtractMetadata("G0 X0\nM30\n", Opts(kEmco, std::nullopt, ""));
  EXPECT_EQ(plain.dialect, kEmco);
  EXPECT_THAT(plain.warnings, IsEmpty());
}

TEST(Detection, StationDialectIsTheFallback) {
  ExtractOptions kt;
  kt.namespace_dialect = kKtapl;
  // Nothing dialect-specific: the station's dialect.
  Metadata plain = ExtractMetadata("N10 G0 X1. F0\nN20 M30\n", kt);
  EXPECT_EQ(plain.dialect, kKtapl);
  EXPECT_EQ(plain.type, FileType::kPartProgram);
  EXPECT_THAT(plain.warnings, IsEmpty());
  // A clear detection wins over the station.
  Metadata okuma = ExtractMetadata("O100\nVSET V1=1\nM02\n", kt);
  EXPECT_EQ(okuma.dialect, kOkuma);
  // Ambiguous, and the station's dialect is one of the candidates: taken, with a warning.
  Metadata mixed = ExtractMetadata("%\n(NAM,MIXED)\nN10 VSET V1=2\nN20 M30\n", kt);
  EXPECT_EQ(mixed.dialect, kKtapl);
  EXPECT_THAT(Joined(mixed.warnings), HasSubstr("took ktapl, the dialect of the station namespace"));
  // Ambiguous between two others: still an error.
  ExtractOptions emco;
  emco.namespace_dialect = kEmco;
  ExpectError([&] { ExtractMetadata("%\n(NAM,MIXED)\nN10 VSET V1=2\nN20 M30\n", emco); },
              Errc::kInvalidArgument, "cannot tell the dialect");
  // Plain text stays data.
  Metadata data = ExtractMetadata("just some notes\n", kt);
  EXPECT_EQ(data.type, FileType::kData);
  EXPECT_EQ(data.dialect, kNone);
}

TEST(Detection, PlainTextIsData) {
  Metadata md = ExtractMetadata("part,feature,nominal,actual\n1,BORE A,25.000,25.004\n", {});
  EXPECT_EQ(md.type, FileType::kData);
  EXPECT_EQ(md.dialect, kNone);
  Metadata insp = ExtractMetadata("G26 X1\n", Opts(std::nullopt, FileType::kInspection, ""));
  EXPECT_EQ(insp.type, FileType::kInspection);
  EXPECT_EQ(insp.dialect, kNone);
}

TEST(Detection, PartModelIsCheckedAtThePut) {
  Metadata md = ExtractMetadata("[[plane]]\npoint = [0, 0, 50]\nnormal = [0, 0, 1]\n",
                                Opts(std::nullopt, FileType::kPartModel, "PALLET7 PART"));
  EXPECT_EQ(md.type, FileType::kPartModel);
  EXPECT_EQ(md.dialect, kNone);
  // The model's own error, with the name it is stored under, line and column.
  ExpectError(
      [] { ExtractMetadata("[[plane]]\npoint = [0, 0\n", Opts(std::nullopt, FileType::kPartModel, "BAD")); },
      Errc::kInvalidArgument, "BAD:2:");
}

TEST(Text, BinaryContentIsRejected) {
  ExpectError([] { CheckText(std::string("G0\0X1", 5)); }, Errc::kInvalidArgument,
              "content is not text: control byte 0x00 at offset 2");
  ExpectError([] { CheckText("ok\x01"); }, Errc::kInvalidArgument, "control byte 0x01");
  ExpectError([] { CheckText("caf\xe9\n"); }, Errc::kInvalidArgument, "invalid UTF-8 byte 0xe9 at offset 3");
  ExpectError([] { CheckText("\xe2\x82"); }, Errc::kInvalidArgument, "invalid UTF-8");
  CheckText("");
  CheckText("Winkel 45\xc2\xb0, \xce\xbcm\r\n\tTAB\f\x1a");
  ExpectError([] { ExtractMetadata(std::string("\x89PNG\r\n\x1a\n\0\0", 10), {}); }, Errc::kInvalidArgument,
              "not text");
}

TEST(Names, KtaplRules) {
  ValidateName("GEAR HOUSING", FileType::kPartProgram, kKtapl);
  ValidateName("PALLET38;FXT", FileType::kFixtureOffsets, kKtapl);
  ValidateName("PALLET38;FXT", FileType::kFixtureOffsets, kNone);
  ValidateName("MFD;SYS", FileType::kData, kKtapl);
  ValidateName(std::string(32, 'A'), FileType::kPartProgram, kKtapl);
  ValidateName(std::string(28, 'B') + ";FXT", FileType::kFixtureOffsets, kKtapl);
  ExpectError([] { ValidateName("", FileType::kPartProgram, kKtapl); }, Errc::kInvalidArgument,
              "empty KT-APL name");
  ExpectError([] { ValidateName(std::string(33, 'A'), FileType::kPartProgram, kKtapl); },
              Errc::kInvalidArgument, "too long: 33 characters");
  ExpectError([] { ValidateName(std::string(29, 'B') + ";FXT", FileType::kFixtureOffsets, kKtapl); },
              Errc::kInvalidArgument, "at most 28");
  ExpectError([] { ValidateName("PUMP,341", FileType::kPartProgram, kKtapl); }, Errc::kInvalidArgument,
              "contains a comma");
  ExpectError([] { ValidateName("A;TOOLONG", FileType::kPartProgram, kKtapl); }, Errc::kInvalidArgument,
              "extension after ';'");
  ExpectError([] { ValidateName("PALLET38", FileType::kFixtureOffsets, kKtapl); }, Errc::kInvalidArgument,
              "must end in ;FXT");
  ExpectError([] { ValidateName(" LEAD", FileType::kPartProgram, kKtapl); }, Errc::kInvalidArgument,
              "leading or trailing spaces");
  ExpectError([] { ValidateName("A*", FileType::kPartProgram, kKtapl); }, Errc::kInvalidArgument, "wildcard");
  ExpectError([] { ValidateName("A/B", FileType::kPartProgram, kKtapl); }, Errc::kInvalidArgument,
              "path separator");
  ExpectError([] { ValidateName("A\tB", FileType::kPartProgram, kKtapl); }, Errc::kInvalidArgument,
              "non-printable");
  ExpectError([] { ValidateName("A#B", FileType::kPartProgram, kKtapl); }, Errc::kInvalidArgument,
              "contains '#'");
}

TEST(Names, OkumaEmcoBaltAndGenericRules) {
  ValidateName("A.MIN", FileType::kPartProgram, kOkuma);
  ValidateName("SHAFT-1.SDF", FileType::kSchedule, kOkuma);
  ValidateName("SHAFT-ABC.SUB", FileType::kLibrary, kOkuma);
  ValidateName(std::string(16, 'P'), FileType::kPartProgram, kOkuma);
  ExpectError([] { ValidateName("1SHAFT.MIN", FileType::kPartProgram, kOkuma); }, Errc::kInvalidArgument,
              "must begin with a letter");
  ExpectError([] { ValidateName(std::string(17, 'P') + ".MIN", FileType::kPartProgram, kOkuma); },
              Errc::kInvalidArgument, "at most 16");
  ExpectError([] { ValidateName("MD1:A.MIN", FileType::kPartProgram, kOkuma); }, Errc::kInvalidArgument,
              "device prefixes");
  ExpectError([] { ValidateName("A B.MIN", FileType::kPartProgram, kOkuma); }, Errc::kInvalidArgument,
              "contains ' '");
  ValidateName("O0010", FileType::kPartProgram, kEmco);
  ValidateName("turn-1.nc", FileType::kPartProgram, kEmco);
  ExpectError([] { ValidateName(std::string(33, 'E'), FileType::kPartProgram, kEmco); },
              Errc::kInvalidArgument, "at most 32");
  ExpectError([] { ValidateName("V1 ISO", FileType::kPartProgram, kBalt); }, Errc::kInvalidArgument,
              "contains ' '");
  ValidateName("inspection run 7; pallet 3, op 10.txt", FileType::kInspection, kNone);
  ValidateName(std::string(128, 'd'), FileType::kData, kNone);
  ExpectError([] { ValidateName(std::string(129, 'd'), FileType::kData, kNone); }, Errc::kInvalidArgument,
              "too long");
  ExpectError([] { ValidateName("", FileType::kData, kNone); }, Errc::kInvalidArgument, "empty");
}

TEST(Names, TypeFromNameAndParsing) {
  EXPECT_EQ(TypeFromName("PALLET38;FXT"), FileType::kFixtureOffsets);
  EXPECT_EQ(TypeFromName("shaft-1.sdf"), FileType::kSchedule);
  EXPECT_EQ(TypeFromName("X.SUB"), FileType::kLibrary);
  EXPECT_EQ(TypeFromName("A.MIN"), FileType::kPartProgram);
  EXPECT_EQ(TypeFromName("GEAR HOUSING"), std::nullopt);
  EXPECT_EQ(TypeFromName(";FXT"), std::nullopt);
  EXPECT_EQ(ParseDialect("KT-APL"), kKtapl);
  EXPECT_EQ(ParseDialect("okuma"), kOkuma);
  EXPECT_EQ(ParseDialect("emco"), kEmco);
  EXPECT_EQ(ParseDialect("balt"), kBalt);
  ExpectError([] { ParseDialect("fanuc"); }, Errc::kInvalidArgument, "unknown dialect 'fanuc'");
  EXPECT_EQ(ParseFileType("fxt"), FileType::kFixtureOffsets);
  EXPECT_EQ(ParseFileType("part_program"), FileType::kPartProgram);
  for (FileType t :
       {FileType::kPartProgram, FileType::kLibrary, FileType::kSchedule, FileType::kToolTable,
        FileType::kFixtureOffsets, FileType::kInspection, FileType::kData, FileType::kPartModel}) {
    EXPECT_EQ(ParseFileType(FileTypeName(t)), t);
  }
  ExpectError([] { ParseFileType("binary"); }, Errc::kInvalidArgument, "unknown file type");
}

TEST(Misc, LinesAndDefaultName) {
  EXPECT_EQ(CountLines(""), 0u);
  EXPECT_EQ(CountLines("a"), 1u);
  EXPECT_EQ(CountLines("a\n"), 1u);
  EXPECT_EQ(CountLines("a\nb"), 2u);
  EXPECT_EQ(CountLines("\n\n"), 2u);
  Metadata md = ExtractMetadata(kFmsProgram, {});
  EXPECT_EQ(DefaultName("/tmp/x/gear.apl", md), "GEAR HOUSING");
  Metadata data = ExtractMetadata("x\n", {});
  EXPECT_EQ(DefaultName("/tmp/x/notes.txt", data), "notes.txt");
}

}  // namespace
}  // namespace cell::program_store
