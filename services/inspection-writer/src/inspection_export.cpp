// An inspection file's measurements as CSV and as a QIF 3.0 results document.
#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <iterator>

#include "cell/inspection/inspection_file.h"

namespace cell::inspection {

namespace {

// xs:decimal (QIF's values) and CSV readers alike want no exponent: the shortest form that reads back
// exactly, in positional notation.
std::string Decimal(double v) {
  std::string s = fmt::format("{}", v);
  if (s.find('e') == std::string::npos) return s;
  s = fmt::format("{:.17f}", v);
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  return s;
}

std::optional<bool> Verdict(const Result& r) {
  if (!r.nominal || !r.tolerance) return std::nullopt;
  // G24 stops the program when |deviation| > E (ln 11807), so exactly E passes.
  return std::fabs(r.value - *r.nominal) <= *r.tolerance;
}

// RFC 4180: a field holding a comma, a quote or a line break is quoted, its quotes doubled.
void CsvField(fmt::memory_buffer& out, std::string_view s) {
  if (s.find_first_of(",\"\r\n") == std::string_view::npos) {
    out.append(s);
    return;
  }
  out.push_back('"');
  for (char c : s) {
    if (c == '"') out.push_back('"');
    out.push_back(c);
  }
  out.push_back('"');
}

void XmlText(fmt::memory_buffer& out, std::string_view s) {
  for (char c : s) {
    switch (c) {
      case '&':
        out.append(std::string_view("&amp;"));
        break;
      case '<':
        out.append(std::string_view("&lt;"));
        break;
      case '>':
        out.append(std::string_view("&gt;"));
        break;
      case '"':
        out.append(std::string_view("&quot;"));
        break;
      default:
        out.push_back(c);
    }
  }
}

// The QIF characteristic type of a quantity: positions are coordinates, separations diameters (the G27
// cycles measure bores and bosses), alignments angular coordinates of the rotary axis, the probe a length.
struct QifType {
  std::string_view element;      // "LinearCoordinateCharacteristic", ...
  std::string_view direction;    // the nominal's Direction, or empty
  std::string_view coordinates;  // the measurement's TypeOfCoordinates, or empty
};

QifType TypeOf(Quantity q) {
  using Q = Quantity;
  switch (q) {
    case Q::kXSurface:
    case Q::kXCenter:
    case Q::kToleranceX:
      return {"LinearCoordinateCharacteristic", "XAXIS", "CARTESIAN_3D"};
    case Q::kYSurface:
    case Q::kYCenter:
    case Q::kToleranceY:
      return {"LinearCoordinateCharacteristic", "YAXIS", "CARTESIAN_3D"};
    case Q::kZSurface:
    case Q::kToleranceZ:
      return {"LinearCoordinateCharacteristic", "ZAXIS", "CARTESIAN_3D"};
    case Q::kXSeparation:
    case Q::kYSeparation:
    case Q::kXYSeparation:
    case Q::kToleranceR:
      return {"DiameterCharacteristic", "", ""};
    case Q::kAAlignment:
    case Q::kBAlignment:
    case Q::kCAlignment:
    case Q::kToleranceA:
    case Q::kToleranceB:
    case Q::kToleranceC:
      return {"AngularCoordinateCharacteristic", "ANGULAR", "CYLINDRICAL_3D"};
    case Q::kProbeLength:
      return {"LengthCharacteristic", "", ""};
  }
  return {};
}

// 128 bits from the content (two FNV-1a passes), shaped as an RFC 9562 version 8 (custom) UUID: the same
// file exports to the same document id.
std::string ContentId(std::string_view a, std::string_view b) {
  auto fnv = [&](std::uint64_t h) {
    for (std::string_view s : {a, std::string_view("\0", 1), b})
      for (unsigned char c : s) h = (h ^ c) * 0x100000001b3ULL;
    return h;
  };
  std::uint64_t hi = fnv(0xcbf29ce484222325ULL), lo = fnv(0x84222325cbf29ce4ULL);
  hi = (hi & ~0xf000ULL) | 0x8000ULL;        // version 8
  lo = (lo & ~(3ULL << 62)) | (2ULL << 62);  // RFC variant
  return fmt::format("{:08x}-{:04x}-{:04x}-{:04x}-{:012x}", hi >> 32, (hi >> 16) & 0xffff, hi & 0xffff,
                     lo >> 48, lo & 0xffffffffffffULL);
}

std::string ItemName(const Characteristic& c) {
  return c.n ? fmt::format("N{} {}", *c.n, Label(c.result.quantity))
             : fmt::format("#{} {}", c.feature, Label(c.result.quantity));
}

}  // namespace

std::vector<Characteristic> Characteristics(const InspectionFile& f, LinearUnit unit) {
  std::vector<Characteristic> out;
  int feature = 0;
  for (const Entry& e : f.body) {
    const auto* c = std::get_if<CycleResult>(&e);
    if (!c) continue;
    ++feature;
    for (const Result& r : c->results)
      out.push_back({feature, c->kind, CycleName(c->kind, c->results), c->n, r,
                     IsAngular(r.quantity)       ? "degree"
                     : unit == LinearUnit::kInch ? "inch"
                                                 : "mm",
                     Verdict(r)});
  }
  return out;
}

std::string ToCsv(const InspectionFile& f, LinearUnit unit) {
  fmt::memory_buffer out;
  out.append(
      std::string_view("part,feature,n,cycle,kind,quantity,measured,nominal,tolerance,status,unit\r\n"));
  for (const Characteristic& c : Characteristics(f, unit)) {
    CsvField(out, f.header.part);
    out.push_back(',');
    fmt::format_to(std::back_inserter(out), "{},", c.feature);
    if (c.n) fmt::format_to(std::back_inserter(out), "{}", *c.n);
    out.push_back(',');
    CsvField(out, c.cycle);
    out.push_back(',');
    CsvField(out, KindName(c.kind));
    out.push_back(',');
    CsvField(out, Label(c.result.quantity));
    fmt::format_to(std::back_inserter(out), ",{},", Decimal(c.result.value));
    if (c.result.nominal) out.append(Decimal(*c.result.nominal));
    out.push_back(',');
    if (c.result.tolerance) out.append(Decimal(*c.result.tolerance));
    out.push_back(',');
    if (c.pass) out.append(std::string_view(*c.pass ? "PASS" : "FAIL"));
    out.push_back(',');
    CsvField(out, c.unit);
    out.append(std::string_view("\r\n"));
  }
  return fmt::to_string(out);
}

std::string ToQif(const InspectionFile& f, LinearUnit unit, std::string_view name) {
  const std::vector<Characteristic> cs = Characteristics(f, unit);
  const std::string text = Format(f);
  const Stamp& s = f.header.created;
  // Ids: 1 the standard, 2 the part, 3 the results; then definition, nominal, item, measurement per
  // characteristic.
  const int base = 4;
  auto id = [&](std::size_t i, int k) { return base + static_cast<int>(i) * 4 + k; };
  const int id_max = base + static_cast<int>(cs.size()) * 4 - 1;
  auto out_it = [](fmt::memory_buffer& b) { return std::back_inserter(b); };

  fmt::memory_buffer out;
  auto put = [&](std::string_view sv) { out.append(sv); };
  put("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
  fmt::format_to(
      out_it(out),
      "<QIFDocument xmlns=\"http://qifstandards.org/xsd/qif3\" versionQIF=\"3.0.0\" idMax=\"{}\">\n",
      std::max(id_max, 3));
  fmt::format_to(out_it(out), "  <QPId>{}</QPId>\n", ContentId(name, text));
  // The file's own stamp (the control's local time, when OIF opened it): the export adds no clock of its own.
  fmt::format_to(
      out_it(out),
      "  <Version>\n    <TimeCreated>{:04}-{:02}-{:02}T{:02}:{:02}:00</TimeCreated>\n  </Version>\n", s.year,
      s.month, s.day, s.hour, s.minute);
  put("  <Header>\n    <Application>\n      <Name>cellctl inspect export</Name>\n      "
      "<Organization>cell</Organization>\n"
      "    </Application>\n    <Scope>KT-APL inspection file ");
  XmlText(out, name);
  put(" of control ");
  XmlText(out, f.header.serial);
  put("</Scope>\n  </Header>\n");
  // The characteristics are the probe cycles' results as the KT-APL manual (PUB 929A, App. E) defines them.
  put("  <StandardsDefinitions n=\"1\">\n    <Standard id=\"1\">\n      <Organization>\n"
      "        <OtherStandardsOrganization>Kearney &amp; Trecker</OtherStandardsOrganization>\n"
      "      </Organization>\n      <Designator>PUB 929A</Designator>\n"
      "      <Title>KT-APL part programming manual, App. E probe cycles</Title>\n    </Standard>\n"
      "  </StandardsDefinitions>\n");
  const bool inch = unit == LinearUnit::kInch;
  fmt::format_to(
      out_it(out),
      "  <FileUnits>\n    <PrimaryUnits>\n      <AngularUnit>\n        <SIUnitName>radian</SIUnitName>\n"
      "        <UnitName>degree</UnitName>\n        <UnitConversion>\n"
      "          <Factor>0.017453292519943295</Factor>\n        </UnitConversion>\n      </AngularUnit>\n"
      "      <LinearUnit>\n        <SIUnitName>meter</SIUnitName>\n        <UnitName>{}</UnitName>\n"
      "        <UnitConversion>\n          <Factor>{}</Factor>\n        </UnitConversion>\n"
      "      </LinearUnit>\n    </PrimaryUnits>\n  </FileUnits>\n",
      inch ? "inch" : "mm", inch ? "0.0254" : "0.001");
  put("  <Product>\n    <PartSet n=\"1\">\n      <Part id=\"2\">\n        <ModelNumber>");
  XmlText(out, f.header.part);
  put("</ModelNumber>\n      </Part>\n    </PartSet>\n  </Product>\n");

  if (!cs.empty()) {
    put("  <Characteristics>\n    <FormalStandardId>1</FormalStandardId>\n");
    fmt::format_to(out_it(out), "    <CharacteristicDefinitions n=\"{}\">\n", cs.size());
    for (std::size_t i = 0; i < cs.size(); ++i) {
      const Result& r = cs[i].result;
      const QifType t = TypeOf(r.quantity);
      fmt::format_to(out_it(out), "      <{}Definition id=\"{}\">\n", t.element, id(i, 0));
      if (r.tolerance)
        fmt::format_to(
            out_it(out),
            "        <Tolerance>\n          <MaxValue>{}</MaxValue>\n          <MinValue>{}</MinValue>\n"
            "          <DefinedAsLimit>false</DefinedAsLimit>\n        </Tolerance>\n",
            Decimal(*r.tolerance), Decimal(-*r.tolerance));
      else
        put("        <NonTolerance>MEASURED</NonTolerance>\n");
      fmt::format_to(out_it(out), "      </{}Definition>\n", t.element);
    }
    put("    </CharacteristicDefinitions>\n");
    fmt::format_to(out_it(out), "    <CharacteristicNominals n=\"{}\">\n", cs.size());
    for (std::size_t i = 0; i < cs.size(); ++i) {
      const Result& r = cs[i].result;
      const QifType t = TypeOf(r.quantity);
      fmt::format_to(out_it(out),
                     "      <{}Nominal id=\"{}\">\n        "
                     "<CharacteristicDefinitionId>{}</CharacteristicDefinitionId>\n",
                     t.element, id(i, 1), id(i, 0));
      if (r.nominal)
        fmt::format_to(out_it(out), "        <TargetValue>{}</TargetValue>\n", Decimal(*r.nominal));
      if (!t.direction.empty())
        fmt::format_to(out_it(out), "        <Direction>{}</Direction>\n", t.direction);
      fmt::format_to(out_it(out), "      </{}Nominal>\n", t.element);
    }
    put("    </CharacteristicNominals>\n");
    fmt::format_to(out_it(out), "    <CharacteristicItems n=\"{}\">\n", cs.size());
    for (std::size_t i = 0; i < cs.size(); ++i) {
      const QifType t = TypeOf(cs[i].result.quantity);
      fmt::format_to(out_it(out), "      <{}Item id=\"{}\">\n        <Name>", t.element, id(i, 2));
      XmlText(out, ItemName(cs[i]));
      fmt::format_to(
          out_it(out),
          "</Name>\n        <CharacteristicNominalId>{}</CharacteristicNominalId>\n      </{}Item>\n",
          id(i, 1), t.element);
    }
    put("    </CharacteristicItems>\n  </Characteristics>\n");
  }

  bool any_fail = false, any_checked = false;
  for (const Characteristic& c : cs) {
    any_checked = any_checked || c.pass.has_value();
    any_fail = any_fail || c.pass == false;
  }
  put("  <Results>\n    <MeasurementResultsSet n=\"1\">\n      <MeasurementResults id=\"3\">\n");
  if (!cs.empty()) {
    fmt::format_to(out_it(out),
                   "        <MeasuredCharacteristics>\n          <CharacteristicMeasurements n=\"{}\">\n",
                   cs.size());
    for (std::size_t i = 0; i < cs.size(); ++i) {
      const Characteristic& c = cs[i];
      const QifType t = TypeOf(c.result.quantity);
      fmt::format_to(
          out_it(out),
          "            <{}Measurement id=\"{}\">\n              <Status>\n"
          "                <CharacteristicStatusEnum>{}</CharacteristicStatusEnum>\n              </Status>\n"
          "              <CharacteristicItemId>{}</CharacteristicItemId>\n",
          t.element, id(i, 3),
          !c.pass   ? "NOT_ANALYZED"
          : *c.pass ? "PASS"
                    : "FAIL",
          id(i, 2));
      if (!t.coordinates.empty())
        fmt::format_to(
            out_it(out),
            "              <TypeOfCoordinates>\n                <CoordinateEnum>{}</CoordinateEnum>\n"
            "              </TypeOfCoordinates>\n",
            t.coordinates);
      fmt::format_to(out_it(out), "              <Value>{}</Value>\n            </{}Measurement>\n",
                     Decimal(c.result.value), t.element);
    }
    put("          </CharacteristicMeasurements>\n        </MeasuredCharacteristics>\n");
  }
  // Only G24 gives a verdict; a file without one has none to report.
  fmt::format_to(out_it(out),
                 "        <InspectionStatus>\n          <InspectionStatusEnum>{}</InspectionStatusEnum>\n"
                 "        </InspectionStatus>\n",
                 any_fail      ? "FAIL"
                 : any_checked ? "PASS"
                               : "NOT_CALCULATED");
  put("      </MeasurementResults>\n    </MeasurementResultsSet>\n  </Results>\n</QIFDocument>\n");
  return fmt::to_string(out);
}

}  // namespace cell::inspection
