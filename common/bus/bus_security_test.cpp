// DDS Security through the bus (issue 22; docs/security.md), on each vendor. Every refusal is checked against
// its positive control: the same probe, allowed or unsecured, does see, write or capture what the refused one
// does not. The PKIs are made once per run with `openssl` (cell::security::InitPki) in a temporary directory.
#include <arpa/inet.h>
#include <fcntl.h>
#include <linux/filter.h>
#include <linux/if_ether.h>
#include <linux/if_packet.h>
#include <net/if.h>
#include <netinet/in.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/idl/health.h"
#include "cell/idl/motion.h"
#include "cell/idl/program_store.h"
#include "cell/idl/station.h"
#include "cell/security/pki.h"

namespace bus = cell::bus;
namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

// Long enough for any allowed pair to match: the 15 s a secured Client allows a server (bus.h, issue 44: the
// handshakes of a sanitized build on a loaded host took over 5 s; at 5 s here a fresh run failed while
// another job loaded the host). Every use waits for success, so a longer bound only makes a failure slower.
constexpr bus::Millis kMatch{15000};
// How long a refused endpoint is given to match or receive after its allowed twin did.
constexpr auto kRefusedFor = 3s;

fs::path g_pki, g_foreign;

fs::path MakePki(const std::string& name) {
  char tmpl[] = "/tmp/cell-bus-sec-XXXXXX";
  fs::path dir = fs::path(mkdtemp(tmpl)) / name;
  cell::security::PkiOptions o;
  o.dir = dir;
  o.identities = cell::security::CellIdentities({"KT01", "KT02"});
  cell::security::InitPki(o);
  return dir;
}

// Every participant of these tests says which PKI (or none) it uses; CELL_SECURITY is read when it is made.
bus::Participant Make(const std::string& vendor, const std::string& identity, const fs::path& dir = g_pki) {
  if (identity.empty()) {
    setenv("CELL_SECURITY", "off", 1);
  } else {
    setenv("CELL_SECURITY", "on", 1);
  }
  bus::ParticipantOptions o;
  o.name = "bus-security-test/" + (identity.empty() ? std::string("unsecured") : identity);
  o.backend = vendor;
  o.identity = identity;
  o.security_dir = dir.string();
  return bus::Participant(o);
}

cell::MotionSegment Segment(uint64_t seq) {
  cell::MotionSegment s;
  s.station("KT01");
  s.seq(seq);
  return s;
}

// Both PKIs, made once for every suite of the run and removed when it ends (a peer process makes none).
void EnsurePki() {
  if (g_pki.empty()) {
    g_pki = MakePki("cell");
    g_foreign = MakePki("foreign");
  }
}
struct RemovePki : ::testing::Environment {
  void TearDown() override {
    std::error_code ec;
    if (!g_pki.empty()) fs::remove_all(g_pki.parent_path(), ec);
    if (!g_foreign.empty()) fs::remove_all(g_foreign.parent_path(), ec);
  }
};
[[maybe_unused]] const auto* const kRemovePki = ::testing::AddGlobalTestEnvironment(new RemovePki);

class BusSecurity : public ::testing::TestWithParam<std::string> {
 public:
  static void SetUpTestSuite() { EnsurePki(); }
  void TearDown() override { unsetenv("CELL_SECURITY"); }
  const std::string& vendor() const { return GetParam(); }
};

// A writer that keeps writing (volatile topics: a reader sees what is written after it matched).
struct Pump {
  Pump(bus::Writer<cell::MotionSegment>& w)
      : t([&w, this] {
          for (uint64_t i = 1; !stop; ++i) {
            w.Write(Segment(i));
            std::this_thread::sleep_for(20ms);
          }
        }) {}
  ~Pump() {
    stop = true;
    t.join();
  }
  std::atomic<bool> stop{false};
  std::thread t;
};

