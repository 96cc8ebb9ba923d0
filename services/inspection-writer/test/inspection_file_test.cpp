// The inspection file against the KT-APL manual (seeds/kearney-trecker-kt-apl.txt, "ln N" = its line):
// Ch. 7 examples 7-11 to 7-22 (catalogue reference/seed-ktapl-part2.md §12.3) byte for byte, and the lines
// App. E's probe cycles write. Judgement calls are docs/dialects/ktapl.md items 53-60.
#include <gtest/gtest.h>

#include "cell/inspection/inspection_file.h"

namespace cell::inspection {
namespace {

const std::string kDashes(30, '-');  // the delimiter the scan lost (ln 7908), judgement call 54

Header ManualHeader() {
  // ln 7900-7906 (and again ln 8065-8069): serial 345879, pallet code/part 3452, 13 Dec 1989 12:24.
  return {"345879", "3452", std::nullopt, {1989, 12, 13, 12, 24}};
}

const std::string kManualHeader =
    "CONTROL SERIAL NUMBER = 345879\n"
    "PALLET CODE/PART NUMBER = 3452\n"
    "89:12:13 12:24\n" +
    kDashes + "\n";

// 7-11, ln 7894-7908: N120G36 N130(OIF,PUMP341) writes the canned header, then the dashed delimiter.
TEST(InspectionFormat, Example7_11OifHeader) {
  EXPECT_EQ(FormatHeader(ManualHeader()), kManualHeader);
  FileText f;
  f.Open(ManualHeader());
  EXPECT_EQ(f.str(), kManualHeader);
}

// Part 1's G36 list (ln 1553-1557) names part cycles completed; written only when known (call 53).
TEST(InspectionFormat, PartCyclesCompletedLineOnlyWhenKnown) {
  Header h = ManualHeader();
  h.parts_completed = 14;
  EXPECT_EQ(FormatHeader(h),
            "CONTROL SERIAL NUMBER = 345879\n"
            "PALLET CODE/PART NUMBER = 3452\n"
            "NUMBER OF PART CYCLES COMPLETED = 14\n"
            "89:12:13 12:24\n" +
                kDashes + "\n");
  EXPECT_EQ(Parse(FormatHeader(h)).header, h);
}

TEST(InspectionFormat, StampKeepsTwoDigitYearsAndPadsFields) {
  Header h = ManualHeader();
  h.created = {2026, 3, 4, 5, 6};
  EXPECT_NE(FormatHeader(h).find("\n26:03:04 05:06\n"), std::string::npos);
  EXPECT_EQ(Parse(FormatHeader(h)).header.created, h.created);
  h.created.year = 2070;  // two digits cannot say which century
  EXPECT_THROW(FormatHeader(h), Error);
}

TEST(InspectionFormat, HeaderFieldsMustFitTheLineAndBePrintable) {
  Header h = ManualHeader();
  h.part = std::string(80 - 26 + 1, '7');  // "PALLET CODE/PART NUMBER = " is 26 characters
  EXPECT_THROW(FormatHeader(h), Error);
  h.part = std::string(80 - 26, '7');
  EXPECT_EQ(FormatHeader(h).find('\n'), 30u);  // serial line unchanged
  h.part = "34\n52";
  EXPECT_THROW(FormatHeader(h), Error);
  h.part = "";
  EXPECT_THROW(FormatHeader(h), Error);
}

// 7-12, ln 7952: L23=3.9567, L24=5.: PART<L23R> is PART4; PART<L23R><L24> is PART4 + 5.0000000 (the OCR's
// "PART45.000000" is one digit short of the 8-digit rule, judgement call 57).
TEST(InspectionFormat, Example7_12RoundedAndPlainParameters) {
  EXPECT_EQ("PART" + FormatRounded(3.9567), "PART4");
  EXPECT_EQ("PART" + FormatRounded(3.9567) + FormatNumber(5.), "PART45.0000000");
}

// 7-13, ln 7958-7977: TESTFILE123.00000, TESTFILE123.45600, TESTFILE123 and the NC file 123987.
TEST(InspectionFormat, Example7_13NumbersInFileNames) {
  EXPECT_EQ("TESTFILE" + FormatNumber(123), "TESTFILE123.00000");
  EXPECT_EQ("TESTFILE" + FormatNumber(123.456), "TESTFILE123.45600");
  EXPECT_EQ("TESTFILE" + FormatTruncated(123.456), "TESTFILE123");
  EXPECT_EQ(FormatTruncated(123.456) + FormatTruncated(987.6543), "123987");
}

// 7-14 (ln 7997-8004) and 7-15 (ln 8018-8041) wait on L1050/L1051 and delete files: they write no text.

// 7-16, ln 8049-8071: G36, OIF, two MSG statements, G37. Each message is followed by one empty line
// (ln 8045); the scan runs the two together on ln 8071 (judgement call 55).
TEST(InspectionFormat, Example7_16MessagesInAnOifFile) {
  FileText f;
  f.Open(ManualHeader());
  f.Msg("THIS WRITTEN WITH \"MSG\".");
  f.Msg("THIS IS A TEST.");
  const std::string expected = kManualHeader +
                               "THIS WRITTEN WITH \"MSG\".\n"
                               "\n"
                               "THIS IS A TEST.\n"
                               "\n";
  EXPECT_EQ(f.str(), expected);
  InspectionFile parsed = Parse(expected);
  EXPECT_EQ(parsed.header, ManualHeader());
  ASSERT_EQ(parsed.body.size(), 4u);
  EXPECT_EQ(std::get<TextLine>(parsed.body[0]).text, "THIS WRITTEN WITH \"MSG\".");
  EXPECT_EQ(std::get<TextLine>(parsed.body[1]).text, "");
  EXPECT_EQ(Format(parsed), expected);
}

// 7-17, ln 8079-8097: the same messages into an OPF file: no header, so it is no inspection file.
TEST(InspectionFormat, Example7_17MessagesInAnOpfFileHaveNoHeader) {
  FileText f;
  f.Msg("THIS WRITTEN WITH \"MSG\".");
  f.Msg("THIS IS A TEST.");
  EXPECT_EQ(f.str(), "THIS WRITTEN WITH \"MSG\".\n\nTHIS IS A TEST.\n\n");
  try {
    Parse(f.str());
    FAIL() << "an OPF file parsed as an inspection file";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), 1);
    EXPECT_EQ(e.column(), 1);
    EXPECT_NE(e.reason().find("not a KT-APL inspection file"), std::string::npos);
  }
}

