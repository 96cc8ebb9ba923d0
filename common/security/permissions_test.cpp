// The permissions table: it covers exactly the bus's topics, grants least privilege (each negative with its
// positive control), and is the table docs/security.md shows.
#include "cell/security/permissions.h"

#include <fnmatch.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <set>
#include <sstream>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/error/error.h"

namespace cell::security {
namespace {

namespace topics = bus::topics;

// What both stacks do with a permissions <topic>: fnmatch without FNM_PATHNAME ('*' spans '/').
bool Matches(const std::vector<std::string>& patterns, const std::string& topic) {
  return std::any_of(patterns.begin(), patterns.end(), [&](const std::string& p) {
    return fnmatch(p.c_str(), topic.c_str(), FNM_NOESCAPE) == 0;
  });
}
bool MayPublish(const std::string& identity, const std::string& topic) {
  return Matches(GrantsFor(*ParseIdentity(identity)).publish, topic);
}
bool MaySubscribe(const std::string& identity, const std::string& topic) {
  return Matches(GrantsFor(*ParseIdentity(identity)).subscribe, topic);
}

std::vector<std::string> AllIdentityNames() {
  std::vector<std::string> out;
  for (const auto& id : CellIdentities({"KT01", "KT02"})) out.push_back(id.Name());
  return out;
}

TEST(Table, CoversExactlyTheBusTopics) {
  const std::string st = "<ID>";
  std::set<std::string> bus_topics{
      topics::kHealth,           topics::kStationStatus,  topics::kToolTable,      topics::kVariables,
      topics::kStationIo,        topics::kStationEvent,   topics::kSchedulerState, topics::kJobState,
      topics::kRunStatus,        topics::kJobStatus,      topics::kProgramChange,  topics::kAlarm,
      topics::kInspectionStored, topics::kAxisState,      topics::kProgramList,    topics::Segments(st),
      topics::Probe(st),         topics::Part(st),        topics::Progress(st),    topics::ServoControl(st),
      topics::ServoTools(st),    topics::kStationProgram, topics::kDncStatus};
  for (const std::string& svc :
       {std::string(topics::kProgramStore), std::string(topics::kScheduler), std::string(topics::kInspection),
        std::string(topics::kStationRun), topics::StationCommand(st), topics::StationDnc(st)}) {
    bus_topics.insert(bus::RequestTopic(svc));
    bus_topics.insert(bus::ReplyTopic(svc));
  }
  std::set<std::string> table;
  for (const auto& r : Table()) {
    EXPECT_TRUE(table.insert(std::string(r.topic)).second) << "twice in the table: " << r.topic;
    EXPECT_FALSE(r.publish.empty()) << r.topic;
    EXPECT_FALSE(r.subscribe.empty()) << r.topic;
    EXPECT_EQ(r.scope == Scope::kOwnStation, r.topic.find("<ID>") != std::string_view::npos) << r.topic;
  }
  EXPECT_EQ(table, bus_topics);
}

TEST(Table, RendersOneMarkdownRowPerTopic) {
  const std::string md = RenderTable();
  std::istringstream in(md);
  size_t rows = 0;
  for (std::string line; std::getline(in, line); ++rows)
    EXPECT_EQ(std::count(line.begin(), line.end(), '|'), 6) << line;  // no '|' inside a cell
  EXPECT_EQ(rows, Table().size() + 2);
}

TEST(Grants, OnlyTheSchedulerDispatchesToStations) {
  // One dispatch service for every station (topics::kStationRun): the scheduler writes it, every station's
  // interpreter reads it and answers; nobody else writes a request or reads an answer.
  EXPECT_TRUE(MayPublish("scheduler", "cell/station/run/request"));
  EXPECT_TRUE(MaySubscribe("scheduler", "cell/station/run/reply"));
  EXPECT_TRUE(MaySubscribe("interpreter-KT01", "cell/station/run/request"));
  EXPECT_TRUE(MayPublish("interpreter-KT02", "cell/station/run/reply"));
  for (const auto& n : AllIdentityNames())
    if (n != "scheduler") {
      EXPECT_FALSE(MayPublish(n, "cell/station/run/request")) << n;
      EXPECT_FALSE(MaySubscribe(n, "cell/station/run/reply")) << n;
    }
  EXPECT_FALSE(MayPublish("axis-servo-KT01", "cell/station/run/reply"));
}

TEST(Grants, AStationWritesOnlyItsOwnSegmentsAndProbeResults) {
  EXPECT_TRUE(MayPublish("interpreter-KT01", "cell/station/KT01/segments"));
  EXPECT_FALSE(MayPublish("interpreter-KT01", "cell/station/KT02/segments"));
  EXPECT_FALSE(MayPublish("interpreter-KT02", "cell/station/KT01/segments"));
  EXPECT_FALSE(MayPublish("axis-servo-KT01", "cell/station/KT01/segments"));
  EXPECT_TRUE(MayPublish("axis-servo-KT01", "cell/station/KT01/probe"));
  EXPECT_FALSE(MayPublish("axis-servo-KT01", "cell/station/KT02/probe"));
  EXPECT_FALSE(MayPublish("interpreter-KT01", "cell/station/KT01/probe"));
  // Reading too: a station's stream is its own servo's.
  EXPECT_TRUE(MaySubscribe("axis-servo-KT01", "cell/station/KT01/segments"));
  EXPECT_FALSE(MaySubscribe("axis-servo-KT01", "cell/station/KT02/segments"));
  // A station identity never holds a pattern that spans stations.
  for (const auto& n : AllIdentityNames()) {
    if (!IsStationRole(ParseIdentity(n)->role)) continue;
    const Grants g = GrantsFor(*ParseIdentity(n));
    for (const auto* list : {&g.publish, &g.subscribe})
      for (const auto& t : *list) EXPECT_EQ(t.find('*'), std::string::npos) << n << ": " << t;
  }
}

TEST(Grants, OnlyAStationsOwnDncServesItsLineAndTheOperatorCommandsIt) {
  EXPECT_TRUE(MaySubscribe("dnc-KT01", "cell/station/KT01/dnc/request"));
  EXPECT_TRUE(MayPublish("dnc-KT01", "cell/station/KT01/dnc/reply"));
  EXPECT_FALSE(MaySubscribe("dnc-KT01", "cell/station/KT02/dnc/request"));
  EXPECT_FALSE(MayPublish("dnc-KT01", "cell/station/KT02/dnc/reply"));
  EXPECT_TRUE(MayPublish("operator", "cell/station/KT02/dnc/request"));
  EXPECT_FALSE(MayPublish("viewer", "cell/station/KT01/dnc/request"));
  EXPECT_TRUE(MayPublish("interpreter-KT01", "cell/station/KT01/dnc/request"));  // an Okuma READ/WRITE
  EXPECT_FALSE(MayPublish("interpreter-KT01", "cell/station/KT02/dnc/request"));
  // It reads and stores programs through the store, writes its line's state, and nothing of the machine.
  EXPECT_TRUE(MayPublish("dnc-KT01", "cell/program_store/request"));
  EXPECT_TRUE(MayPublish("dnc-KT01", "cell/dnc/status"));
  EXPECT_TRUE(MaySubscribe("viewer", "cell/dnc/status"));
  EXPECT_FALSE(MayPublish("dnc-KT01", "cell/station/KT01/segments"));
  EXPECT_FALSE(MayPublish("dnc-KT01", "cell/station/KT01/command/request"));
}

TEST(Grants, AStationAnswersOnlyItsOwnCommands) {
  EXPECT_TRUE(MaySubscribe("interpreter-KT01", "cell/station/KT01/command/request"));
  EXPECT_TRUE(MayPublish("interpreter-KT01", "cell/station/KT01/command/reply"));
  EXPECT_FALSE(MaySubscribe("interpreter-KT01", "cell/station/KT02/command/request"));
  EXPECT_FALSE(MayPublish("interpreter-KT01", "cell/station/KT02/command/reply"));
}

TEST(Grants, OnlyOperatorsCommandTheCell) {
  for (const std::string t : {"cell/program_store/request", "cell/scheduler/request",
                              "cell/station/KT01/command/request", "cell/station/KT02/command/request"})
    EXPECT_TRUE(MayPublish("operator", t)) << t;
  // Routes, pallet maps and jobs go through the scheduler's service: the operator's, and the viewer's for
  // the plan alone (the scheduler refuses it every other request: scheduler_service_test).
  for (const auto& n : AllIdentityNames())
    if (n != "operator" && n != "viewer") {
      EXPECT_FALSE(MayPublish(n, "cell/scheduler/request")) << n;
    }
  // Panel verbs: the operator's, and the scheduler's for VSET (the topic carries every op).
  for (const auto& n : AllIdentityNames())
    if (n != "operator" && n != "scheduler") {
      EXPECT_FALSE(MayPublish(n, "cell/station/KT01/command/request")) << n;
    }
  for (const std::string n : {"viewer", "axis-servo-KT01", "inspection-writer", "program-store"})
    EXPECT_FALSE(MayPublish(n, "cell/program_store/request")) << n;
}

TEST(Grants, TheViewerReadsStateAndEventsAndAsksOnlyTheScheduler) {
  const Grants g = GrantsFor(*ParseIdentity("viewer"));
  // The dashboard's Gantt chart asks the scheduler's plan (SCHED_PLAN): its one request topic.
  EXPECT_EQ(g.publish, std::vector<std::string>{"cell/scheduler/request"});
  EXPECT_TRUE(MaySubscribe("viewer", "cell/scheduler/reply"));
  for (const std::string t :
       {"cell/station/status", "cell/station/tools", "cell/scheduler/state", "cell/job/state",
        "cell/run/status", "cell/inspection/stored", "cell/motion/axes", "cell/health"})
    EXPECT_TRUE(MaySubscribe("viewer", t)) << t;
  // No service's answers, and not the machines' internal streams.
  for (const std::string t :
       {"cell/program_store/reply", "cell/inspection/reply", "cell/station/KT01/segments",
        "cell/station/KT01/progress", "cell/station/KT01/command/reply"})
    EXPECT_FALSE(MaySubscribe("viewer", t)) << t;
}

TEST(Grants, ServicesWriteWhatTheyOwnOnly) {
  EXPECT_TRUE(MayPublish("program-store", "cell/program/change"));
  EXPECT_FALSE(MayPublish("scheduler", "cell/program/change"));
  EXPECT_TRUE(MayPublish("inspection-writer", "cell/inspection/stored"));
  EXPECT_FALSE(MayPublish("interpreter-KT01", "cell/inspection/stored"));
  EXPECT_TRUE(MayPublish("scheduler", "cell/job/state"));
  EXPECT_FALSE(MayPublish("operator", "cell/job/state"));
  EXPECT_TRUE(MayPublish("interpreter-KT01", "cell/station/status"));
  EXPECT_FALSE(MayPublish("axis-servo-KT01", "cell/station/status"));
  EXPECT_FALSE(MayPublish("operator", "cell/station/status"));
}

TEST(Identity, NamesRoundTrip) {
  for (const auto& id : CellIdentities({"KT01", "OK-1_b"})) {
    auto back = ParseIdentity(id.Name());
    ASSERT_TRUE(back) << id.Name();
    EXPECT_EQ(*back, id);
  }
  EXPECT_EQ(CellIdentities({"KT01"}).size(), 8u);
  EXPECT_EQ(CellIdentities({"KT01", "KT01"}).size(), 8u);
  EXPECT_EQ(ParseIdentity("interpreter-KT01")->station, "KT01");
  for (const char* bad : {"interpreter", "interpreter-", "axis-servo-K/T", "root", "operator-KT01", "",
                          "interpreter-ABCDEFGHIJKLMNOPQ"})
    EXPECT_FALSE(ParseIdentity(bad)) << bad;
  EXPECT_THROW(CellIdentities({"KT 01"}), Error);
}

TEST(Documents, SubjectNameIsTheRfc2253FormOfTheCertificateSubject) {
  EXPECT_EQ(SubjectName("interpreter-KT01"), "CN=interpreter-KT01,O=cell");
  EXPECT_EQ(OpensslSubject("interpreter-KT01"), "/O=cell/CN=interpreter-KT01");
}

// "publish <partition>" or "subscribe <partition>": the criterion naming `topic` in a permissions document.
std::string CriterionOf(const std::string& x, const std::string& topic) {
  const auto at = x.find("<topic>" + topic + "</topic>");
  if (at == std::string::npos) return "none";
  const auto pub = x.rfind("<publish>", at), sub = x.rfind("<subscribe>", at);
  const bool is_pub = pub != std::string::npos && (sub == std::string::npos || pub > sub);
  const auto p = x.find("<partition>", at) + std::string("<partition>").size();
  return std::string(is_pub ? "publish " : "subscribe ") + x.substr(p, x.find("</partition>", p) - p);
}

TEST(Documents, PartitionsNameTheIdentity) {
  EXPECT_EQ(WritePartition("interpreter-KT01"), "id/interpreter-KT01");
  EXPECT_EQ(IdentityOfPartition("id/interpreter-KT01"), "interpreter-KT01");
  EXPECT_EQ(IdentityOfPartition("KT01"), "");
  EXPECT_EQ(IdentityOfPartition(""), "");
}

TEST(Documents, PermissionsGrantTheTableAndDenyTheRest) {
  const auto id = *ParseIdentity("interpreter-KT01");
  const std::string x = PermissionsXml(id, "2026-01-01T00:00:00", "2036-01-01T00:00:00");
  EXPECT_NE(x.find("<subject_name>CN=interpreter-KT01,O=cell</subject_name>"), std::string::npos);
  EXPECT_NE(x.find("<not_before>2026-01-01T00:00:00</not_before>"), std::string::npos);
  EXPECT_NE(x.find("<default>DENY</default>"), std::string::npos);
  EXPECT_NE(x.find("<max>230</max>"), std::string::npos);  // Cyclone 0.10 refuses more
  // Its own segments it publishes, in its own partition only; the probe results it reads, in any.
  EXPECT_EQ(CriterionOf(x, "cell/station/KT01/segments"), "publish id/interpreter-KT01");
  EXPECT_EQ(CriterionOf(x, "cell/station/KT01/probe"), "subscribe *");
  EXPECT_EQ(CriterionOf(x, "cell/station/status"), "publish id/interpreter-KT01");
  EXPECT_EQ(x.find("KT02"), std::string::npos);
  // One allow_rule per topic (Fast DDS checks a partition against every criterion of a rule).
  const Grants g = GrantsFor(id);
  size_t rules = 0;
  for (auto at = x.find("<allow_rule>"); at != std::string::npos; at = x.find("<allow_rule>", at + 1))
    ++rules;
  std::set<std::string> topics(g.publish.begin(), g.publish.end());
  topics.insert(g.subscribe.begin(), g.subscribe.end());
  EXPECT_EQ(rules, topics.size());

  const std::string v =
      PermissionsXml(*ParseIdentity("viewer"), "2026-01-01T00:00:00", "2036-01-01T00:00:00");
  // The viewer's one write: the plan request, in its own partition.
  EXPECT_EQ(CriterionOf(v, "cell/scheduler/request"), "publish id/viewer");
  EXPECT_EQ(v.find("<publish>"), v.rfind("<publish>"));
  EXPECT_NE(v.find("<subscribe>"), std::string::npos);
}

TEST(Documents, GovernanceProtectsEveryCellTopic) {
  const std::string g = GovernanceXml();
  for (const char* s :
       {"<allow_unauthenticated_participants>false</allow_unauthenticated_participants>",
        "<enable_join_access_control>true</enable_join_access_control>",
        "<discovery_protection_kind>ENCRYPT</discovery_protection_kind>",
        "<liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>",
        "<rtps_protection_kind>ENCRYPT</rtps_protection_kind>", "<topic_expression>cell/*</topic_expression>",
        "<enable_discovery_protection>true</enable_discovery_protection>",
        "<enable_liveliness_protection>true</enable_liveliness_protection>",
        "<enable_read_access_control>true</enable_read_access_control>",
        "<enable_write_access_control>true</enable_write_access_control>",
        "<metadata_protection_kind>ENCRYPT</metadata_protection_kind>",
        "<data_protection_kind>ENCRYPT</data_protection_kind>"})
    EXPECT_NE(g.find(s), std::string::npos) << s;
  for (const auto& r : Table())
    EXPECT_EQ(fnmatch("cell/*", std::string(r.topic).c_str(), FNM_NOESCAPE), 0) << r.topic;
}

// docs/security.md carries the rendered table between two markers: what the docs say is what is enforced.
TEST(Docs, SecurityMdShowsTheTableTheCodeEnforces) {
  std::ifstream in(CELL_SECURITY_DOC);
  ASSERT_TRUE(in) << CELL_SECURITY_DOC;
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string doc = ss.str();
  const std::string begin = "<!-- permissions table: begin (cell::security::RenderTable) -->\n";
  const std::string end = "<!-- permissions table: end -->";
  const auto b = doc.find(begin), e = doc.find(end);
  ASSERT_NE(b, std::string::npos) << "no begin marker in " << CELL_SECURITY_DOC;
  ASSERT_NE(e, std::string::npos) << "no end marker in " << CELL_SECURITY_DOC;
  ASSERT_LT(b, e);
  EXPECT_EQ(doc.substr(b + begin.size(), e - b - begin.size()), RenderTable())
      << "docs/security.md is out of date; paste the output of RenderTable() between the markers";
}

}  // namespace
}  // namespace cell::security
