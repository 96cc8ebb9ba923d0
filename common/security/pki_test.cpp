// The PKI on disk: every file where docs/security.md says, owner-only keys, certificates and signatures that
// openssl verifies against the CA (and not against another CA), re-runs that keep keys, --force that
// replaces them, and one-line errors.
#include "cell/security/pki.h"

#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "cell/error/error.h"
#include "openssl.h"

namespace cell::security {
namespace {

namespace fs = std::filesystem;

std::string Read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

unsigned Mode(const fs::path& p) {
  struct stat st {};
  EXPECT_EQ(::stat(p.c_str(), &st), 0) << p;
  return st.st_mode & 07777;
}

void Openssl(const std::vector<std::string>& args) {
  detail::RunOpenssl(detail::FindProgram("openssl"), args);
}

class Pki : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string t = (fs::temp_directory_path() / "cell-pki-test-XXXXXX").string();
    ASSERT_NE(::mkdtemp(t.data()), nullptr);
    tmp_ = t;
    opts_.dir = tmp_ / "security";
    opts_.identities = CellIdentities({"KT01"});
  }
  void TearDown() override { fs::remove_all(tmp_); }

  fs::path Id(const std::string& name) const { return opts_.dir / "identities" / name; }

  // `openssl smime -verify` of p7s against ca: the signed text, its lines ending in LF again (S/MIME text
  // travels with CRLF; the stacks' XML parsers take either).
  std::string VerifiedText(const fs::path& p7s, const fs::path& ca) {
    const fs::path out = tmp_ / "verified.xml";
    fs::remove(out);
    Openssl({"smime", "-verify", "-text", "-in", p7s.string(), "-CAfile", ca.string(), "-out", out.string()});
    std::string text = Read(out);
    std::erase(text, '\r');
    return text;
  }

  fs::path tmp_;
  PkiOptions opts_;
};

TEST_F(Pki, MakesEveryFileOwnerOnlyWhereKeysAre) {
  const PkiReport r = InitPki(opts_);
  EXPECT_EQ(r.ca, Outcome::kCreated);
  EXPECT_EQ(r.governance, Outcome::kCreated);
  ASSERT_EQ(r.identities.size(), 8u);
  for (auto& [name, out] : r.identities) EXPECT_EQ(out, Outcome::kCreated) << name;

  const fs::path& d = opts_.dir;
  EXPECT_EQ(Mode(d), 0700u);
  EXPECT_EQ(Mode(d / "identities"), 0700u);
  EXPECT_EQ(Mode(d / "ca.key"), 0600u);
  EXPECT_EQ(Mode(d / "ca.pem"), 0644u);
  EXPECT_EQ(Mode(d / "governance.xml"), 0644u);
  EXPECT_EQ(Mode(d / "governance.p7s"), 0644u);
  for (const char* name : {"program-store", "scheduler", "inspection-writer", "operator", "viewer",
                           "interpreter-KT01", "axis-servo-KT01", "dnc-KT01"}) {
    EXPECT_EQ(Mode(Id(name)), 0700u) << name;
    EXPECT_EQ(Mode(Id(name) / "key.pem"), 0600u) << name;
    EXPECT_EQ(Mode(Id(name) / "cert.pem"), 0644u) << name;
    EXPECT_EQ(Mode(Id(name) / "permissions.xml"), 0644u) << name;
    EXPECT_EQ(Mode(Id(name) / "permissions.p7s"), 0644u) << name;
    EXPECT_NO_THROW(FindIdentityFiles(d, name));
  }
  // Nothing else: no staged files, no openssl configuration left behind.
  size_t files = 0;
  for (auto& e : fs::recursive_directory_iterator(d)) files += e.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, 4u + 8u * 4u);
}