// 7-18, Fig. 7.25, ln 8103-8122: one line per FWR, the quotes already resolved by the interpreter.
const std::string kFig725 =
    "THIS WRITTEN WITH FWR.\n"
    "ANY TYPE OF NEEDED TEXT.\n"
    "UPPER and lower case ALLOWED!\n"
    "Insert a comma, just for demonstration.\n"
    "Insert \"quotes\", just for demonstration.\n"
    "(END)\n";

TEST(InspectionFormat, Example7_18FwrTextLines) {
  FileText f;
  for (const char* t :
       {"THIS WRITTEN WITH FWR.", "ANY TYPE OF NEEDED TEXT.", "UPPER and lower case ALLOWED!",
        "Insert a comma, just for demonstration.", "Insert \"quotes\", just for demonstration.", "(END)"})
    f.Fwr(t);
  EXPECT_EQ(f.str(), kFig725);
}

// 7-19, Fig. 7.26, ln 8126-8144: (OPF,TESTFILE,A/AS) keeps the old lines and appends the new (ln 7981). The
// reprint's lost period (ln 8137) and missing (END) line are print damage (judgement call 56).
TEST(InspectionFormat, Example7_19AppendKeepsTheOldLines) {
  FileText again;
  again.Fwr("THIS LINE CHOSEN TO TEST THE 'APPEND' OPTION.");
  again.Fwr("Note that the previous data was not deleted!!");
  EXPECT_EQ(kFig725 + again.str(), kFig725 +
                                       "THIS LINE CHOSEN TO TEST THE 'APPEND' OPTION.\n"
                                       "Note that the previous data was not deleted!!\n");
}

// 7-20, Fig. 7.27, ln 8156-8173: L100=123.4567, L200=9.8, L300=-45.67.
TEST(InspectionFormat, Example7_20ParametersInFwr) {
  FileText f;
  f.Fwr(FormatNumber(123.4567));
  f.Fwr("Parameter L200 equals " + FormatNumber(9.8));
  f.Fwr("Parameter L300 equals " + FormatNumber(-45.67) + " at this time.");
  f.Fwr("Parameter L100, TRUNCATED, equals " + FormatTruncated(123.4567));
  EXPECT_EQ(f.str(),
            "123.45670\n"
            "Parameter L200 equals 9.8000000\n"
            "Parameter L300 equals -45.670000 at this time.\n"
            "Parameter L100, TRUNCATED, equals 123\n");
}

