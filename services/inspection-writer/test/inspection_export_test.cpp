// CSV and QIF 3.0 exports of an inspection file (the QIF schema check itself is
// inspection_qif_schema_test). Expected rows are derived by hand from the records below.
#include <gtest/gtest.h>

#include "cell/inspection/inspection_file.h"

namespace cell::inspection {
namespace {

InspectionFile Sample() {
  InspectionFile f;
  f.header = {"345879", "PUMP \"A\",341", std::nullopt, {1989, 12, 13, 12, 24}};
  f.body = {CentreXY(1310, 2.1358, 5., 4.0002), TextLine{"BORE CHECKED"},
            Tolerance(1320, 'R', 2.1358, 2.135, .0015),  // |2.1358 - 2.135| = .0008 <= .0015: PASS
            Alignment(std::nullopt, 'B', 90.0125),
            Tolerance(1330, 'X', 4.0021, 4., .002)};  // |4.0021 - 4| = .0021 > .002: FAIL (ln 11807)
  return f;
}

TEST(InspectionCsv, OneRowPerMeasuredQuantityQuotedAsRfc4180) {
  const std::string part = "\"PUMP \"\"A\"\",341\"";  // comma and quotes: quoted, quotes doubled
  EXPECT_EQ(ToCsv(Sample(), LinearUnit::kInch),
            "part,feature,n,cycle,kind,quantity,measured,nominal,tolerance,status,unit\r\n" + part +
                ",1,1310,G27,centre,\"X,Y SURFACE SEPARATION\",2.1358,,,,inch\r\n" + part +
                ",1,1310,G27,centre,X CENTER,5,,,,inch\r\n" + part +
                ",1,1310,G27,centre,Y CENTER,4.0002,,,,inch\r\n" + part +
                ",2,1320,G24,tolerance,G24 R,2.1358,2.135,0.0015,PASS,inch\r\n" + part +
                ",3,,G26/G27,alignment,B ALIGNMENT,90.0125,,,,degree\r\n" + part +
                ",4,1330,G24,tolerance,G24 X,4.0021,4,0.002,FAIL,inch\r\n");
}

TEST(InspectionCsv, UnitsAndTinyValuesWithoutExponent) {
  InspectionFile f = Sample();
  f.header.part = "3452";
  f.body = {Surface(1, Quantity::kZSurface, -.00000001), ProbeLength(2, 114.483)};
  EXPECT_EQ(ToCsv(f, LinearUnit::kMillimetre),
            "part,feature,n,cycle,kind,quantity,measured,nominal,tolerance,status,unit\r\n"
            "3452,1,1,G26,surface,Z SURFACE,-0.00000001,,,,mm\r\n"
            "3452,2,2,G26,probe_length,SPINDLE PROBE LENGTH,114.483,,,,mm\r\n");
}

TEST(InspectionCharacteristics, FeaturesCountCycleResultsNotLines) {
  auto cs = Characteristics(Sample(), LinearUnit::kMillimetre);
  ASSERT_EQ(cs.size(), 6u);
  EXPECT_EQ(cs[2].feature, 1);
  EXPECT_EQ(cs[2].result.quantity, Quantity::kYCenter);
  EXPECT_EQ(cs[2].unit, "mm");
  EXPECT_EQ(cs[4].unit, "degree");
  EXPECT_EQ(cs[4].cycle, "G26/G27");  // B ALIGNMENT: G26XZB and G27B write the same line
  EXPECT_FALSE(cs[4].pass.has_value());
  EXPECT_EQ(cs[3].pass, true);
  EXPECT_EQ(cs[5].pass, false);
  EXPECT_EQ(CycleName(CycleKind::kAlignment, Alignment(1, 'A', 0).results), "G26");  // A: G26YZA only
}

std::size_t Count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (auto at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
  return n;
}

TEST(InspectionQif, CharacteristicsNominalsAndActuals) {
  const std::string q = ToQif(Sample(), LinearUnit::kInch, "KT01/PUMP<341>");
  EXPECT_NE(q.find("<ModelNumber>PUMP &quot;A&quot;,341</ModelNumber>"), std::string::npos);
  EXPECT_NE(q.find("<Scope>KT-APL inspection file KT01/PUMP&lt;341&gt; of control 345879</Scope>"),
            std::string::npos);
  EXPECT_NE(q.find("<TimeCreated>1989-12-13T12:24:00</TimeCreated>"), std::string::npos);
  EXPECT_NE(q.find("<UnitName>inch</UnitName>"), std::string::npos);
  EXPECT_NE(q.find("<CharacteristicMeasurements n=\"6\">"), std::string::npos);
  // Definition, nominal, item, measurement per quantity.
  EXPECT_EQ(Count(q, "<DiameterCharacteristicDefinition "), 2u);    // X,Y separation and G24 R
  EXPECT_EQ(Count(q, "<LinearCoordinateCharacteristicItem "), 3u);  // X, Y CENTER and G24 X
  EXPECT_EQ(Count(q, "<AngularCoordinateCharacteristicMeasurement "), 1u);
  EXPECT_NE(q.find("<TargetValue>2.135</TargetValue>"), std::string::npos);
  EXPECT_NE(q.find("<MaxValue>0.0015</MaxValue>\n          <MinValue>-0.0015</MinValue>"), std::string::npos);
  EXPECT_NE(q.find("<Name>N1330 G24 X</Name>"), std::string::npos);
  EXPECT_NE(q.find("<Name>#3 B ALIGNMENT</Name>"), std::string::npos);
  EXPECT_NE(q.find("<Value>4.0021</Value>"), std::string::npos);
  EXPECT_EQ(Count(q, "<CharacteristicStatusEnum>FAIL<"), 1u);
  EXPECT_EQ(Count(q, "<CharacteristicStatusEnum>PASS<"), 1u);
  EXPECT_EQ(Count(q, "<CharacteristicStatusEnum>NOT_ANALYZED<"), 4u);
  EXPECT_NE(q.find("<InspectionStatusEnum>FAIL</InspectionStatusEnum>"), std::string::npos);
  EXPECT_NE(q.find("idMax=\"27\""), std::string::npos);  // 3 fixed ids, then 4 for each of 6 quantities
}

TEST(InspectionQif, DocumentIdFollowsTheContent) {
  auto id = [](const std::string& q) {
    auto at = q.find("<QPId>");
    return q.substr(at + 6, 36);
  };
  InspectionFile f = Sample();
  const std::string a = id(ToQif(f, LinearUnit::kInch, "A"));
  EXPECT_EQ(a, id(ToQif(f, LinearUnit::kInch, "A")));
  EXPECT_NE(a, id(ToQif(f, LinearUnit::kInch, "B")));
  f.body.pop_back();
  EXPECT_NE(a, id(ToQif(f, LinearUnit::kInch, "A")));
  EXPECT_EQ(a[14], '8');  // RFC 9562 version 8
  EXPECT_NE(std::string("89ab").find(a[19]), std::string::npos);
}

TEST(InspectionQif, WithoutToleranceNoVerdictAndNoCharacteristicsWhenNothingMeasured) {
  InspectionFile f = Sample();
  f.body = {Surface(1, Quantity::kXSurface, 1.5)};
  std::string q = ToQif(f, LinearUnit::kMillimetre, "X");
  EXPECT_NE(q.find("<NonTolerance>MEASURED</NonTolerance>"), std::string::npos);
  EXPECT_NE(q.find("<InspectionStatusEnum>NOT_CALCULATED</InspectionStatusEnum>"), std::string::npos);
  EXPECT_NE(q.find("<UnitName>mm</UnitName>"), std::string::npos);
  f.body = {TextLine{"ONLY TEXT"}};
  q = ToQif(f, LinearUnit::kMillimetre, "X");
  EXPECT_EQ(q.find("<Characteristics>"), std::string::npos);
  EXPECT_EQ(q.find("<MeasuredCharacteristics>"), std::string::npos);
}

}  // namespace
}  // namespace cell::inspection
