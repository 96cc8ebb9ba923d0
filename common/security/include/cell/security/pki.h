// The cell's PKI on disk (docs/security.md): a CA, one certificate and key per identity, the signed
// governance and permissions documents; made with the openssl command, and found again by the processes
// that use them.
//
// Layout (fixed; the bus and the units rely on it):
//   <dir>/ca.pem, ca.key (0600)                  the cell CA: identity CA and permissions CA in one
//   <dir>/governance.xml, governance.p7s         the governance document and its S/MIME signature
//   <dir>/identities/<name>/cert.pem, key.pem (0600), permissions.xml, permissions.p7s
// <dir>, identities/ and identities/<name>/ are 0700: they hold private keys.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "cell/security/permissions.h"

namespace cell::security {

struct PkiOptions {
  std::filesystem::path dir;
  std::vector<Identity> identities;  // CellIdentities(stations)
  bool force = false;                // replace the CA and every key, certificate and document
  std::string openssl = "openssl";   // the openssl program: looked up in PATH unless it names a path
  int days = 3650;                   // validity of certificates and permission grants
};

// What became of one part of the PKI.
enum class Outcome {
  kCreated,   // did not exist: made now
  kKept,      // complete: left as it was
  kReissued,  // key kept; its certificate or documents made now: they were missing, the CA is new, or the
              // code now writes the document otherwise (the permissions table changed)
  kReplaced,  // existed; replaced under force
};
std::string_view OutcomeName(Outcome o);  // "created", "kept", "reissued", "replaced"

struct PkiReport {
  Outcome ca;
  Outcome governance;
  std::vector<std::pair<std::string, Outcome>> identities;  // in PkiOptions::identities order
};

// Makes what is missing of the PKI in opts.dir, signed by its CA (made first when there is none). Without
// force an existing key is never touched: a complete PKI is left as it is, missing identities are added,
// and a document that differs from what the code now makes (governance, or permissions under their own
// dates) is signed again. Throws cell::Error with a one-line reason: kFailedPrecondition when openssl cannot
// be run or the CA is half there (one of ca.pem and ca.key), kIo when the directory cannot be made or
// written, kInternal when an openssl command fails (its last line of stderr is quoted).
PkiReport InitPki(const PkiOptions& opts);

// Where `cellctl pki init` writes by default: <CELL_CONFIG_DIR>/security.
std::filesystem::path DefaultPkiDir();

// Where a process finds the PKI: $CELL_DATA_DIR/security when that directory exists (a local cell of
// `cellctl up --secure`), else <CELL_CONFIG_DIR>/security.
std::filesystem::path SecurityDir();

// The files one identity's participant needs.
struct IdentityFiles {
  std::filesystem::path ca;           // identity CA and permissions CA
  std::filesystem::path governance;   // governance.p7s
  std::filesystem::path certificate;  // identities/<name>/cert.pem
  std::filesystem::path key;          // identities/<name>/key.pem
  std::filesystem::path permissions;  // identities/<name>/permissions.p7s
  std::filesystem::path crl;          // crl.pem, the CA's revocation list; empty when none was made
};

// The files of identity `name` in `dir`, each checked to exist. Throws cell::Error: kInvalidArgument for a
// name that is no identity (ParseIdentity), kNotFound naming the first missing file.
IdentityFiles FindIdentityFiles(const std::filesystem::path& dir, std::string_view name);

// Revokes identity `name`'s certificate in the PKI at `dir` (which holds the CA's key): its serial joins the
// CA's revocation database (crl-index.txt) and crl.pem is signed again, listing every revoked certificate.
// Every participant started afterwards loads crl.pem: the revoked identity cannot join, nor is it accepted by
// the others (their authentication checks the peer's certificate against it). The rest of the PKI is kept.
// Throws cell::Error: kNotFound without the certificate or the CA key. Returns the revoked serial (hex).
std::string RevokeIdentity(const std::filesystem::path& dir, std::string_view name,
                           const std::string& openssl = "openssl");

// Why a DDS stack may have refused identity `identity`'s files, checked with openssl: "" when the certificate
// verifies against the CA, is the identity's own (its subject is SubjectName(identity), the name its grant
// carries), matches the private key, and both documents carry a valid signature by the CA; else a one-line
// reason naming the file ("cert.pem (interpreter-KT01): the certificate of CN=interpreter-KT02,O=cell, not of
// interpreter-KT01"). "" too when openssl cannot be run.
std::string DiagnoseIdentity(const std::string& identity, const std::filesystem::path& ca,
                             const std::filesystem::path& governance,
                             const std::filesystem::path& certificate, const std::filesystem::path& key,
                             const std::filesystem::path& permissions, const std::filesystem::path& crl = {});

}  // namespace cell::security