TEST_F(Pki, CertificatesAndSignaturesVerifyAgainstTheCaAndNoOther) {
  InitPki(opts_);
  PkiOptions other = opts_;
  other.dir = tmp_ / "other";
  other.identities = {};
  InitPki(other);
  const fs::path ca = opts_.dir / "ca.pem", other_ca = other.dir / "ca.pem";

  for (const auto& id : opts_.identities) {
    const fs::path cert = Id(id.Name()) / "cert.pem";
    EXPECT_NO_THROW(Openssl({"verify", "-CAfile", ca.string(), cert.string()})) << id.Name();
    EXPECT_THROW(Openssl({"verify", "-CAfile", other_ca.string(), cert.string()}), Error) << id.Name();
    // The subject both DDS stacks compare with the grant's <subject_name>.
    const fs::path subject = tmp_ / "subject.txt";
    Openssl({"x509", "-in", cert.string(), "-noout", "-subject", "-nameopt", "RFC2253", "-out",
             subject.string()});
    EXPECT_EQ(Read(subject), "subject=" + SubjectName(id.Name()) + "\n");

    const fs::path p7s = Id(id.Name()) / "permissions.p7s";
    EXPECT_EQ(VerifiedText(p7s, ca), Read(Id(id.Name()) / "permissions.xml")) << id.Name();
    EXPECT_THROW(VerifiedText(p7s, other_ca), Error) << id.Name();
  }
  EXPECT_EQ(VerifiedText(opts_.dir / "governance.p7s", ca), GovernanceXml());

  // A document changed after signing is refused.
  const fs::path p7s = Id("viewer") / "permissions.p7s";
  std::string text = Read(p7s);
  const auto at = text.find("<default>DENY</default>");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 23, "<default>ALLOW</default>");
  std::ofstream(p7s, std::ios::binary | std::ios::trunc) << text;
  EXPECT_THROW(VerifiedText(p7s, ca), Error);
}

// Issue 39 item 9: a station's certificate swapped for another's verifies against the CA, so the stack's
// refusal said only "cannot create a DDS participant"; the diagnosis names the identity and what is wrong.
TEST_F(Pki, DiagnoseNamesASwappedCertificateAndAForeignKey) {
  InitPki(opts_);
  const fs::path ca = opts_.dir / "ca.pem", gov = opts_.dir / "governance.p7s";
  auto diagnose = [&](const std::string& id) {
    return DiagnoseIdentity(id, ca, gov, Id(id) / "cert.pem", Id(id) / "key.pem", Id(id) / "permissions.p7s");
  };
  EXPECT_EQ(diagnose("interpreter-KT01"), "");  // the control: its own files
  fs::copy_file(Id("axis-servo-KT01") / "cert.pem", Id("interpreter-KT01") / "cert.pem",
                fs::copy_options::overwrite_existing);
  EXPECT_EQ(
      diagnose("interpreter-KT01"),
      "cert.pem (interpreter-KT01): the certificate of " + SubjectName("axis-servo-KT01") +
          ", not of interpreter-KT01 (a certificate swapped for another's: copy the identity's own files "
          "back, or `cellctl pki init` issues them again)");
  fs::copy_file(Id("axis-servo-KT01") / "key.pem", Id("viewer") / "key.pem",
                fs::copy_options::overwrite_existing);
  EXPECT_EQ(diagnose("viewer"), "cert.pem (viewer): " + (Id("viewer") / "key.pem").string() +
                                    " is not the private key of this certificate");
}

TEST_F(Pki, ARerunKeepsEveryKeyAndAddsNewStations) {
  InitPki(opts_);
  const std::string ca_key = Read(opts_.dir / "ca.key"), key = Read(Id("interpreter-KT01") / "key.pem");
  const std::string cert = Read(Id("interpreter-KT01") / "cert.pem");

  opts_.identities = CellIdentities({"KT01", "KT02"});
  const PkiReport r = InitPki(opts_);
  EXPECT_EQ(r.ca, Outcome::kKept);
  EXPECT_EQ(r.governance, Outcome::kKept);
  for (auto& [name, out] : r.identities)
    EXPECT_EQ(out, name.find("KT02") != std::string::npos ? Outcome::kCreated : Outcome::kKept) << name;
  EXPECT_EQ(Read(opts_.dir / "ca.key"), ca_key);
  EXPECT_EQ(Read(Id("interpreter-KT01") / "key.pem"), key);
  EXPECT_EQ(Read(Id("interpreter-KT01") / "cert.pem"), cert);
  // The new station is signed by the CA that was there.
  EXPECT_NO_THROW(Openssl(
      {"verify", "-CAfile", (opts_.dir / "ca.pem").string(), (Id("axis-servo-KT02") / "cert.pem").string()}));
}

