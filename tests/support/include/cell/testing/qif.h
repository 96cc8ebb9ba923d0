// QIF 3.0 documents against the schema (DESIGN §6: `xmllint --noout --nonet --schema
// reference/qif3/QIFApplications/QIFDocument.xsd`). The schema is the shared reference beside the repository
// (../shared/reference/qif3), or CELL_QIF_SCHEMAS; tests skip the check where it is absent.
#pragma once

#include <string>

namespace cell::testing {

// The folder holding QIFApplications/QIFDocument.xsd, or "" when there is none.
std::string QifSchemaDir();
// "" when `xml` validates, else xmllint's complaint.
std::string ValidateQif(const std::string& xml);

}  // namespace cell::testing
