// QIF 3.0 documents against the schema (DESIGN §6: `xmllint --noout --nonet --schema
// reference/qif3/QIFApplications/QIFDocument.xsd`). The schema is the repository's copy (tests/schemas/qif3),
// or CELL_QIF_SCHEMAS.
#pragma once

#include <string>

namespace cell::testing {

// The folder holding QIFApplications/QIFDocument.xsd, or "" when there is none.
std::string QifSchemaDir();
// "" when `xml` validates, else xmllint's complaint (or that the schema is missing).
std::string ValidateQif(const std::string& xml);

}  // namespace cell::testing