TEST_P(BusSecurity, OwnStationsSegmentsFlowAndNobodyElseSeesThem) {
  auto interp = Make(vendor(), "interpreter-KT01");
  auto servo = Make(vendor(), "axis-servo-KT01");
  auto plain = Make(vendor(), "");
  auto foreign = Make(vendor(), "axis-servo-KT01", g_foreign);
  const std::string topic = bus::topics::Segments("KT01");
  bus::Writer<cell::MotionSegment> w(interp, topic, bus::QosKind::kStream);
  bus::Reader<cell::MotionSegment> ok(servo, topic, bus::QosKind::kStream);
  bus::Reader<cell::MotionSegment> no_identity(plain, topic, bus::QosKind::kStream);
  bus::Reader<cell::MotionSegment> other_ca(foreign, topic, bus::QosKind::kStream);
  Pump pump(w);
  // Positive control: the station's own servo, same PKI.
  ASSERT_TRUE(ok.WaitForMatched(1, kMatch));
  ASSERT_TRUE(ok.Take(kMatch).has_value());
  std::this_thread::sleep_for(kRefusedFor);
  EXPECT_EQ(no_identity.Matched(), 0);
  EXPECT_FALSE(no_identity.Take(0ms).has_value()) << "an unsecured participant received a segment";
  EXPECT_EQ(other_ca.Matched(), 0);
  EXPECT_FALSE(other_ca.Take(0ms).has_value()) << "an identity of another CA received a segment";
  EXPECT_EQ(w.Matched(), 1) << "only the station's own servo matches";
}

TEST_P(BusSecurity, UnsecuredParticipantsStillTalkToEachOther) {
  // The control for the test above: the unsecured probe works where nobody secures the topic.
  auto a = Make(vendor(), "");
  auto b = Make(vendor(), "");
  bus::Writer<cell::MotionSegment> w(a, bus::topics::Segments("KT01"), bus::QosKind::kStream);
  bus::Reader<cell::MotionSegment> r(b, bus::topics::Segments("KT01"), bus::QosKind::kStream);
  Pump pump(w);
  ASSERT_TRUE(r.WaitForMatched(1, kMatch));
  EXPECT_TRUE(r.Take(kMatch).has_value());
}

TEST_P(BusSecurity, AStationCannotWriteAnotherStationsTopics) {
  auto kt01 = Make(vendor(), "interpreter-KT01");
  auto kt02 = Make(vendor(), "interpreter-KT02");
  EXPECT_NO_THROW(
      bus::Writer<cell::MotionSegment>(kt01, bus::topics::Segments("KT01"), bus::QosKind::kStream));
  try {
    bus::Writer<cell::MotionSegment> w(kt02, bus::topics::Segments("KT01"), bus::QosKind::kStream);
    ADD_FAILURE() << "interpreter-KT02 could write KT01's segments";
  } catch (const cell::Error& e) {
    EXPECT_EQ(e.code(), cell::Errc::kPermissionDenied) << e.what();
    EXPECT_NE(std::string(e.what()).find("interpreter-KT02"), std::string::npos) << e.what();
  }
}

TEST_P(BusSecurity, ViewerReadsStateButWritesNothing) {
  auto viewer = Make(vendor(), "viewer");
  auto sched = Make(vendor(), "scheduler");
  // Its read works: the scheduler's health reaches it.
  bus::Writer<cell::ServiceHealth> hw(sched, bus::topics::kHealth, bus::QosKind::kState);
  bus::Reader<cell::ServiceHealth> hr(viewer, bus::topics::kHealth, bus::QosKind::kState);
  cell::ServiceHealth h;
  h.service_id("cell-scheduler");
  hw.Write(h);
  ASSERT_TRUE(hr.WaitForMatched(1, kMatch));
  EXPECT_TRUE(hr.Take(kMatch).has_value());
  // Its writes are refused where the scheduler's are not.
  EXPECT_THROW(bus::Writer<cell::ServiceHealth>(viewer, bus::topics::kHealth, bus::QosKind::kState),
               cell::Error);
  EXPECT_THROW((bus::Client<cell::ProgramRequest, cell::ProgramReply>(viewer, bus::topics::kProgramStore)),
               cell::Error);
  auto op = Make(vendor(), "operator");
  EXPECT_NO_THROW((bus::Client<cell::ProgramRequest, cell::ProgramReply>(op, bus::topics::kProgramStore)));
}

