// bus_pingpong_bench: what the bus adds to raw DDS (deploy/bench.d/45-bus-overhead.sh). Not a test.
//
//   bus_pingpong_bench ping|pong IMPL SIZE COUNT
//
// IMPL is raw-fastdds or raw-cyclonedds (the vendor's own API, pingpong.h), bus-fastdds or bus-cyclonedds
// (a bus Writer and Reader per direction), rpc-fastdds or rpc-cyclonedds (a bus Client calling a bus Server).
// The pong process echoes every sample (or answers every request) with the same payload; the ping process
// waits until both directions match, warms up, then times COUNT round trips of SIZE payload bytes and prints
//   RESULT IMPL SIZE MEDIAN_US P99_US
// The domain is CELL_DOMAIN. Each process has one participant and one vendor, as every cell process.
// IMPL srpc-fastdds or srpc-cyclonedds: the request/reply secured (DDS Security, docs/security.md) on the
// program store's own service topics, ping as `operator`, pong as `program-store`, with the PKI in
// CELL_BENCH_PKI (`cellctl pki init --dir`); rpc-* uses the same topic names unsecured when CELL_BENCH_PKI is
// set, so the two differ only in security.
// IMPL sbus-fastdds or sbus-cyclonedds: the pub/sub secured, on a station's segment and probe topics (the
// only pair one identity writes and the other reads back: ping as `interpreter-KT01` writes
// cell/station/KT01/segments and reads cell/station/KT01/probe, pong as `axis-servo-KT01` the other way),
// with the PKI in CELL_BENCH_PKI (made with `--station KT01`); bus-* uses the same topic names unsecured when
// CELL_BENCH_PKI is set.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "cell/bus/bus.h"
#include "cell/config/config.h"
#include "cell/idl/program_store.h"
#include "pingpong.h"

namespace bus = cell::bus;
using namespace cell::bus::bench;
using Clock = std::chrono::steady_clock;

namespace {

constexpr uint32_t kStop = 0xffffffffu;
constexpr int kWarmUp = 50;

bus::ParticipantOptions Options(const std::string& name, int domain, const std::string& vendor) {
  auto o = bus::Named(name, vendor);
  o.domain = domain;
  return o;
}

// The pub/sub topics: the bench's own, or (CELL_BENCH_PKI set) a station's segments and probe topics, which
// the governance covers and the permissions grant one way each.
std::string PingTopic() {
  return std::getenv("CELL_BENCH_PKI") ? "cell/station/KT01/segments" : kPingTopic;
}
std::string PongTopic() {
  return std::getenv("CELL_BENCH_PKI") ? "cell/station/KT01/probe" : kPongTopic;
}
bus::ParticipantOptions PubSubOptions(bool pinger, int domain, const std::string& vendor, bool secure) {
  auto o = Options(pinger ? "pingpong-ping" : "pingpong-pong", domain, vendor);
  setenv("CELL_SECURITY", secure ? "on" : "off", 1);
  if (secure) {
    o.identity = pinger ? "interpreter-KT01" : "axis-servo-KT01";
    o.security_dir = std::getenv("CELL_BENCH_PKI");
  }
  return o;
}

// A bus Writer and Reader per direction: the bus's pub/sub path against the vendor's.
class BusPingPong : public PingPong {
 public:
  BusPingPong(bool pinger, int domain, const std::string& vendor, bool secure, OnReceive on_receive)
      : p_(PubSubOptions(pinger, domain, vendor, secure)),
        w_(p_, pinger ? PingTopic() : PongTopic(), bus::QosKind::kCommand),
        r_(p_, pinger ? PongTopic() : PingTopic(), bus::QosKind::kCommand,
           [cb = std::move(on_receive)](const cell::ProgramRequest& m, const bus::SampleInfo&) {
             cb(m.chunk_index(), m.data().data(), m.data().size());
           }) {}
  bool Matched() override { return w_.Matched() > 0 && r_.Matched() > 0; }
  void Send(uint32_t seq, const uint8_t* data, size_t size) override {
    std::lock_guard lk(mu_);
    out_.chunk_index(seq);
    out_.data().assign(data, data + size);
    w_.Write(out_);
  }

