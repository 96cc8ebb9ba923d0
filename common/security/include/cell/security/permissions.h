// Who may write and read which topic (docs/security.md): the one permissions table of the cell, the
// identities it names, and the DDS Security documents made from it (governance, permissions per identity).
// Pure functions; cell/security/pki.h writes and signs the documents.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cell::security {

// A role is what an identity does. Station roles have one identity per station ("interpreter-KT01").
enum class Role {
  kProgramStore,      // cell-program-store
  kScheduler,         // cell-scheduler
  kInspectionWriter,  // cell-inspection-writer
  kInterpreter,       // cell-interpreter --station ID
  kAxisServo,         // cell-axis-servo --station ID
  kDnc,               // cell-dnc --station ID (stations with a [serial] line)
  kOperator,          // cellctl
  kViewer,            // cell-dashboard, read-only cellctl (CELL_IDENTITY=viewer)
};

// Every role, in the table's column order.
const std::vector<Role>& Roles();
std::string_view RoleName(Role r);  // "program-store", "interpreter", ...
bool IsStationRole(Role r);         // interpreter, axis-servo, dnc

// How far a topic's grants can be narrowed to one station.
enum class Scope {
  kCell,           // carries no station's data (or only the cell services' view of it)
  kOwnStation,     // "cell/station/<ID>/...": a station identity is granted its own station's topic only
  kSharedKeyed,    // one topic keyed by station or service: a station identity writes it in its own partition
                   // only, and every reader drops a station identity's sample about another station
  kSharedService,  // a cell service's request or reply topic that station identities use too: the service
                   // knows each request's sender (its partition) and refuses another station's data
};

// Partitions (docs/security.md, "Partitions"): every participant writes in the one partition of its
// identity, "id/<identity>", and reads every partition ("*"). The permissions grant each identity its own
// partition only, so the partition of a sample names its writer's authenticated identity.
std::string WritePartition(const std::string& identity_name);   // "id/interpreter-KT01"
std::string IdentityOfPartition(const std::string& partition);  // "" unless "id/<identity>"
inline constexpr std::string_view kReadPartition = "*";

// One row of the table. `topic` is a topic name, or a pattern with "<ID>" standing for a station id.
struct TopicRule {
  std::string_view topic;
  std::vector<Role> publish;
  std::vector<Role> subscribe;
  Scope scope;
  std::string_view use;  // who uses it today, for the docs
};

// The table (docs/security.md renders it). Every topic of cell/bus/topics.h appears; request/reply services
// as their two topics "<name>/request" and "<name>/reply".
const std::vector<TopicRule>& Table();

// One identity: a role, and for station roles the station id.
struct Identity {
  Role role;
  std::string station;       // empty unless IsStationRole(role)
  std::string Name() const;  // "scheduler", "interpreter-KT01"
  bool operator==(const Identity&) const = default;
};

// The identity a name stands for; nullopt for an unknown role or a malformed station id.
std::optional<Identity> ParseIdentity(std::string_view name);

// The identities of a cell with these stations: the cell services, operator, viewer, then the two station
// identities of each station in the order given. Throws cell::Error(kInvalidArgument) for a malformed
// station id (names::IsStationId).
std::vector<Identity> CellIdentities(const std::vector<std::string>& stations);

// The topic names (fnmatch patterns for roles that span stations, e.g. "cell/station/*/command/request")
// an identity may publish and subscribe, in table order.
struct Grants {
  std::vector<std::string> publish;    // in WritePartition(identity) only
  std::vector<std::string> subscribe;  // in kReadPartition
};
Grants GrantsFor(const Identity& id);

// The subject name of an identity's certificate as both DDS stacks compare it with the permissions
// document's <subject_name>: the RFC 2253 form of the subject "/O=cell/CN=<name>" (RFC 2253 lists the
// attributes last first). Fast DDS 2.9 compares attribute by attribute in order; Cyclone 0.10 splits at
// ',' and compares values exactly, so there are no spaces.
std::string SubjectName(const std::string& identity_name);
// The same subject in openssl's -subj form.
std::string OpensslSubject(const std::string& identity_name);

// The DDS domain ids the documents cover. Cyclone 0.10's parser refuses a domain id above 230 (the whole
// document, "Can not parse governance file"), so a secured cell uses domains 0-230 although
// config::kMaxDomain is 232.
inline constexpr int kFirstDomain = 0;
inline constexpr int kLastDomain = 230;

// The governance document: discovery, liveliness and RTPS messages encrypted, unauthenticated
// participants refused, join access control on, and every "cell/*" topic discovery- and
// liveliness-protected, read- and write-access-controlled, metadata and data encrypted.
std::string GovernanceXml();

// The permissions document of one identity: one grant for SubjectName(id), valid from not_before to
// not_after ("YYYY-MM-DDTHH:MM:SS", UTC), allowing GrantsFor(id) in their partitions, default DENY. One
// allow_rule per topic: Fast DDS 2.9 checks a writer's partitions against every criterion of the first
// rule that names its topic, so a rule shared by topics would let one topic's partition grant another's.
std::string PermissionsXml(const Identity& id, const std::string& not_before, const std::string& not_after);

// The table as the Markdown docs/security.md carries between its table markers.
std::string RenderTable();

}  // namespace cell::security