TEST_P(BusSecurity, ABrokenSignatureOrAMissingFileStopsTheProcessWithTheReason) {
  // A copy of the PKI whose scheduler permissions were changed after signing.
  const fs::path copy = g_pki.parent_path() / ("tampered-" + vendor());
  fs::copy(g_pki, copy, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  const fs::path p7s = copy / "identities" / "scheduler" / "permissions.p7s";
  std::string text;
  {
    std::ifstream in(p7s);
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto at = text.find("<subscribe>");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 11, "<publish>  ");  // same length: only the signature can tell
  std::ofstream(p7s, std::ios::trunc) << text;
  EXPECT_NO_THROW(Make(vendor(), "operator", copy));  // the rest of the copy is fine
  try {
    Make(vendor(), "scheduler", copy);
    ADD_FAILURE() << "a participant started with a tampered permissions document";
  } catch (const cell::Error& e) {
    EXPECT_NE(std::string(e.what()).find("permissions.p7s: its signature does not verify"), std::string::npos)
        << e.what();
  }
  fs::remove(copy / "identities" / "viewer" / "key.pem");
  try {
    Make(vendor(), "viewer", copy);
    ADD_FAILURE() << "a participant started without its key";
  } catch (const cell::Error& e) {
    EXPECT_EQ(e.code(), cell::Errc::kNotFound) << e.what();
    EXPECT_NE(std::string(e.what()).find("key.pem"), std::string::npos) << e.what();
  }
}

// Captures every frame on the loopback interface (needs CAP_NET_RAW) and looks for a byte string.
class LoopbackCapture {
 public:
  explicit LoopbackCapture(std::string needle) : needle_(std::move(needle)) {
    fd_ = socket(AF_PACKET, SOCK_RAW, htons(ETH_P_ALL));
    if (fd_ < 0) return;
    sockaddr_ll sll{};
    sll.sll_family = AF_PACKET;
    sll.sll_protocol = htons(ETH_P_ALL);
    sll.sll_ifindex = static_cast<int>(if_nametoindex("lo"));
    if (bind(fd_, reinterpret_cast<sockaddr*>(&sll), sizeof sll) != 0) {
      close(fd_);
      fd_ = -1;
      return;
    }
    timeval tv{0, 100000};
    setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    // Each participant's first announcements go to every port of the peer range at once (ten bursts of
    // config::DdsParticipants datagrams): with the default 208 kB buffer a slow (sanitized, loaded) reader
    // lost packets, among them the request this test looks for (issue 44). So the kernel keeps only UDP to
    // an odd port (user data goes to 7411 + 250 d + 2 n, discovery to the even ports below them; the
    // marker to port 9), each packet once (not its outgoing copy too), in up to 32 MB, and Dropped() counts
    // what it still loses (such a run is repeated).
    static sock_filter code[] = {
        BPF_STMT(BPF_LD | BPF_H | BPF_ABS, 12),  // ethertype (lo frames carry a zero Ethernet header)
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, ETH_P_IP, 0, 6),
        BPF_STMT(BPF_LD | BPF_B | BPF_ABS, 23),  // IP protocol
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, IPPROTO_UDP, 0, 4),
        BPF_STMT(BPF_LDX | BPF_B | BPF_MSH, 14),  // IP header length
        BPF_STMT(BPF_LD | BPF_H | BPF_IND, 16),   // UDP destination port
        BPF_JUMP(BPF_JMP | BPF_JSET | BPF_K, 1, 0, 1),
        BPF_STMT(BPF_RET | BPF_K, 0x40000),
        BPF_STMT(BPF_RET | BPF_K, 0),
    };
    const sock_fprog prog{static_cast<unsigned short>(sizeof code / sizeof code[0]), code};
    setsockopt(fd_, SOL_SOCKET, SO_ATTACH_FILTER, &prog, sizeof prog);
    const int one = 1, big = 32 << 20;
    setsockopt(fd_, SOL_PACKET, PACKET_IGNORE_OUTGOING, &one, sizeof one);
    if (setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &big, sizeof big) != 0)
      setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &big, sizeof big);
    tpacket_stats st{};
    socklen_t len = sizeof st;
    getsockopt(fd_, SOL_PACKET, PACKET_STATISTICS, &st, &len);  // resets the counters
    t_ = std::thread([this] {
      std::vector<char> buf(70000);
      while (!stop_) {
        const ssize_t n = recv(fd_, buf.data(), buf.size(), 0);
        if (n <= 0) continue;
        const std::string_view packet(buf.data(), static_cast<size_t>(n));
        if (packet.find(needle_) != std::string_view::npos) seen_ = true;
        if (packet.find(marker_) != std::string_view::npos) marked_ = true;
      }
    });
  }
  // Sends a marker datagram on loopback and waits until the capture has read it: one socket reads the
  // interface's packets in order, so by then it has read everything sent before. A fixed sleep here was a
  // flake under load (issue 44: the unsecured control saw no program text).
  bool Drain(std::chrono::milliseconds timeout) {
    const int s = socket(AF_INET, SOCK_DGRAM, 0);
    if (s < 0) return false;
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(9);  // discard: nobody needs to listen, the capture sees it on lo
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!marked_ && std::chrono::steady_clock::now() < deadline) {
      sendto(s, marker_.data(), marker_.size(), 0, reinterpret_cast<sockaddr*>(&a), sizeof a);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    close(s);
    return marked_;
  }
  ~LoopbackCapture() {
    stop_ = true;
    if (t_.joinable()) t_.join();
    if (fd_ >= 0) close(fd_);
  }
  bool ok() const { return fd_ >= 0; }
  bool seen() const { return seen_; }
  // Packets the kernel dropped since the last call: a capture that lost any cannot say "not on the wire".
  unsigned Dropped() const {
    tpacket_stats st{};
    socklen_t len = sizeof st;
    return getsockopt(fd_, SOL_PACKET, PACKET_STATISTICS, &st, &len) == 0 ? st.tp_drops : 0;
  }

 private:
  std::string needle_;
  std::string marker_ = "CAPTURE-MARKER-" + std::to_string(getpid());
  int fd_ = -1;
  std::atomic<bool> stop_{false}, seen_{false}, marked_{false};
  std::thread t_;
};

