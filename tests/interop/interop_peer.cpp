// One side of the cross-vendor interop test. Run once with "fastdds" and once with
// "cyclonedds" on the same domain. Each side:
//  1. writes a string-keyed transient-local topic (3 keys x 2 revisions) before anyone reads it;
//  2. for every topic type, publishes a sample with every field non-default, strings at their
//     maximum length and sequences at their bound (seed 1 from Fast DDS, 2 from Cyclone), and
//     checks the peer's sample field by field against the same generator;
//  3. joins the peer's keyed topic late and checks it gets exactly the last sample of each key;
//  4. handshakes "done" so neither side exits while the other still needs its writers.
// Waits are on matched status and on data, never fixed sleeps.
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "cell/bus/bus.h"
#include "cell/config/config.h"
#include "cell/idl/fill.h"

using namespace cell::bus;

namespace {

constexpr Millis kTimeout(20000);

struct ExchangeBase {
  virtual ~ExchangeBase() = default;
  virtual bool Matched() const = 0;
  virtual void Send() = 0;
  virtual bool Received() = 0;  // true once the peer's sample arrived and was checked
  virtual std::string Name() const = 0;
  bool ok = false;
};

// DDS topic names allow letters, digits, '_' and '/'; Cyclone rejects "::".
std::string TopicName(std::string type) {
  for (size_t i; (i = type.find("::")) != std::string::npos;) type.replace(i, 2, "_");
  return type;
}

template <class T>
struct Exchange : ExchangeBase {
  Exchange(Participant& p, const std::string& out, const std::string& in, long my_seed, long peer_seed)
      : w(p, "interop/" + TopicName(cell::idl::TypeMeta<T>::kName) + "/" + out, QosKind::kState),
        r(p, "interop/" + TopicName(cell::idl::TypeMeta<T>::kName) + "/" + in, QosKind::kState),
        mine(my_seed),
        theirs(peer_seed) {}
  bool Matched() const override { return w.Matched() > 0 && r.Matched() > 0; }
  void Send() override {
    T v;
    cell::idl::Fill(v, mine);
    w.Write(v);
  }
  bool Received() override {
    if (done) return true;
    auto got = r.Take(Millis(0));
    if (!got) return false;
    T expect;
    cell::idl::Fill(expect, theirs);
    ok = *got == expect;
    done = true;
    return true;
  }
  std::string Name() const override { return cell::idl::TypeMeta<T>::kName; }
  Writer<T> w;
  Reader<T> r;
  long mine, theirs;
  bool done = false;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 || (std::string(argv[1]) != "fastdds" && std::string(argv[1]) != "cyclonedds")) {
    std::fprintf(stderr, "usage: interop_peer fastdds|cyclonedds\n");
    return 2;
  }
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  const std::string me = argv[1];
  const bool fast = me == "fastdds";
  // The stack as every service chooses it (and CELL_DDS_PROFILE for it: the loopback test's control).
  Participant p(Named("interop-" + me, me));
  const std::string out = fast ? "f2c" : "c2f", in = fast ? "c2f" : "f2c";
  const long my_seed = fast ? 1 : 2, peer_seed = fast ? 2 : 1;

  // 1. Keyed transient-local samples for the peer's late joiner.
  Writer<cell::StationStatus> late_w(p, "interop/late/" + out, QosKind::kState);
  for (int rev = 1; rev <= 2; ++rev)
    for (int k = 0; k < 3; ++k) {
      cell::StationStatus s;
      cell::idl::Fill(s, my_seed);
      s.station(cell::idl::FillString(16, k).substr(0, 15) + std::to_string(k));
      s.line(rev * 100 + k);
      late_w.Write(s);
    }

  // 2. Every topic type, both directions.
  std::vector<std::unique_ptr<ExchangeBase>> ex;
#define CELL_INTEROP_ADD(T) ex.push_back(std::make_unique<Exchange<T>>(p, out, in, my_seed, peer_seed));
  CELL_IDL_FOR_EACH_TOPIC_TYPE(CELL_INTEROP_ADD)
#undef CELL_INTEROP_ADD
  if (!WaitUntil(
          [&] {
            for (auto& e : ex)
              if (!e->Matched()) return false;
            return true;
          },
          kTimeout)) {
    for (auto& e : ex)
      if (!e->Matched()) std::printf("NOT MATCHED %s\n", e->Name().c_str());
    return 1;
  }
  std::printf("%s: matched %zu topic types\n", me.c_str(), ex.size());
  for (auto& e : ex) e->Send();
  bool all = WaitUntil(
      [&] {
        bool done = true;
        for (auto& e : ex) done = e->Received() && done;
        return done;
      },
      kTimeout);
  int failures = 0;
  for (auto& e : ex) {
    bool got = e->Received();
    std::printf("%s %s %s\n", !got ? "MISSING" : e->ok ? "OK" : "MISMATCH", me.c_str(), e->Name().c_str());
    if (!got || !e->ok) ++failures;
  }
  if (!all) ++failures;

  // 3. Late joiner on the peer's string-keyed transient-local topic.
  Reader<cell::StationStatus> late_r(p, "interop/late/" + in, QosKind::kState);
  std::map<std::string, int> last;
  int extra = 0;
  while (last.size() < 3) {
    auto s = late_r.Take(kTimeout);
    if (!s) break;
    if (last.count(s->station().to_string())) ++extra;
    last[s->station().to_string()] = s->line();
  }
  bool late_ok = last.size() == 3 && extra == 0;
  for (int k = 0; k < 3; ++k) {
    std::string key = cell::idl::FillString(16, k).substr(0, 15) + std::to_string(k);
    late_ok = late_ok && last.count(key) && last[key] == 200 + k;
  }
  std::printf("%s %s late-joiner keyed by string (%zu keys)\n", late_ok ? "OK" : "MISMATCH", me.c_str(),
              last.size());
  if (!late_ok) ++failures;

  // 4. Done handshake.
  Writer<cell::ServiceHealth> done_w(p, "interop/done/" + out, QosKind::kState);
  Reader<cell::ServiceHealth> done_r(p, "interop/done/" + in, QosKind::kState);
  cell::ServiceHealth h;
  h.service_id("interop-" + me);
  h.state(cell::SERVICE_READY);
  // Exit only when the peer acknowledged our "done" and we have its "done": neither side's
  // writers vanish while the other still needs them.
  if (!done_w.WaitForMatched(1, kTimeout)) ++failures;
  done_w.Write(h);
  if (!done_r.Take(kTimeout)) {
    std::printf("peer never finished\n");
    ++failures;
  }
  if (!done_w.WaitForAcked(kTimeout)) {
    std::printf("peer never acknowledged done\n");
    ++failures;
  }
  std::fflush(stdout);
  return failures == 0 ? 0 : 1;
}
