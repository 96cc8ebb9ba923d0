// QIF exports validated against the QIF 3.0 schema (DESIGN §6: `xmllint --noout --nonet --schema
// reference/qif3/QIFApplications/QIFDocument.xsd`), with a broken document as the negative control so the
// check can fail. The schema is the repository's copy (tests/schemas/qif3, as the MTConnect tests find
// theirs in tests/schemas/mtconnect); without it the tests fail.
#include <gtest/gtest.h>

#include "cell/inspection/inspection_file.h"
#include "cell/testing/qif.h"

namespace cell::inspection {
namespace {

using cell::testing::QifSchemaDir;
using cell::testing::ValidateQif;

class QifSchema : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_NE(QifSchemaDir(), "") << "QIF 3.0 schema not found (tests/schemas/qif3 in CELL_SOURCE_DIR)";
  }
};

InspectionFile EveryKind() {
  InspectionFile f;
  f.header = {"345879", "PUMP<341>&\"X\"", 12, {2026, 11, 24, 9, 5}};
  f.body = {Surface(1300, Quantity::kZSurface, -2.5),
            SurfaceXY(1301, 6., -.0004),
            TextLine{"FIRST BORE"},
            CentreXY(1310, 2.1358, 5., 4.0002),
            Centre(std::nullopt, 'X', 1.25, -3.),
            Centre(1311, 'Y', 1.5, 3.),
            Tolerance(1320, 'R', 2.1358, 2.135, .0015),
            Alignment(1340, 'A', -.5),
            Alignment(1341, 'B', 359.99),
            Alignment(1342, 'C', 0),
            ProbeLength(std::nullopt, 8.1234),
            ToleranceXY(1350, 4.0003, 4., 5.9999, 6., .001),
            Tolerance(1360, 'Z', -1.0021, -1., .002),
            Tolerance(1370, 'B', 90.001, 90., .01),
            Surface(1380, Quantity::kXSurface, -.00000001)};
  return f;
}

TEST_F(QifSchema, EveryCycleKindValidatesInInchAndMillimetres) {
  EXPECT_EQ(ValidateQif(ToQif(EveryKind(), LinearUnit::kInch, "KT01/PUMP341")), "");
  EXPECT_EQ(ValidateQif(ToQif(EveryKind(), LinearUnit::kMillimetre, "KT01/<odd & name>")), "");
}

TEST_F(QifSchema, AFileWithoutMeasurementsValidates) {
  InspectionFile f = EveryKind();
  f.body = {TextLine{"NOTHING MEASURED"}};
  EXPECT_EQ(ValidateQif(ToQif(f, LinearUnit::kInch, "EMPTY")), "");
  f.body.clear();
  EXPECT_EQ(ValidateQif(ToQif(f, LinearUnit::kInch, "EMPTY")), "");
}

TEST_F(QifSchema, ParsedFileExportsValidate) {
  const std::string text = Format(EveryKind());
  EXPECT_EQ(ValidateQif(ToQif(Parse(text), LinearUnit::kInch, "KT01/PUMP341")), "");
}

// The negative control: the same check refuses a document the schema does not allow.
TEST_F(QifSchema, BrokenDocumentsFail) {
  std::string q = ToQif(EveryKind(), LinearUnit::kInch, "KT01/PUMP341");
  std::string no_id = q;
  no_id.erase(no_id.find("  <QPId>"), no_id.find("</QPId>\n") + 8 - no_id.find("  <QPId>"));
  EXPECT_NE(ValidateQif(no_id), "");
  std::string exponent = q;
  auto at = exponent.find("<Value>-2.5</Value>");
  ASSERT_NE(at, std::string::npos);
  exponent.replace(at, 19, "<Value>-2.5e0</Value>");  // xs:decimal has no exponent
  EXPECT_NE(ValidateQif(exponent), "");
  std::string dangling = q;
  at = dangling.find("<CharacteristicItemId>");
  dangling.replace(at, 22, "<CharacteristicItemId>9999");  // an id no item has
  EXPECT_NE(ValidateQif(dangling), "");
}

}  // namespace
}  // namespace cell::inspection