// Puts a program through the program store's request topic and says whether its text was seen on the wire;
// nullopt when the capture lost packets (where the buffer cannot be raised, e.g. without CAP_NET_ADMIN), so
// that neither answer can be trusted.
std::optional<bool> ProgramTextOnTheWireOnce(const std::string& vendor, const std::string& client,
                                             const std::string& server, const std::string& text) {
  LoopbackCapture cap(text);
  if (!cap.ok()) return false;
  auto c = Make(vendor, client);
  auto s = Make(vendor, server);
  bus::Server<cell::ProgramRequest, cell::ProgramReply> srv(
      s, bus::topics::kProgramStore, [](const cell::ProgramRequest&) { return cell::ProgramReply(); });
  bus::Client<cell::ProgramRequest, cell::ProgramReply> cl(c, bus::topics::kProgramStore);
  cell::ProgramRequest req;
  req.data().assign(text.begin(), text.end());
  cl.Call(req, kMatch);
  EXPECT_TRUE(cap.Drain(std::chrono::seconds(10))) << "the capture never read its own marker";
  if (const unsigned lost = cap.Dropped()) {
    std::printf("the capture lost %u packets: run again\n", lost);
    return std::nullopt;
  }
  return cap.seen();
}

bool ProgramTextOnTheWire(const std::string& vendor, const std::string& client, const std::string& server,
                          const std::string& text) {
  for (int attempt = 0; attempt < 5; ++attempt)
    if (const auto seen = ProgramTextOnTheWireOnce(vendor, client, server, text)) return *seen;
  ADD_FAILURE() << "the capture lost packets in 5 runs out of 5: it cannot tell what crossed the wire";
  return false;
}