 private:
  bus::Participant p_;
  bus::Writer<cell::ProgramRequest> w_;
  bus::Reader<cell::ProgramRequest> r_;
  std::mutex mu_;
  cell::ProgramRequest out_;
};

void Report(const std::string& impl, size_t size, std::vector<double> us) {
  std::sort(us.begin(), us.end());
  const double median = us[us.size() / 2];
  const double p99 = us[std::min(us.size() - 1, (us.size() * 99 + 99) / 100 - 1)];
  std::printf("RESULT %s %zu %.1f %.1f\n", impl.c_str(), size, median, p99);
}

// The service name, and (secured) the identity and PKI of one side.
std::string RpcService() {
  return std::getenv("CELL_BENCH_PKI") ? "cell/program_store" : "bench/rpc";
}
bus::ParticipantOptions RpcOptions(const std::string& name, int domain, const std::string& vendor,
                                   bool secure, const std::string& identity) {
  auto o = Options(name, domain, vendor);
  setenv("CELL_SECURITY", secure ? "on" : "off", 1);
  if (secure) {
    o.identity = identity;
    o.security_dir = std::getenv("CELL_BENCH_PKI");
  }
  return o;
}

int PingRpc(const std::string& vendor, bool secure, int domain, size_t size, int count) {
  bus::Participant p(RpcOptions("pingpong-ping", domain, vendor, secure, "operator"));
  bus::Client<cell::ProgramRequest, cell::ProgramReply> client(p, RpcService());
  if (!client.WaitForServer(bus::Millis(10000))) {
    std::fprintf(stderr, "pingpong: no rpc server\n");
    return 1;
  }
  cell::ProgramRequest req;
  req.data().assign(size, 0x5a);
  std::vector<double> us;
  for (int i = 0; i < kWarmUp + count; ++i) {
    req.chunk_index(static_cast<uint32_t>(i));
    const auto t0 = Clock::now();
    auto rep = client.Call(req, bus::Millis(10000));
    const auto t1 = Clock::now();
    if (rep.data().size() != size) {
      std::fprintf(stderr, "pingpong: a reply of %zu bytes, not %zu\n", rep.data().size(), size);
      return 1;
    }
    if (i >= kWarmUp) us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  Report((secure ? "srpc-" : "rpc-") + vendor, size, us);
  req.chunk_index(kStop);
  req.data().clear();
  client.Call(req, bus::Millis(5000));
  return 0;
}

int PongRpc(const std::string& vendor, bool secure, int domain) {
  bus::Participant p(RpcOptions("pingpong-pong", domain, vendor, secure, "program-store"));
  std::atomic<bool> done{false};
  bus::Server<cell::ProgramRequest, cell::ProgramReply> server(p, RpcService(),
                                                               [&](const cell::ProgramRequest& r) {
                                                                 if (r.chunk_index() == kStop) done = true;
                                                                 cell::ProgramReply rep;
                                                                 rep.chunk_index(r.chunk_index());
                                                                 rep.data(r.data());
                                                                 return rep;
                                                               });
  const auto deadline = Clock::now() + std::chrono::minutes(5);
  while (!done && Clock::now() < deadline) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the stop's reply leaves before we do
  return done ? 0 : 1;
}

std::unique_ptr<PingPong> Make(const std::string& impl, bool pinger, int domain, PingPong::OnReceive cb) {
  if (impl == "raw-fastdds") return MakeRawFastDds(pinger, domain, std::move(cb));
  if (impl == "raw-cyclonedds") return MakeRawCyclone(pinger, domain, std::move(cb));
  for (const std::string vendor : {"fastdds", "cyclonedds"}) {
    if (impl == "bus-" + vendor)
      return std::make_unique<BusPingPong>(pinger, domain, vendor, false, std::move(cb));
    if (impl == "sbus-" + vendor) {
      if (!std::getenv("CELL_BENCH_PKI")) {
        std::fprintf(stderr, "pingpong: %s needs CELL_BENCH_PKI (a `cellctl pki init --dir` directory)\n",
                     impl.c_str());
        return nullptr;
      }
      return std::make_unique<BusPingPong>(pinger, domain, vendor, true, std::move(cb));
    }
  }
  return nullptr;
}

int Ping(const std::string& impl, int domain, size_t size, int count) {
  std::mutex mu;
  std::condition_variable cv;
  int64_t got = -1;
  auto ep = Make(impl, true, domain, [&](uint32_t seq, const uint8_t*, size_t) {
    std::lock_guard lk(mu);
    got = seq;
    cv.notify_all();
  });
  if (!ep) return 2;
  if (!bus::WaitUntil([&] { return ep->Matched(); }, bus::Millis(10000))) {
    std::fprintf(stderr, "pingpong: %s did not match\n", impl.c_str());
    return 1;
  }
  std::vector<uint8_t> payload(size, 0x5a);
  std::vector<double> us;
  for (int i = 0; i < kWarmUp + count; ++i) {
    const auto seq = static_cast<uint32_t>(i);
    const auto t0 = Clock::now();
    ep->Send(seq, payload.data(), payload.size());
    std::unique_lock lk(mu);
    // The pong's writer may match our reader a little after ours matched: a warm-up echo written before
    // that is lost (volatile), so warm-up rounds are sent again; timed rounds never are.
    while (
        !cv.wait_for(lk, std::chrono::milliseconds(i < kWarmUp ? 500 : 10000), [&] { return got == seq; })) {
      if (i >= kWarmUp) {
        std::fprintf(stderr, "pingpong: %s: no echo of round %d within 10 s\n", impl.c_str(), i);
        return 1;
      }
      lk.unlock();
      ep->Send(seq, payload.data(), payload.size());
      lk.lock();
    }
    const auto t1 = Clock::now();
    if (i >= kWarmUp) us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  Report(impl, size, us);
  ep->Send(kStop, nullptr, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the stop leaves before we do
  return 0;
}

int Pong(const std::string& impl, int domain) {
  std::atomic<PingPong*> self{nullptr};
  std::atomic<bool> done{false};
  auto ep = Make(impl, false, domain, [&](uint32_t seq, const uint8_t* data, size_t n) {
    if (seq == kStop) {
      done = true;
      return;
    }
    PingPong* me;
    while (!(me = self.load())) std::this_thread::yield();  // a sample before Make() returned
    me->Send(seq, data, n);
  });
  if (!ep) return 2;
  self = ep.get();
  const auto deadline = Clock::now() + std::chrono::minutes(5);
  while (!done && Clock::now() < deadline) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  return done ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5 && !(argc == 3 && std::string(argv[1]) == "pong")) {
    std::fprintf(stderr, "usage: bus_pingpong_bench ping IMPL SIZE COUNT | pong IMPL\n");
    return 2;
  }
  const std::string role = argv[1], impl = argv[2];
  const int domain = cell::config::Domain();
  try {
    if (impl.rfind("rpc-", 0) == 0 || impl.rfind("srpc-", 0) == 0) {
      const bool secure = impl[0] == 's';
      if (secure && !std::getenv("CELL_BENCH_PKI")) {
        std::fprintf(stderr, "pingpong: %s needs CELL_BENCH_PKI (a `cellctl pki init --dir` directory)\n",
                     impl.c_str());
        return 2;
      }
      const std::string vendor = impl.substr(impl.find('-') + 1);
      if (role == "pong") return PongRpc(vendor, secure, domain);
      return PingRpc(vendor, secure, domain, std::stoul(argv[3]), std::stoi(argv[4]));
    }
    if (role == "pong") return Pong(impl, domain);
    return Ping(impl, domain, std::stoul(argv[3]), std::stoi(argv[4]));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pingpong: %s: %s\n", impl.c_str(), e.what());
    return 1;
  }
}
