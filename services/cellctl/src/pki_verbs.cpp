// cellctl pki init|revoke: the cell's CA, identities and signed documents (docs/security.md). No bus.
#include <algorithm>

#include "cell/config/config.h"
#include "cell/security/pki.h"
#include "context.h"

namespace cellctl {

namespace {

// The configured stations (CELL_CONFIG_DIR/stations), then those named on the command line.
std::vector<std::string> Stations(const std::vector<std::string>& extra) {
  std::vector<std::string> out;
  try {
    out = cell::config::ListStations();
  } catch (const cell::Error& e) {
    // No stations directory: a PKI for the stations named, or for the cell services alone.
    if (e.code() != cell::Errc::kNotFound) throw;
  }
  for (const auto& s : extra)
    if (std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
  return out;
}

}  // namespace

void AddPkiVerbs(CLI::App& app, Context&) {
  struct Opts {
    std::string dir;
    bool force = false;
    std::vector<std::string> stations;
    std::string name;
  };
  auto o = std::make_shared<Opts>();
  auto* pki =
      app.add_subcommand("pki", "the cell's DDS Security PKI (docs/security.md)")->require_subcommand(1);

  auto* init = pki->add_subcommand(
      "init",
      "make the cell CA, one certificate and key per identity (cell services, operator, viewer, each "
      "station's "
      "interpreter and axis servo), the signed governance and permissions; keeps what exists");
  init->add_option("--dir", o->dir, "where (default: CELL_CONFIG_DIR/security)");
  init->add_flag("--force", o->force, "replace the CA and every key, certificate and document");
  init->add_option("--station", o->stations,
                   "a station besides those of CELL_CONFIG_DIR/stations (repeatable)");
  init->callback([o] {
    cell::security::PkiOptions po;
    po.dir = o->dir.empty() ? cell::security::DefaultPkiDir() : std::filesystem::path(o->dir);
    po.identities = cell::security::CellIdentities(Stations(o->stations));
    po.force = o->force;
    const auto r = cell::security::InitPki(po);
    std::cout << "ca: " << cell::security::OutcomeName(r.ca) << "\n";
    std::cout << "governance: " << cell::security::OutcomeName(r.governance) << "\n";
    for (const auto& [name, outcome] : r.identities)
      std::cout << name << ": " << cell::security::OutcomeName(outcome) << "\n";
    std::cout << "pki in " << po.dir.string() << " (" << r.identities.size() << " identities)\n";
  });

  // Issue 39 item 8: one identity out, the rest of the PKI kept.
  auto* revoke = pki->add_subcommand(
      "revoke",
      "revoke one identity's certificate (crl.pem, read by every process at its start): it can no longer "
      "join the cell, nor is it accepted by processes started afterwards");
  revoke->add_option("NAME", o->name, "the identity (interpreter-KT02, viewer, ...)")->required();
  revoke->add_option("--dir", o->dir, "the PKI (default: where the cell's processes find it)");
  revoke->callback([o] {
    const std::filesystem::path dir =
        o->dir.empty() ? cell::security::SecurityDir() : std::filesystem::path(o->dir);
    if (!cell::security::ParseIdentity(o->name))
      throw Exit{2, "'" + o->name + "' is no cell identity (docs/security.md)"};
    const std::string serial = cell::security::RevokeIdentity(dir, o->name);
    std::cout << "revoked " << o->name << " (serial " << serial << "): " << (dir / "crl.pem").string()
              << "; restart the cell's processes to apply it to those already running\n";
  });
}

}  // namespace cellctl