// A participant of `identity`'s files that writes in `partition`: what a station would do to pass for
// another one (docs/security.md, "Partitions").
std::unique_ptr<bus::Backend> Impersonating(const std::string& identity, const std::string& partition) {
  const auto f = cell::security::FindIdentityFiles(g_pki, identity);
  bus::BackendOptions o;
  o.domain = std::atoi(std::getenv("CELL_DOMAIN"));
  o.participant_name = "bus-security-test/impersonator";
  o.security = {identity,       f.ca.string(),          f.governance.string(), f.certificate.string(),
                f.key.string(), f.permissions.string(), f.crl.string()};
  o.partition = partition;
  return bus::MakeFastDdsBackend(o);
}

TEST_P(BusSecurity, AStationWritesOnlyInItsOwnPartition) {
  auto tk = cell::bus::TypeSupportFor<cell::StationStatus>();
  // Control: in its own partition interpreter-KT02 may publish the shared status topic.
  EXPECT_NO_THROW(Impersonating("interpreter-KT02", "id/interpreter-KT02")
                      ->CreateWriter(bus::topics::kStationStatus, tk, bus::QosKind::kState));
  try {
    Impersonating("interpreter-KT02", "id/interpreter-KT01")
        ->CreateWriter(bus::topics::kStationStatus, tk, bus::QosKind::kState);
    ADD_FAILURE() << "interpreter-KT02 could publish in interpreter-KT01's partition";
  } catch (const cell::Error& e) {
    EXPECT_EQ(e.code(), cell::Errc::kPermissionDenied) << e.what();
  }
}

TEST_P(BusSecurity, AStationsSampleAboutAnotherStationIsDroppedAndEverySampleNamesItsWriter) {
  auto kt01 = Make(vendor(), "interpreter-KT01");
  auto kt02 = Make(vendor(), "interpreter-KT02");
  auto sched = Make(vendor(), "scheduler");
  std::mutex mu;
  std::vector<std::pair<std::string, std::string>> got;  // (station, authenticated writer)
  bus::Reader<cell::StationStatus> r(sched, bus::topics::kStationStatus, bus::QosKind::kState,
                                     [&](const cell::StationStatus& v, const bus::SampleInfo& info) {
                                       std::lock_guard lk(mu);
                                       got.emplace_back(v.station().to_string(), info.writer);
                                     });
  bus::Writer<cell::StationStatus> w1(kt01, bus::topics::kStationStatus, bus::QosKind::kState);
  bus::Writer<cell::StationStatus> w2(kt02, bus::topics::kStationStatus, bus::QosKind::kState);
  ASSERT_TRUE(w1.WaitForMatched(1, kMatch));
  ASSERT_TRUE(w2.WaitForMatched(1, kMatch));
  cell::StationStatus st;
  st.station("KT01");
  st.line(66);
  w2.Write(st);  // KT02 writes KT01's status: dropped
  w1.Write(st);  // the control: KT01 writes its own
  st.station("KT02");
  w2.Write(st);  // and KT02 its own, after the forged one
  // KT02's own status follows its forged one on the same writer: once it is here, the forged one was
  // delivered or dropped before it.
  auto has_kt02 = [&] {
    std::lock_guard lk(mu);
    return std::find(got.begin(), got.end(),
                     std::make_pair(std::string("KT02"), std::string("interpreter-KT02"))) != got.end();
  };
  ASSERT_TRUE(bus::WaitUntil([&] { return has_kt02(); }, kMatch));
  ASSERT_TRUE(bus::WaitUntil(
      [&] {
        std::lock_guard lk(mu);
        return std::find(got.begin(), got.end(),
                         std::make_pair(std::string("KT01"), std::string("interpreter-KT01"))) != got.end();
      },
      kMatch));
  std::lock_guard lk(mu);
  std::sort(got.begin(), got.end());
  const std::vector<std::pair<std::string, std::string>> want{{"KT01", "interpreter-KT01"},
                                                              {"KT02", "interpreter-KT02"}};
  EXPECT_EQ(got, want);
}