// 7-21, Fig. 7.28, ln 8195-8225: L1=10000., L2=(5.+2.)*L1, L3=(6.+3.)*L1, L4=(12.-3.)*L1 written with I.
TEST(InspectionFormat, Example7_21NcFileLines) {
  const double l1 = 10000., l2 = (5. + 2.) * l1, l3 = (6. + 3.) * l1, l4 = (12. - 3.) * l1;
  FileText f;
  f.Fwr("N10G01G70G90G94X10.Y8.F0");
  f.Fwr("N20X" + FormatTruncated(l2) + "Y" + FormatTruncated(l3) + "Z" + FormatTruncated(l4) +
        "F15.5S2000M3M8");
  f.Fwr("(END)");
  EXPECT_EQ(f.str(), "N10G01G70G90G94X10.Y8.F0\nN20X70000Y90000Z90000F15.5S2000M3M8\n(END)\n");
}

// 7-22, Fig. 7.29, ln 8229-8254: ';' continues the line; L500=12.3456 and the Y axis at 67.9.
TEST(InspectionFormat, Example7_22ContinuationAndAxisValues) {
  FileText f;
  f.Fwr("FIRST FILE OPEN.");
  f.Fwr("WRITE TWO LINES ONTO ONE LINE .... ", true);
  f.Fwr("THIS IS THE SECOND INPUT.");
  f.Fwr("A SEMICOLON CAN BE WRITTEN, ;, INSIDE A TEXT STREAM.");
  f.Fwr("PARAMETER/AXIS EXAMPLE .... " + FormatNumber(12.3456), true);
  // N330 (FWR," ----",Y) prints as "---- 67.900000": the scan lost the blank inside the quotes, as it loses
  // blanks elsewhere; an axis value has no leading blank, like a parameter's (judgement call 56).
  f.Fwr(" ---- " + FormatNumber(67.9));
  f.Fwr("SECOND FILE OPEN.");  // after (OPF,TESTFILE,A): appended
  f.Fwr("WRITE TWO LINES ONTO TWO LINES .... ");
  f.Fwr("THIS IS THE SECOND INPUT.");
  EXPECT_EQ(f.str(),
            "FIRST FILE OPEN.\n"
            "WRITE TWO LINES ONTO ONE LINE .... THIS IS THE SECOND INPUT.\n"
            "A SEMICOLON CAN BE WRITTEN, ;, INSIDE A TEXT STREAM.\n"
            "PARAMETER/AXIS EXAMPLE .... 12.345600 ---- 67.900000\n"
            "SECOND FILE OPEN.\n"
            "WRITE TWO LINES ONTO TWO LINES .... \n"
            "THIS IS THE SECOND INPUT.\n");
}

// ln 8075 (MSG) and ln 8101 (FWR): the control cuts a line at 80 characters.
TEST(InspectionFormat, LinesAreCutAt80Characters) {
  const std::string long_text(100, 'A');
  EXPECT_EQ(FormatLine(long_text), std::string(80, 'A') + "\n");
  EXPECT_EQ(FormatMessage(long_text), std::string(80, 'A') + "\n\n");
  FileText f;
  f.Fwr(std::string(50, 'B'), true);
  f.Fwr(std::string(50, 'C'));
  EXPECT_EQ(f.str(), std::string(50, 'B') + std::string(30, 'C') + "\n");
  EXPECT_THROW(FormatLine("TAB\tINSIDE"), Error);
}

// App. E: each cycle writes N<L814I> when its block had an N (ln 12273-12275), its lines, then (FWR,).
TEST(InspectionFormat, G26SurfaceLines) {
  // G26Z, ln 12273-12277: (FWR,"N",L814I) (FWR,"Z SURFACE=",Z) (FWR,); labels take " = " (call 54).
  EXPECT_EQ(FormatCycle(Surface(1300, Quantity::kZSurface, -2.5)), "N1300\nZ SURFACE = -2.5000000\n\n");
  // G26X, ln 12403 ("XSURFACE=", a space lost in the scan); G26Y, ln 12426-12434.
  EXPECT_EQ(FormatCycle(Surface(std::nullopt, Quantity::kXSurface, 6.0001)), "X SURFACE = 6.0001000\n\n");
  EXPECT_EQ(FormatCycle(Surface(140, Quantity::kYSurface, .25)), "N140\nY SURFACE = .25000000\n\n");
  // G26XY / G26RA, ln 12372-12377; 7-10's N120G26X6.Y6. (ln 7602).
  EXPECT_EQ(FormatCycle(SurfaceXY(120, 6., 6.)), "N120\nX SURFACE = 6.0000000\nY SURFACE = 6.0000000\n\n");
}