TEST_F(Pki, AMissingCertificateIsReissuedForTheKeptKey) {
  InitPki(opts_);
  const std::string key = Read(Id("operator") / "key.pem");
  fs::remove(Id("operator") / "cert.pem");
  const PkiReport r = InitPki(opts_);
  for (auto& [name, out] : r.identities)
    EXPECT_EQ(out, name == "operator" ? Outcome::kReissued : Outcome::kKept);
  EXPECT_EQ(Read(Id("operator") / "key.pem"), key);
  EXPECT_NO_THROW(Openssl(
      {"verify", "-CAfile", (opts_.dir / "ca.pem").string(), (Id("operator") / "cert.pem").string()}));
}

TEST_F(Pki, ADocumentTheCodeNoLongerWritesIsSignedAgainKeepingTheKey) {
  InitPki(opts_);
  const fs::path xml = Id("viewer") / "permissions.xml";
  const std::string key = Read(Id("viewer") / "key.pem"), cert = Read(Id("viewer") / "cert.pem");
  const std::string signed_before = Read(Id("viewer") / "permissions.p7s");
  std::string text = Read(xml);
  text.replace(text.find("<subscribe>"), 11,
               "<publish><topics><topic>cell/edited/*</topic></topics></publish><subscribe>");
  std::ofstream(xml, std::ios::binary | std::ios::trunc) << text;
  std::ofstream(opts_.dir / "governance.xml", std::ios::app) << "<!-- edited -->\n";

  const PkiReport r = InitPki(opts_);
  EXPECT_EQ(r.ca, Outcome::kKept);
  EXPECT_EQ(r.governance, Outcome::kReissued);
  for (auto& [name, out] : r.identities)
    EXPECT_EQ(out, name == "viewer" ? Outcome::kReissued : Outcome::kKept);
  EXPECT_EQ(Read(Id("viewer") / "key.pem"), key);
  EXPECT_EQ(Read(Id("viewer") / "cert.pem"), cert);
  EXPECT_NE(Read(Id("viewer") / "permissions.p7s"), signed_before);
  // The edit is gone (the viewer publishes one topic of its own since the Gantt chart: look for the edit's).
  EXPECT_EQ(Read(xml).find("cell/edited/*"), std::string::npos);
  EXPECT_EQ(VerifiedText(Id("viewer") / "permissions.p7s", opts_.dir / "ca.pem"), Read(xml));
  EXPECT_EQ(VerifiedText(opts_.dir / "governance.p7s", opts_.dir / "ca.pem"), GovernanceXml());
  // And a second run finds nothing to do.
  const PkiReport again = InitPki(opts_);
  EXPECT_EQ(again.governance, Outcome::kKept);
  for (auto& [name, out] : again.identities) EXPECT_EQ(out, Outcome::kKept) << name;
}

TEST_F(Pki, ForceReplacesEveryKey) {
  InitPki(opts_);
  const std::string ca_key = Read(opts_.dir / "ca.key"), key = Read(Id("scheduler") / "key.pem");
  opts_.force = true;
  const PkiReport r = InitPki(opts_);
  EXPECT_EQ(r.ca, Outcome::kReplaced);
  for (auto& [name, out] : r.identities) EXPECT_EQ(out, Outcome::kReplaced) << name;
  EXPECT_NE(Read(opts_.dir / "ca.key"), ca_key);
  EXPECT_NE(Read(Id("scheduler") / "key.pem"), key);
  EXPECT_EQ(Mode(Id("scheduler") / "key.pem"), 0600u);
  EXPECT_NO_THROW(Openssl(
      {"verify", "-CAfile", (opts_.dir / "ca.pem").string(), (Id("scheduler") / "cert.pem").string()}));
}

