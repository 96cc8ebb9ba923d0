#include "cell/security/permissions.h"

#include <fmt/format.h>

#include <algorithm>

#include "cell/error/error.h"
#include "cell/names/names.h"

namespace cell::security {

namespace {

constexpr Role kPs = Role::kProgramStore;
constexpr Role kSch = Role::kScheduler;
constexpr Role kIw = Role::kInspectionWriter;
constexpr Role kInt = Role::kInterpreter;
constexpr Role kSrv = Role::kAxisServo;
constexpr Role kDnc = Role::kDnc;
constexpr Role kOp = Role::kOperator;
constexpr Role kView = Role::kViewer;

constexpr std::string_view kStationMark = "<ID>";

}  // namespace

const std::vector<Role>& Roles() {
  static const std::vector<Role> roles{kPs, kSch, kIw, kInt, kSrv, kDnc, kOp, kView};
  return roles;
}

std::string_view RoleName(Role r) {
  switch (r) {
    case Role::kProgramStore:
      return "program-store";
    case Role::kScheduler:
      return "scheduler";
    case Role::kInspectionWriter:
      return "inspection-writer";
    case Role::kInterpreter:
      return "interpreter";
    case Role::kAxisServo:
      return "axis-servo";
    case Role::kDnc:
      return "dnc";
    case Role::kOperator:
      return "operator";
    case Role::kViewer:
      return "viewer";
  }
  return "?";
}

bool IsStationRole(Role r) {
  return r == Role::kInterpreter || r == Role::kAxisServo || r == Role::kDnc;
}

// Who writes and reads each topic today (the services' bus bindings), narrowed to that. The viewer and the
// operator read every state and event topic meant for people (a person sees the cell through them), not
// the machine-internal ones (credits, servo control, segments, probe results, part models) nor any reply
// but the scheduler's: the viewer asks it the plan, the one request the scheduler answers a viewer.
const std::vector<TopicRule>& Table() {
  static const std::vector<TopicRule> table{
      {"cell/health",
       {kPs, kSch, kIw, kInt, kSrv, kDnc},
       {kPs, kSch, kIw, kInt, kSrv, kDnc, kOp, kView},
       Scope::kSharedKeyed,
       "every service's heartbeat; its identity claim, the scheduler's census, `cellctl up`, the dashboard"},
      {"cell/station/status",
       {kInt},
       {kSch, kOp, kView},
       Scope::kSharedKeyed,
       "interpreter writes; scheduler (dispatch), `station ls`, dashboard read"},
      {"cell/station/tools",
       {kInt},
       {kSch, kOp, kView},
       Scope::kSharedKeyed,
       "interpreter writes; scheduler (UTL check), `station tools`, dashboard read"},
      {"cell/station/variables",
       {kInt},
       {kSch, kOp, kView},
       Scope::kSharedKeyed,
       "interpreter writes; scheduler (schedule IF), `station vars` read"},
      {"cell/station/io",
       {kInt},
       {kOp, kView},
       Scope::kSharedKeyed,
       "interpreter writes; `station io` reads"},
      {"cell/station/event",
       {kInt},
       {kOp, kView},
       Scope::kSharedKeyed,
       "interpreter writes the events programs record (KT-APL EVT); `watch`, dashboard read"},
      {"cell/station/program",
       {kInt},
       {kOp, kView},
       Scope::kSharedKeyed,
       "interpreter writes the text of the program each run starts; the dashboard's toolpath reads"},
      {"cell/motion/axes",
       {kSrv},
       {kOp, kView},
       Scope::kSharedKeyed,
       "axis servo writes 50 Hz axis state; the dashboard reads"},
      {"cell/run/status",
       {kInt},
       {kSch, kOp, kView},
       Scope::kSharedKeyed,
       "interpreter writes run events; scheduler, dashboard read"},
      {"cell/scheduler/state",
       {kSch},
       {kOp, kView},
       Scope::kCell,
       "scheduler writes backlog; `station ls`, `watch`, dashboard read"},
      {"cell/job/state",
       {kSch},
       {kOp, kView},
       Scope::kCell,
       "scheduler writes jobs with their decision logs; `watch`, dashboard read"},
      {"cell/job/status",
       {kSch},
       {kOp, kView},
       Scope::kCell,
       "scheduler writes job events; `job wait` reads"},
      {"cell/alarm",
       {kSch},
       {kOp, kView},
       Scope::kCell,
       "scheduler writes alarms; `station ls` and the dashboard read"},
      {"cell/program/change",
       {kPs},
       {kSch, kOp, kView},
       Scope::kCell,
       "program store writes program changes; the scheduler reads"},
      {"cell/program/list",
       {kPs},
       {kOp, kView},
       Scope::kCell,
       "program store writes the list of every namespace; `program ls` as viewer reads"},
      {"cell/dnc/status",
       {kDnc},
       {kOp, kView, kInt},
       Scope::kSharedKeyed,
       "cell-dnc writes its serial line's state (transfer, bytes, rate, stalls, errors); `dnc status`, "
       "the dashboard and the station's interpreter (a READ/WRITE refused while a transfer runs) read"},
      {"cell/inspection/stored",
       {kIw},
       {kOp, kView},
       Scope::kCell,
       "inspection writer writes what it made durable (run records, whole files); dashboard reads"},
      {"cell/station/<ID>/segments",
       {kInt},
       {kSrv},
       Scope::kOwnStation,
       "the station's interpreter streams motion segments to its axis servo"},
      {"cell/station/<ID>/probe",
       {kSrv},
       {kInt},
       Scope::kOwnStation,
       "the station's axis servo writes probe results to its interpreter"},
      {"cell/station/<ID>/progress",
       {kSrv},
       {kInt},
       Scope::kOwnStation,
       "the station's axis servo writes segment credits to its interpreter"},
      {"cell/station/<ID>/control",
       {kInt},
       {kSrv},
       Scope::kOwnStation,
       "the station's interpreter writes feed hold and overrides to its axis servo"},
      {"cell/station/<ID>/servo_tools",
       {kInt},
       {kSrv},
       Scope::kOwnStation,
       "the station's interpreter gives its axis servo's tool changer the tool table"},
      {"cell/station/<ID>/part",
       {kInt},
       {kSrv},
       Scope::kOwnStation,
       "the station's interpreter gives its axis servo the part model its pallet map names"},
      {"cell/station/run/request",
       {kSch},
       {kInt},
       Scope::kSharedService,
       "scheduler dispatches runs (pallets); each station takes those that name it"},
      {"cell/station/run/reply",
       {kInt},
       {kSch},
       Scope::kSharedService,
       "the station acknowledges dispatches; the scheduler drops a station's answer to another's"},
      {"cell/station/<ID>/command/request",
       {kSch, kOp},
       {kInt},
       Scope::kOwnStation,
       "panel verbs, tool loads, variables and inputs (`cellctl station ...`); scheduler sets variables "
       "(VSET)"},
      {"cell/station/<ID>/command/reply",
       {kInt},
       {kSch, kOp},
       Scope::kOwnStation,
       "the station answers commands"},
      {"cell/station/<ID>/dnc/request",
       {kOp, kInt},
       {kDnc},
       Scope::kOwnStation,
       "`cellctl dnc send`, `receive`, `drip`, `status`: transfers on the station's serial line; the "
       "station's interpreter: an Okuma program's READ/WRITE"},
      {"cell/station/<ID>/dnc/reply",
       {kDnc},
       {kOp, kInt},
       Scope::kOwnStation,
       "the station's cell-dnc answers when the transfer has ended"},
      {"cell/program_store/request",
       {kSch, kInt, kDnc, kOp},
       {kPs},
       Scope::kSharedService,
       "`cellctl program ...`; scheduler and interpreters read programs, interpreters store files, cell-dnc "
       "reads what it sends and stores what a control punches (its own station's namespace)"},
      {"cell/program_store/reply",
       {kPs},
       {kSch, kInt, kDnc, kOp},
       Scope::kSharedService,
       "the program store answers"},
      {"cell/scheduler/request",
       {kOp, kView},
       {kSch},
       Scope::kCell,
       "`cellctl pallet`, `route`, `schedule`, `job`, `plan`: pallet maps, routes, dispatches, jobs; the "
       "dashboard's Gantt chart asks the plan (the scheduler refuses the viewer every other request)"},
      {"cell/scheduler/reply", {kSch}, {kOp, kView}, Scope::kCell, "the scheduler answers"},
      {"cell/inspection/request",
       {kInt, kOp},
       {kIw},
       Scope::kSharedService,
       "interpreters write run records and inspection files; `cellctl inspect ...` reads them"},
      {"cell/inspection/reply", {kIw}, {kInt, kOp}, Scope::kSharedService, "the inspection writer answers"},
  };
  return table;
}

std::string Identity::Name() const {
  return IsStationRole(role) ? fmt::format("{}-{}", RoleName(role), station) : std::string(RoleName(role));
}

std::optional<Identity> ParseIdentity(std::string_view name) {
  for (Role r : Roles()) {
    const std::string_view rn = RoleName(r);
    if (!IsStationRole(r)) {
      if (name == rn) return Identity{r, ""};
      continue;
    }
    if (name.size() > rn.size() + 1 && name.substr(0, rn.size()) == rn && name[rn.size()] == '-') {
      std::string station(name.substr(rn.size() + 1));
      if (names::IsStationId(station)) return Identity{r, std::move(station)};
    }
  }
  return std::nullopt;
}

std::vector<Identity> CellIdentities(const std::vector<std::string>& stations) {
  std::vector<Identity> out;
  for (Role r : Roles())
    if (!IsStationRole(r)) out.push_back({r, ""});
  for (const auto& s : stations) {
    if (!names::IsStationId(s))
      throw Error(Errc::kInvalidArgument,
                  fmt::format("station id '{}' is malformed (1-16 of A-Z a-z 0-9 _ -)", s));
    for (Role r : Roles()) {
      Identity id{r, s};
      if (IsStationRole(r) && std::find(out.begin(), out.end(), id) == out.end()) out.push_back(id);
    }
  }
  return out;
}

namespace {

bool Has(const std::vector<Role>& roles, Role r) {
  return std::find(roles.begin(), roles.end(), r) != roles.end();
}

// The topic as granted to `id`: a station identity's own station, anyone else every station.
std::string TopicFor(std::string_view topic, const Identity& id) {
  const auto at = topic.find(kStationMark);
  if (at == std::string_view::npos) return std::string(topic);
  const std::string station = IsStationRole(id.role) ? id.station : "*";
  return fmt::format("{}{}{}", topic.substr(0, at), station, topic.substr(at + kStationMark.size()));
}

}  // namespace

Grants GrantsFor(const Identity& id) {
  Grants g;
  for (const auto& rule : Table()) {
    if (Has(rule.publish, id.role)) g.publish.push_back(TopicFor(rule.topic, id));
    if (Has(rule.subscribe, id.role)) g.subscribe.push_back(TopicFor(rule.topic, id));
  }
  return g;
}

std::string WritePartition(const std::string& identity_name) {
  return "id/" + identity_name;
}

std::string IdentityOfPartition(const std::string& partition) {
  return partition.rfind("id/", 0) == 0 ? partition.substr(3) : std::string();
}

std::string SubjectName(const std::string& identity_name) {
  return fmt::format("CN={},O=cell", identity_name);
}

std::string OpensslSubject(const std::string& identity_name) {
  return fmt::format("/O=cell/CN={}", identity_name);
}

namespace {

std::string DomainsXml(const std::string& indent) {
  return fmt::format(
      "{0}<domains>\n{0}  <id_range>\n{0}    <min>{1}</min>\n{0}    <max>{2}</max>\n"
      "{0}  </id_range>\n{0}</domains>\n",
      indent, kFirstDomain, kLastDomain);
}

}  // namespace

std::string GovernanceXml() {
  std::string x =
      "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
      "<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\"\n"
      "     xsi:noNamespaceSchemaLocation=\"http://www.omg.org/spec/DDS-Security/20170801/"
      "omg_shared_ca_governance.xsd\">\n"
      "  <domain_access_rules>\n"
      "    <domain_rule>\n";
  x += DomainsXml("      ");
  // The element order is the XSD's: Fast DDS's parser expects it.
  x += "      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>\n"
       "      <enable_join_access_control>true</enable_join_access_control>\n"
       "      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>\n"
       "      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>\n"
       "      <rtps_protection_kind>ENCRYPT</rtps_protection_kind>\n"
       "      <topic_access_rules>\n"
       "        <topic_rule>\n"
       "          <topic_expression>cell/*</topic_expression>\n"
       "          <enable_discovery_protection>true</enable_discovery_protection>\n"
       "          <enable_liveliness_protection>true</enable_liveliness_protection>\n"
       "          <enable_read_access_control>true</enable_read_access_control>\n"
       "          <enable_write_access_control>true</enable_write_access_control>\n"
       "          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>\n"
       "          <data_protection_kind>ENCRYPT</data_protection_kind>\n"
       "        </topic_rule>\n"
       "      </topic_access_rules>\n"
       "    </domain_rule>\n"
       "  </domain_access_rules>\n"
       "</dds>\n";
  return x;
}

std::string PermissionsXml(const Identity& id, const std::string& not_before, const std::string& not_after) {
  const Grants g = GrantsFor(id);
  std::string x = fmt::format(
      "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
      "<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\"\n"
      "     xsi:noNamespaceSchemaLocation=\"http://www.omg.org/spec/DDS-Security/20170801/"
      "omg_shared_ca_permissions.xsd\">\n"
      "  <permissions>\n"
      "    <grant name=\"{0}\">\n"
      "      <subject_name>{1}</subject_name>\n"
      "      <validity>\n"
      "        <not_before>{2}</not_before>\n"
      "        <not_after>{3}</not_after>\n"
      "      </validity>\n",
      id.Name(), SubjectName(id.Name()), not_before, not_after);
  auto criterion = [&x](const char* what, const std::string& topic, std::string_view partition) {
    x += fmt::format(
        "        <{0}>\n          <topics>\n            <topic>{1}</topic>\n          </topics>\n"
        "          <partitions>\n            <partition>{2}</partition>\n          </partitions>\n"
        "        </{0}>\n",
        what, topic, partition);
  };
  const std::string own = WritePartition(id.Name());
  for (const auto& rule : Table()) {
    const bool pub = Has(rule.publish, id.role), sub = Has(rule.subscribe, id.role);
    if (!pub && !sub) continue;
    x += "      <allow_rule>\n";
    x += DomainsXml("        ");
    if (pub) criterion("publish", TopicFor(rule.topic, id), own);
    if (sub) criterion("subscribe", TopicFor(rule.topic, id), kReadPartition);
    x += "      </allow_rule>\n";
  }
  x += "      <default>DENY</default>\n"
       "    </grant>\n"
       "  </permissions>\n"
       "</dds>\n";
  return x;
}

namespace {

// `writes`: the publish column (a station writes its own station's data only), else the subscribe one.
std::string Who(const std::vector<Role>& roles, const TopicRule& rule, bool writes) {
  const bool per_station = rule.topic.find(kStationMark) != std::string_view::npos;
  std::string out;
  for (Role r : Roles()) {
    if (!Has(roles, r)) continue;
    if (!out.empty()) out += ", ";
    if (!IsStationRole(r))
      out += RoleName(r);
    else if (per_station)
      out += fmt::format("{}-`<ID>` (own station)", RoleName(r));
    else if (writes)
      out += fmt::format("{}-`<ID>` (own station's data)", RoleName(r));
    else
      out += fmt::format("{}-`<ID>` (every station's)", RoleName(r));
  }
  return out.empty() ? "nobody" : out;
}

std::string_view Separable(Scope s) {
  switch (s) {
    case Scope::kCell:
      return "n/a (no station's own data)";
    case Scope::kOwnStation:
      return "yes (per-station topic)";
    case Scope::kSharedKeyed:
      return "yes (writer's partition; readers drop another station's key)";
    case Scope::kSharedService:
      return "yes (writer's partition; the service checks the sender)";
  }
  return "?";
}

}  // namespace

std::string RenderTable() {
  std::string out =
      "| topic | published by | subscribed by | separable per station | used today |\n"
      "|---|---|---|---|---|\n";
  for (const auto& r : Table())
    out += fmt::format("| `{}` | {} | {} | {} | {} |\n", r.topic, Who(r.publish, r, true),
                       Who(r.subscribe, r, false), Separable(r.scope), r.use);
  return out;
}

}  // namespace cell::security