TEST(InspectionFormat, G27CentreLines) {
  // G27X, ln 12607-12613: separation L1005, then X CENTER.
  EXPECT_EQ(FormatCycle(Centre(450, 'X', 2.1358, 7.)),
            "N450\nX SURFACE SEPARATION = 2.1358000\nX CENTER = 7.0000000\n\n");
  // G27Y, ln 12644 and G27YZE, ln 12807-12819.
  EXPECT_EQ(FormatCycle(Centre(std::nullopt, 'Y', 1.5, -4.)),
            "Y SURFACE SEPARATION = 1.5000000\nY CENTER = -4.0000000\n\n");
  // G27XY / G27RA, ln 12708-12715; 7-10's N120G27X4.Y6. (ln 7683).
  EXPECT_EQ(FormatCycle(CentreXY(120, 3.9998, 4., 6.0002)),
            "N120\nX,Y SURFACE SEPARATION = 3.9998000\nX CENTER = 4.0000000\nY CENTER = 6.0002000\n\n");
}

TEST(InspectionFormat, AlignmentProbeLengthAndG24Lines) {
  // G27B, ln 13001-13007 (N430G27B90.F500., ln 7754); G26XZB, ln 12295-12301.
  EXPECT_EQ(FormatCycle(Alignment(430, 'B', 90.0125)), "N430\nB ALIGNMENT = 90.012500\n\n");
  EXPECT_EQ(FormatCycle(Alignment(std::nullopt, 'A', -.5)), "A ALIGNMENT = -.50000000\n\n");
  // G26T0Z, ln 12447: (FWR,"SPINDLE PROBE LENGTH = ",L826); N100G26T0Z-5. (ln 7586).
  EXPECT_EQ(FormatCycle(ProbeLength(100, 8.1234)), "N100\nSPINDLE PROBE LENGTH = 8.1234000\n\n");
  // G24 writes nothing in App. E (ln 11754-11807); the cell's line (call 58) carries E, its band (ln 1043).
  EXPECT_EQ(FormatCycle(Tolerance(460, 'R', 2.1358, 2.135, .0015)),
            "N460\nG24 R = 2.1358000 NOMINAL = 2.1350000 TOLERANCE = .00150000\n\n");
  EXPECT_EQ(FormatCycle(ToleranceXY(std::nullopt, 4.0003, 4., 5.9999, 6., .001)),
            "G24 X = 4.0003000 NOMINAL = 4.0000000 TOLERANCE = .00100000\n"
            "G24 Y = 5.9999000 NOMINAL = 6.0000000 TOLERANCE = .00100000\n\n");
}

TEST(InspectionFormat, RefusesShapesNoCycleWrites) {
  CycleResult c = Centre(1, 'X', 1, 2);
  c.results.pop_back();  // a separation without its centre
  EXPECT_THROW(FormatCycle(c), Error);
  c = Surface(1, Quantity::kXSurface, 1);
  c.results[0].nominal = 1;  // a nominal only G24 has
  c.results[0].tolerance = .1;
  EXPECT_THROW(FormatCycle(c), Error);
  EXPECT_THROW(Tolerance(1, 'Q', 1, 1, 1), Error);
  EXPECT_THROW(FormatCycle(Tolerance(1, 'X', 1, 1, -.1)), Error);  // a band is never negative
  EXPECT_THROW(FormatCycle(Surface(-1, Quantity::kXSurface, 1)), Error);
}

InspectionFile EveryKind() {
  InspectionFile f;
  f.header = {"345879", "PUMP341", 7, {2026, 11, 24, 9, 5}};
  f.body = {Surface(1300, Quantity::kZSurface, -2.5),
            TextLine{"FIRST BORE"},
            TextLine{""},
            CentreXY(1310, 2.1358, 5., 4.0002),
            Tolerance(1320, 'R', 2.1358, 2.135, .0015),
            Centre(std::nullopt, 'X', 1.25, -3.),
            SurfaceXY(1330, 6., -.0004),
            Alignment(1340, 'B', 359.99),
            Alignment(1341, 'C', 0),
            ProbeLength(std::nullopt, 8.1234),
            ToleranceXY(1350, 4.0003, 4., 5.9999, 6., .001),
            Tolerance(1360, 'Z', -1.0021, -1., .002),
            TextLine{"TOLERANCE EXCEEDS SPEC. REWORK .00120000"}};
  return f;
}

TEST(InspectionParse, RoundTripFormatParseGivesTheSameRecords) {
  const InspectionFile f = EveryKind();
  const std::string text = Format(f);
  EXPECT_EQ(Parse(text), f);
  EXPECT_EQ(Format(Parse(text)), text);
}