TEST_F(Pki, AHalfCaIsRefusedWithoutForce) {
  InitPki(opts_);
  fs::remove(opts_.dir / "ca.key");
  try {
    InitPki(opts_);
    FAIL() << "a CA without its key was used";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kFailedPrecondition);
    EXPECT_NE(std::string(e.what()).find("ca.key is missing"), std::string::npos) << e.what();
  }
  opts_.force = true;
  EXPECT_EQ(InitPki(opts_).ca, Outcome::kReplaced);
}

TEST_F(Pki, WithoutOpensslTheErrorIsOneLine) {
  opts_.openssl = (tmp_ / "no-such-openssl").string();
  try {
    InitPki(opts_);
    FAIL() << "ran without openssl";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kFailedPrecondition);
    EXPECT_NE(std::string(e.what()).find("openssl not found"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(opts_.dir));

  // By name, through PATH.
  const char* old = std::getenv("PATH");
  const std::string saved = old ? old : "";
  ::setenv("PATH", tmp_.c_str(), 1);
  opts_.openssl = "openssl";
  EXPECT_THROW(InitPki(opts_), Error);
  ::setenv("PATH", saved.c_str(), 1);
}

TEST_F(Pki, AnUnwritableDirectoryIsAOneLineError) {
  std::ofstream(tmp_ / "a-file") << "x";
  opts_.dir = tmp_ / "a-file" / "security";
  try {
    InitPki(opts_);
    FAIL() << "made a PKI below a file";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kIo);
    EXPECT_NE(std::string(e.what()).find((tmp_ / "a-file").string()), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
}

TEST_F(Pki, AFailingOpensslCommandQuotesItsError) {
  InitPki(opts_);
  std::ofstream(opts_.dir / "ca.key", std::ios::trunc) << "not a key\n";
  opts_.identities = CellIdentities({"KT09"});
  try {
    InitPki(opts_);
    FAIL() << "signed with a broken CA key";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kInternal);
    EXPECT_EQ(std::string(e.what()).rfind("openssl req failed", 0), 0u) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
}

TEST_F(Pki, FindIdentityFilesNamesWhatIsMissing) {
  InitPki(opts_);
  const IdentityFiles f = FindIdentityFiles(opts_.dir, "axis-servo-KT01");
  EXPECT_EQ(f.key, Id("axis-servo-KT01") / "key.pem");
  EXPECT_EQ(f.governance, opts_.dir / "governance.p7s");
  fs::remove(f.permissions);
  try {
    FindIdentityFiles(opts_.dir, "axis-servo-KT01");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kNotFound);
    EXPECT_NE(std::string(e.what()).find(f.permissions.string()), std::string::npos) << e.what();
  }
  try {
    FindIdentityFiles(opts_.dir, "axis-servo-KT02");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kNotFound);
  }
  try {
    FindIdentityFiles(opts_.dir, "../ca");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kInvalidArgument);
  }
}

TEST_F(Pki, SecurityDirPrefersTheDataDirectory) {
  const char* d = std::getenv("CELL_DATA_DIR");
  const char* c = std::getenv("CELL_CONFIG_DIR");
  const std::string saved_d = d ? d : "", saved_c = c ? c : "";
  ::setenv("CELL_DATA_DIR", (tmp_ / "data").c_str(), 1);
  ::setenv("CELL_CONFIG_DIR", (tmp_ / "config").c_str(), 1);
  EXPECT_EQ(SecurityDir(), tmp_ / "config" / "security");
  EXPECT_EQ(DefaultPkiDir(), tmp_ / "config" / "security");
  fs::create_directories(tmp_ / "data" / "security");
  EXPECT_EQ(SecurityDir(), tmp_ / "data" / "security");
  d ? ::setenv("CELL_DATA_DIR", saved_d.c_str(), 1) : ::unsetenv("CELL_DATA_DIR");
  c ? ::setenv("CELL_CONFIG_DIR", saved_c.c_str(), 1) : ::unsetenv("CELL_CONFIG_DIR");
}

}  // namespace
}  // namespace cell::security