TEST_P(BusSecurity, AServerKnowsTheAuthenticatedIdentityOfEachRequest) {
  auto station = Make(vendor(), "interpreter-KT01");
  auto op = Make(vendor(), "operator");
  auto sched = Make(vendor(), "scheduler");
  std::mutex mu;
  std::vector<std::string> from;
  bus::Server<cell::StationRequest, cell::StationReply> srv(
      station, bus::topics::StationCommand("KT01"),
      [&](const cell::StationRequest&) {
        std::lock_guard lk(mu);
        from.push_back(bus::RequesterIdentity());
        return cell::StationReply();
      },
      [](const cell::StationRequest&) { return std::string("reset"); });
  bus::Client<cell::StationRequest, cell::StationReply> c_op(op, bus::topics::StationCommand("KT01"));
  bus::Client<cell::StationRequest, cell::StationReply> c_sched(sched, bus::topics::StationCommand("KT01"));
  cell::StationRequest req;
  req.station("KT01");
  req.op(cell::STATION_RESET);
  c_op.Call(req, kMatch);
  c_sched.Call(req, kMatch);
  std::lock_guard lk(mu);
  EXPECT_EQ(from, (std::vector<std::string>{"operator", "scheduler"}));
}

TEST_P(BusSecurity, NoProgramTextOnTheWire) {
  {
    LoopbackCapture probe("x");
    if (!probe.ok()) GTEST_SKIP() << "no packet capture here (needs CAP_NET_RAW)";
  }
  // Control: unsecured, the program's text crosses loopback in the clear (and the capture sees it).
  EXPECT_TRUE(ProgramTextOnTheWire(vendor(), "", "", "N10 G01 X12.345 (CLEARTEXT-CONTROL)"));
  EXPECT_FALSE(
      ProgramTextOnTheWire(vendor(), "operator", "program-store", "N10 G01 X12.345 (SECRET-PROGRAM)"));
}

// Fast DDS keeps a security configuration per participant, so these tests put several identities in one
// process. Cyclone 0.10 holds one per domain per process (a second participant with other identity files, or
// none, is refused): its tests below run each identity in a process of its own.
INSTANTIATE_TEST_SUITE_P(Vendors, BusSecurity, ::testing::Values("fastdds"),
                         [](const auto& info) { return info.param; });

// One identity in a process of its own (it ends with _exit: a DDS stack torn down by exit() under its own
// running threads may crash, and the parent reads the exit status) (this binary, running the disabled Peer
// test): CELL_SEC_PEER is "MODE IDENTITY DIR SECONDS", MODE write (pumps KT01's segments), read (prints how
// many it took) or try-write (exit 0 if the writer was made, 3 if refused); IDENTITY "-" is unsecured.
TEST(BusSecurityPeer, DISABLED_Peer) {
  std::istringstream in(std::getenv("CELL_SEC_PEER"));
  std::string mode, identity, dir;
  int seconds = 0;
  in >> mode >> identity >> dir >> seconds;
  auto p = Make("cyclonedds", identity == "-" ? "" : identity, dir);
  const std::string topic = bus::topics::Segments("KT01");
  if (mode == "try-write") {
    try {
      bus::Writer<cell::MotionSegment> w(p, topic, bus::QosKind::kStream);
    } catch (const cell::Error& e) {
      std::printf("refused: %s\n", e.what());
      std::fflush(stdout);
      _exit(e.code() == cell::Errc::kPermissionDenied ? 3 : 4);
    }
    _exit(0);
  }
  if (mode == "write") {
    bus::Writer<cell::MotionSegment> w(p, topic, bus::QosKind::kStream);
    Pump pump(w);
    std::this_thread::sleep_for(std::chrono::seconds(seconds));
    _exit(0);
  }
  bus::Reader<cell::MotionSegment> r(p, topic, bus::QosKind::kStream);
  int n = 0;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  while (std::chrono::steady_clock::now() < until)
    if (r.Take(100ms)) ++n;
  std::printf("received %d\n", n);
  std::fflush(stdout);
  _exit(0);  // no destructors while the DDS stack's threads run: the parent reads the exit status
}