TEST(InspectionParse, ReadsTheListingsSpellings) {
  // App. E prints "XSURFACE=" (ln 12375), "BALIGNMENT =" (ln 12299), "Y CENTER=" (ln 12714).
  const std::string text =
      kManualHeader +
      "N120\nXSURFACE=6.0000000\nY SURFACE = 6.0000000\n\n"
      "BALIGNMENT =90.000000\n\n"
      "X,Y SURFACE SEPARATION=3.9998000\r\nX CENTER = 4.0000000\r\nY CENTER=6.0002000\r\n\r\n";
  InspectionFile f = Parse(text);
  ASSERT_EQ(f.body.size(), 3u);
  EXPECT_EQ(std::get<CycleResult>(f.body[0]), SurfaceXY(120, 6., 6.));
  EXPECT_EQ(std::get<CycleResult>(f.body[1]), Alignment(std::nullopt, 'B', 90.));
  EXPECT_EQ(std::get<CycleResult>(f.body[2]), CentreXY(std::nullopt, 3.9998, 4., 6.0002));
}

// The first problem, by line and column.
void ExpectError(const std::string& text, int line, int column, const std::string& words) {
  try {
    Parse(text);
    ADD_FAILURE() << "parsed: " << text;
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.column(), column) << e.what();
    EXPECT_NE(e.reason().find(words), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()), std::to_string(line) + ":" + std::to_string(column) + ": " + e.reason());
  }
}

TEST(InspectionParse, ErrorsNameLineAndColumn) {
  ExpectError("", 1, 1, "empty file");
  ExpectError("{\"station\": \"KT01\"}\n", 1, 1, "not a KT-APL inspection file");
  ExpectError("CONTROL SERIAL NUMBER = 345879\nPART = 3452\n", 2, 1, "PALLET CODE/PART NUMBER");
  ExpectError("CONTROL SERIAL NUMBER = 345879\nPALLET CODE/PART NUMBER = 3452\n89:13:13 12:24\n", 3, 4,
              "month");
  ExpectError("CONTROL SERIAL NUMBER = 345879\nPALLET CODE/PART NUMBER = 3452\n89-12-13 12:24\n", 3, 3,
              "YY:MM:DD HH:MM");
  ExpectError("CONTROL SERIAL NUMBER = 345879\nPALLET CODE/PART NUMBER = 3452\n89:12:13 12:24\nX\n", 4, 1,
              "dashed delimiter");
  ExpectError("CONTROL SERIAL NUMBER = 345879\nPALLET CODE/PART NUMBER = 3452\n89:12:13 12:24\n", 4, 1,
              "ends before");
  ExpectError(kManualHeader + "X CENTER = 5.0000000\n\n", 5, 1, "SEPARATION");
  ExpectError(kManualHeader + "X SURFACE SEPARATION = 2.1358000\nX CENTER = 5.00O0000\n\n", 6, 12, "number");
  ExpectError(kManualHeader + "X SURFACE SEPARATION = 2.1358000\n\n", 6, 1, "X CENTER");
  ExpectError(kManualHeader + "N1300\nTEXT\n", 6, 1, "N1300 is not followed");
  ExpectError(kManualHeader + "Z SURFACE = 1.0000000\nMORE\n", 6, 1, "empty line");
  ExpectError(kManualHeader + "Z SURFACE = 1.0000000", 6, 1, "ends inside");
  ExpectError(kManualHeader + "Z SURFACE = = 1.0\n\n", 5, 13, "number");
  ExpectError(kManualHeader + "Z SURFACE = 1.0 MM\n\n", 5, 17, "unexpected text");
  ExpectError(kManualHeader + "G24 X = 1.0 NOMINAL = 1.0\n\n", 5, 26, "TOLERANCE");
  ExpectError(kManualHeader + std::string(81, 'A') + "\n", 5, 81, "longer than 80");
  ExpectError(kManualHeader + "ABC\x01\n", 5, 4, "not printable");
}

TEST(InspectionParse, OtherLinesStayText) {
  // A user's FWR line that only looks like a result is text unless its label is one of App. E's.
  InspectionFile f = Parse(kManualHeader + "BORE 1 X = 5.0000000\nN20X70000Y90000\n");
  ASSERT_EQ(f.body.size(), 2u);
  EXPECT_EQ(std::get<TextLine>(f.body[0]).text, "BORE 1 X = 5.0000000");
  EXPECT_EQ(std::get<TextLine>(f.body[1]).text, "N20X70000Y90000");
}

}  // namespace
}  // namespace cell::inspection
