#include "cell/security/pki.h"

#include <sys/stat.h>

#include <fmt/format.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <vector>

#include "cell/config/config.h"
#include "cell/error/error.h"
#include "cell/security/permissions.h"
#include "openssl.h"

namespace cell::security {

namespace fs = std::filesystem;

namespace {

constexpr fs::perms kPrivateDir = fs::perms::owner_all;
constexpr fs::perms kPrivateFile = fs::perms::owner_read | fs::perms::owner_write;
constexpr fs::perms kPublicFile = kPrivateFile | fs::perms::group_read | fs::perms::others_read;

// The CA's own subject (it grants nothing; no identity is called this).
constexpr const char* kCaSubject = "/O=cell/CN=cell-ca";

std::string Reason(const std::error_code& ec) {
  return ec.message();
}

void MakePrivateDir(const fs::path& d) {
  std::error_code ec;
  fs::create_directories(d, ec);
  if (ec) throw Error(Errc::kIo, fmt::format("cannot create {}: {}", d.string(), Reason(ec)));
  fs::permissions(d, kPrivateDir, fs::perm_options::replace, ec);
  if (ec) throw Error(Errc::kIo, fmt::format("cannot make {} owner-only: {}", d.string(), Reason(ec)));
}

void SetMode(const fs::path& f, fs::perms mode) {
  std::error_code ec;
  fs::permissions(f, mode, fs::perm_options::replace, ec);
  if (ec) throw Error(Errc::kIo, fmt::format("cannot set the mode of {}: {}", f.string(), Reason(ec)));
}

// Files are made beside their final name and renamed over it: a reader never sees half a file, and an
// interrupted run leaves the old one.
fs::path Staged(const fs::path& f) {
  return fs::path(f.string() + ".new");
}

void Commit(const fs::path& f, fs::perms mode) {
  SetMode(Staged(f), mode);
  std::error_code ec;
  fs::rename(Staged(f), f, ec);
  if (ec) throw Error(Errc::kIo, fmt::format("cannot rename {}: {}", Staged(f).string(), Reason(ec)));
}

void RemoveStaged(const fs::path& f) {
  std::error_code ec;
  fs::remove(Staged(f), ec);
}

void WriteText(const fs::path& f, const std::string& text) {
  RemoveStaged(f);
  {
    std::ofstream out(Staged(f), std::ios::binary | std::ios::trunc);
    out << text;
    out.flush();
    if (!out)
      throw Error(Errc::kIo, fmt::format("cannot write {}: {}", Staged(f).string(), std::strerror(errno)));
  }
  Commit(f, kPublicFile);
}

// UTC "YYYY-MM-DDTHH:MM:SS" (the permissions document's date form).
std::string UtcTime(std::chrono::system_clock::time_point t) {
  const std::time_t tt = std::chrono::system_clock::to_time_t(t);
  std::tm tm{};
  gmtime_r(&tt, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  return buf;
}

// A positive random certificate serial number (no serial file to keep beside the CA).
std::string RandomSerial() {
  std::random_device rd;
  const uint64_t v = (static_cast<uint64_t>(rd()) << 32 | rd()) & 0x7fffffffffffffffULL;
  return fmt::format("0x{:016x}", v | 1);
}

class Maker {
 public:
  Maker(const PkiOptions& o, fs::path program) : o_(o), openssl_(std::move(program)) {
    cnf_ = o_.dir / ".openssl-req.cnf";
    // `openssl req` needs a configuration; this one brings nothing of the system's (no default extensions).
    WriteText(cnf_, "[req]\ndistinguished_name = dn\nprompt = no\n[dn]\n");
  }
  ~Maker() {
    std::error_code ec;
    fs::remove(cnf_, ec);
  }
  Maker(const Maker&) = delete;
  Maker& operator=(const Maker&) = delete;

  void NewKey(const fs::path& key) {
    RemoveStaged(key);
    Run({"genpkey", "-algorithm", "EC", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-pkeyopt",
         "ec_param_enc:named_curve", "-out", Staged(key).string()});
    Commit(key, kPrivateFile);
  }

  void NewCa(const fs::path& key, const fs::path& cert) {
    NewKey(key);
    RemoveStaged(cert);
    // digitalSignature: the CA signs the governance and permissions documents too, and S/MIME verification
    // (PKCS7_verify, in both DDS stacks) refuses a signer whose key usage lacks it.
    Run({"req",         "-config",
         cnf_.string(), "-new",
         "-x509",       "-key",
         key.string(),  "-subj",
         kCaSubject,    "-sha256",
         "-days",       std::to_string(o_.days),
         "-set_serial", RandomSerial(),
         "-addext",     "basicConstraints=critical,CA:TRUE",
         "-addext",     "keyUsage=critical,digitalSignature,keyCertSign,cRLSign",
         "-out",        Staged(cert).string()});
    Commit(cert, kPublicFile);
  }

  void NewCert(const fs::path& key, const fs::path& cert, const std::string& name) {
    RemoveStaged(cert);
    Run({"req",
         "-config",
         cnf_.string(),
         "-new",
         "-x509",
         "-key",
         key.string(),
         "-CA",
         Ca().string(),
         "-CAkey",
         CaKey().string(),
         "-subj",
         OpensslSubject(name),
         "-sha256",
         "-days",
         std::to_string(o_.days),
         "-set_serial",
         RandomSerial(),
         "-addext",
         "basicConstraints=critical,CA:FALSE",
         "-addext",
         "keyUsage=critical,digitalSignature,keyAgreement",
         "-out",
         Staged(cert).string()});
    Commit(cert, kPublicFile);
  }

  // Writes `xml` and its S/MIME signature by the CA (-text: both stacks verify with PKCS7_TEXT).
  void Signed(const fs::path& xml_file, const fs::path& p7s, const std::string& xml) {
    WriteText(xml_file, xml);
    RemoveStaged(p7s);
    Run({"smime", "-sign", "-text", "-in", xml_file.string(), "-out", Staged(p7s).string(), "-signer",
         Ca().string(), "-inkey", CaKey().string()});
    Commit(p7s, kPublicFile);
  }

  fs::path Ca() const { return o_.dir / "ca.pem"; }
  fs::path CaKey() const { return o_.dir / "ca.key"; }

 private:
  void Run(const std::vector<std::string>& args) { detail::RunOpenssl(openssl_, args); }

  const PkiOptions& o_;
  fs::path openssl_;
  fs::path cnf_;
};

bool Exists(const fs::path& p) {
  std::error_code ec;
  return fs::exists(p, ec);
}

std::string ReadFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A document that is missing or says other than the code would: the table changed since it was signed.
bool Stale(const fs::path& xml, const std::string& wanted) {
  return !Exists(xml) || ReadFile(xml) != wanted;
}

// The same for a permissions document, compared under its own validity dates.
bool StalePermissions(const fs::path& xml, const Identity& id) {
  if (!Exists(xml)) return true;
  const std::string text = ReadFile(xml);
  auto element = [&text](const std::string& tag) {
    const std::string open = "<" + tag + ">", close = "</" + tag + ">";
    const auto a = text.find(open);
    const auto b = a == std::string::npos ? a : text.find(close, a);
    return b == std::string::npos ? std::string() : text.substr(a + open.size(), b - a - open.size());
  };
  return text != PermissionsXml(id, element("not_before"), element("not_after"));
}

}  // namespace

std::string_view OutcomeName(Outcome o) {
  switch (o) {
    case Outcome::kCreated:
      return "created";
    case Outcome::kKept:
      return "kept";
    case Outcome::kReissued:
      return "reissued";
    case Outcome::kReplaced:
      return "replaced";
  }
  return "?";
}

PkiReport InitPki(const PkiOptions& o) {
  if (o.dir.empty()) throw Error(Errc::kInvalidArgument, "no directory for the PKI");
  const fs::path openssl = detail::FindProgram(o.openssl);
  MakePrivateDir(o.dir);
  MakePrivateDir(o.dir / "identities");
  Maker m(o, openssl);

  PkiReport report{};
  const bool has_cert = Exists(m.Ca()), has_key = Exists(m.CaKey());
  if (!o.force && has_cert != has_key)
    throw Error(Errc::kFailedPrecondition,
                fmt::format("the CA in {} is incomplete: {} is missing ('pki init --force' makes a new PKI)",
                            o.dir.string(), (has_cert ? m.CaKey() : m.Ca()).string()));
  const bool new_ca = o.force || !has_cert;
  if (new_ca) m.NewCa(m.CaKey(), m.Ca());
  report.ca = !new_ca ? Outcome::kKept : (has_cert || has_key) ? Outcome::kReplaced : Outcome::kCreated;

  // Documents are signed by the CA: a new CA re-signs them; so does a document the code now writes otherwise
  // (the table changed since), keeping every key.
  const fs::path gov_xml = o.dir / "governance.xml", gov_p7s = o.dir / "governance.p7s";
  const bool had_gov = Exists(gov_xml) && Exists(gov_p7s);
  report.governance = !had_gov                                      ? Outcome::kCreated
                      : o.force                                     ? Outcome::kReplaced
                      : (new_ca || Stale(gov_xml, GovernanceXml())) ? Outcome::kReissued
                                                                    : Outcome::kKept;
  if (report.governance != Outcome::kKept) m.Signed(gov_xml, gov_p7s, GovernanceXml());

  const auto now = std::chrono::system_clock::now();
  // A day early: Fast DDS reads the dates as local time.
  const std::string not_before = UtcTime(now - std::chrono::hours(24));
  const std::string not_after = UtcTime(now + std::chrono::hours(24) * o.days);
  for (const auto& id : o.identities) {
    const std::string name = id.Name();
    const fs::path d = o.dir / "identities" / name;
    MakePrivateDir(d);
    const fs::path key = d / "key.pem", cert = d / "cert.pem";
    const fs::path perm_xml = d / "permissions.xml", perm_p7s = d / "permissions.p7s";
    const bool had_key = Exists(key);
    bool new_cert = true, new_doc = true;
    Outcome out = had_key ? Outcome::kReplaced : Outcome::kCreated;
    if (!o.force && had_key) {
      new_cert = new_ca || !Exists(cert);
      new_doc = new_ca || !Exists(perm_p7s) || StalePermissions(perm_xml, id);
      out = new_cert || new_doc ? Outcome::kReissued : Outcome::kKept;
    } else {
      m.NewKey(key);
    }
    if (new_cert) m.NewCert(key, cert, name);
    if (new_doc) m.Signed(perm_xml, perm_p7s, PermissionsXml(id, not_before, not_after));
    report.identities.emplace_back(name, out);
  }
  return report;
}

fs::path DefaultPkiDir() {
  return config::ConfigDir() / "security";
}

fs::path SecurityDir() {
  const fs::path data = config::DataDir() / "security";
  std::error_code ec;
  if (fs::is_directory(data, ec)) return data;
  return DefaultPkiDir();
}

IdentityFiles FindIdentityFiles(const fs::path& dir, std::string_view name) {
  if (!ParseIdentity(name))
    throw Error(
        Errc::kInvalidArgument,
        fmt::format("'{}' is no cell identity (program-store, scheduler, inspection-writer, operator, "
                    "viewer, interpreter-<station>, axis-servo-<station>)",
                    name));
  const fs::path d = dir / "identities" / std::string(name);
  IdentityFiles f{dir / "ca.pem",        dir / "governance.p7s",
                  d / "cert.pem",        d / "key.pem",
                  d / "permissions.p7s", Exists(dir / "crl.pem") ? dir / "crl.pem" : fs::path()};
  for (const fs::path* p : {&f.ca, &f.governance, &f.certificate, &f.key, &f.permissions})
    if (!Exists(*p))
      throw Error(Errc::kNotFound,
                  fmt::format("security: {} is missing (make the PKI with 'cellctl pki init')", p->string()));
  return f;
}

namespace {

// openssl's output of `args` (which end in "-out"), through a private temporary file; nullopt when it fails.
std::optional<std::string> OpensslOutput(const fs::path& openssl, std::vector<std::string> args) {
  std::string dir = (fs::temp_directory_path() / "cell-diagnose-XXXXXX").string();
  if (::mkdtemp(dir.data()) == nullptr) return std::nullopt;
  const fs::path out = fs::path(dir) / "out";
  args.push_back(out.string());
  std::optional<std::string> text;
  try {
    detail::RunOpenssl(openssl, args);
    std::ifstream in(out, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  } catch (const Error&) {
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
  return text;
}

std::string Trimmed(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ')) s.pop_back();
  return s;
}

// The certificate's own checks: issued by the CA, the identity's subject, the private key's pair.
std::string DiagnoseCertificate(const fs::path& openssl, const std::string& identity, const fs::path& ca,
                                const fs::path& certificate, const fs::path& key, const fs::path& crl) {
  const std::string cert = certificate.filename().string() + " (" + identity + ")";
  try {
    detail::RunOpenssl(openssl, {"verify", "-CAfile", ca.string(), certificate.string()});
  } catch (const Error&) {
    return cert + ": not a certificate issued by " + ca.string();
  }
  if (!crl.empty()) {
    try {
      detail::RunOpenssl(openssl, {"verify", "-crl_check", "-CRLfile", crl.string(), "-CAfile", ca.string(),
                                   certificate.string()});
    } catch (const Error&) {
      return fmt::format("{}: revoked ({} lists it)", cert, crl.string());
    }
  }
  // A certificate swapped for another identity's verifies against the CA; its subject gives it away.
  if (auto subject = OpensslOutput(openssl, {"x509", "-in", certificate.string(), "-noout", "-subject",
                                             "-nameopt", "RFC2253", "-out"})) {
    std::string got = Trimmed(*subject);
    if (got.rfind("subject=", 0) == 0) got = got.substr(8);
    if (!identity.empty() && got != SubjectName(identity))
      return fmt::format(
          "{}: the certificate of {}, not of {} (a certificate swapped for another's: copy the "
          "identity's own files back, or `cellctl pki init` issues them again)",
          cert, got, identity);
  }
  auto cert_key = OpensslOutput(openssl, {"x509", "-in", certificate.string(), "-noout", "-pubkey", "-out"});
  auto own_key = OpensslOutput(openssl, {"pkey", "-in", key.string(), "-pubout", "-out"});
  if (cert_key && own_key && *cert_key != *own_key)
    return fmt::format("{}: {} is not the private key of this certificate", cert, key.string());
  return "";
}

}  // namespace

std::string RevokeIdentity(const fs::path& dir, std::string_view name, const std::string& openssl_name) {
  const fs::path cert = dir / "identities" / std::string(name) / "cert.pem";
  const fs::path ca = dir / "ca.pem", ca_key = dir / "ca.key";
  for (const fs::path* p : {&cert, &ca, &ca_key})
    if (!Exists(*p))
      throw Error(Errc::kNotFound, fmt::format("cannot revoke {}: {} is missing", name, p->string()));
  const fs::path openssl = detail::FindProgram(openssl_name);
  const auto serial = OpensslOutput(openssl, {"x509", "-in", cert.string(), "-noout", "-serial", "-out"});
  if (!serial) throw Error(Errc::kInvalidArgument, fmt::format("cannot read {}", cert.string()));
  // openssl ca keeps revoked serials in a text database beside the CA; the CRL is signed from it.
  const fs::path index = dir / "crl-index.txt", cnf = dir / "crl.cnf";
  if (!Exists(index)) std::ofstream(index).close();
  std::ofstream(cnf, std::ios::trunc)
      << "[ca]\ndefault_ca = cell\n[cell]\ndatabase = " << index.string()
      << "\ndefault_md = sha256\ndefault_crl_days = 3650\nunique_subject = no\n";
  try {
    detail::RunOpenssl(openssl, {"ca", "-config", cnf.string(), "-revoke", cert.string(), "-keyfile",
                                 ca_key.string(), "-cert", ca.string()});
  } catch (const Error& e) {
    // Revoked before: openssl says so and changes nothing; the CRL is signed again below all the same.
    if (std::string(e.what()).find("lready revoked") == std::string::npos) throw;
  }
  const fs::path staged = dir / "crl.pem.new";
  detail::RunOpenssl(openssl, {"ca", "-config", cnf.string(), "-gencrl", "-keyfile", ca_key.string(), "-cert",
                               ca.string(), "-out", staged.string()});
  // Public like ca.pem: every process of the cell reads it.
  fs::permissions(staged, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read |
                              fs::perms::others_read);
  fs::rename(staged, dir / "crl.pem");
  std::string text = Trimmed(*serial);
  if (text.rfind("serial=", 0) == 0) text = text.substr(7);
  return text;
}

std::string DiagnoseIdentity(const std::string& identity, const fs::path& ca, const fs::path& governance,
                             const fs::path& certificate, const fs::path& key, const fs::path& permissions,
                             const fs::path& crl) {
  fs::path openssl;
  try {
    openssl = detail::FindProgram("openssl");
  } catch (const Error&) {
    return "";
  }
  if (std::string why = DiagnoseCertificate(openssl, identity, ca, certificate, key, crl); !why.empty())
    return why;
  for (const fs::path& doc : {governance, permissions}) {
    try {
      detail::RunOpenssl(openssl, {"smime", "-verify", "-text", "-in", doc.string(), "-CAfile", ca.string(),
                                   "-out", "/dev/null"});
    } catch (const Error&) {
      return doc.string() + ": its signature does not verify against " + ca.string() +
             " (a changed or foreign document: sign it again with `cellctl pki init`)";
    }
  }
  return "";
}

}  // namespace cell::security