// Starts a peer; Wait() returns its exit status and what it printed.
class Peer {
 public:
  Peer(const std::string& spec) {
    out_ = (g_pki.parent_path() / ("peer-" + std::to_string(++count_) + ".out")).string();
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    std::vector<std::string> args = {"/proc/self/exe", "--gtest_filter=BusSecurityPeer.DISABLED_Peer",
                                     "--gtest_also_run_disabled_tests"};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::vector<std::string> env;
    for (char** e = environ; *e; ++e)
      if (std::strncmp(*e, "CELL_SEC_PEER=", 14) != 0) env.emplace_back(*e);
    env.push_back("CELL_SEC_PEER=" + spec);
    std::vector<char*> envp;
    for (auto& e : env) envp.push_back(e.data());
    envp.push_back(nullptr);
    if (posix_spawn(&pid_, argv[0], &fa, nullptr, argv.data(), envp.data()) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&fa);
  }
  ~Peer() {
    if (pid_ > 0 && !done_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  int Wait() {
    int st = 0;
    waitpid(pid_, &st, 0);
    done_ = true;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  }
  std::string Output() const {
    std::ifstream in(out_);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  int Received() const {
    const std::string o = Output();
    const auto at = o.find("received ");
    return at == std::string::npos ? -1 : std::stoi(o.substr(at + 9));
  }

 private:
  static inline int count_ = 0;
  pid_t pid_ = -1;
  bool done_ = false;
  std::string out_;
};

class BusSecurityCyclone : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { EnsurePki(); }
};

TEST_F(BusSecurityCyclone, OwnStationsSegmentsFlowAndNobodyElseSeesThem) {
  const std::string cell = g_pki.string(), foreign = g_foreign.string();
  Peer writer("write interpreter-KT01 " + cell + " 9");
  Peer servo("read axis-servo-KT01 " + cell + " 8");
  Peer plain("read - " + cell + " 8");
  Peer other_ca("read axis-servo-KT01 " + foreign + " 8");
  EXPECT_EQ(servo.Wait(), 0) << servo.Output();
  EXPECT_EQ(plain.Wait(), 0) << plain.Output();
  EXPECT_EQ(other_ca.Wait(), 0) << other_ca.Output();
  EXPECT_EQ(writer.Wait(), 0) << writer.Output();
  EXPECT_GT(servo.Received(), 0) << "control: the station's own servo receives";
  EXPECT_EQ(plain.Received(), 0) << "an unsecured participant received segments";
  EXPECT_EQ(other_ca.Received(), 0) << "an identity of another CA received segments";
}

TEST_F(BusSecurityCyclone, AStationCannotWriteAnotherStationsTopics) {
  Peer own("try-write interpreter-KT01 " + g_pki.string() + " 0");
  Peer other("try-write interpreter-KT02 " + g_pki.string() + " 0");
  EXPECT_EQ(own.Wait(), 0) << own.Output();
  EXPECT_EQ(other.Wait(), 3) << other.Output();
}

}  // namespace

namespace {

// DESIGN: a secured Fast DDS 2.9.1 and a secured Cyclone 0.10 do not complete the handshake (Fast DDS sends a
// raw DH public key where Cyclone expects ASN.1). Checked here: a Cyclone writer's segments reach a Cyclone
// servo (control) and never a Fast DDS servo of the same PKI.
TEST_F(BusSecurityCyclone, ASecuredFastDdsParticipantAndASecuredCycloneOneNeverMatch) {
  const std::string cell = g_pki.string();
  Peer writer("write interpreter-KT01 " + cell + " 9");
  Peer servo("read axis-servo-KT01 " + cell + " 8");
  auto fast = Make("fastdds", "axis-servo-KT01");
  bus::Reader<cell::MotionSegment> r(fast, bus::topics::Segments("KT01"), bus::QosKind::kStream);
  int n = 0;
  const auto until = std::chrono::steady_clock::now() + 8s;
  while (std::chrono::steady_clock::now() < until)
    if (r.Take(100ms)) ++n;
  EXPECT_EQ(servo.Wait(), 0) << servo.Output();
  EXPECT_EQ(writer.Wait(), 0) << writer.Output();
  EXPECT_GT(servo.Received(), 0) << "control: a Cyclone servo receives";
  EXPECT_EQ(n, 0) << "a secured Fast DDS reader received a secured Cyclone writer's segments";
  EXPECT_EQ(r.Matched(), 0);
}

}  // namespace
