// The cell's bus: typed publish/subscribe, request/reply with request ids and timeouts, and
// "wait until matched", over a DDS backend chosen per process (CELL_DDS). Services include
// this header only; no DDS header or type reaches them.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <shared_mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "cell/bus/backend.h"
#include "cell/bus/cdr.h"
#include "cell/error/error.h"

namespace cell::bus {

using Millis = std::chrono::milliseconds;

struct ParticipantOptions {
  std::string name;           // shown in logs and discovery, e.g. "cell-interpreter/KT01"
  std::optional<int> domain;  // default: cell::config::Domain() (CELL_DOMAIN, else 101)
  std::string backend;  // "fastdds" | "cyclonedds"; default: CELL_DDS, else "fastdds" (config::DdsVendor)
  std::string profile_path;  // default: CELL_DDS_PROFILE for this vendor (config::DdsProfile), else the
                             // built-in loopback profile
  // With CELL_SECURITY=on: the security identity (docs/security.md). Default: CELL_IDENTITY, else derived
  // from the name ("cell-scheduler" -> scheduler, "cell-interpreter/KT01" -> interpreter-KT01, "cellctl" ->
  // operator, "cell-dashboard" -> viewer).
  std::string identity;
  std::string security_dir;  // default: cell::security::SecurityDir()
  // A client of this participant that finds no other participant on the domain within kLoneWindow reports
  // its service absent at once (cellctl: a cell that is down is said so in under a second). Services leave
  // it off: at a cell's start a process may be alone for a while and waits out discovery.
  bool lone_means_down = false;
  // A client that calls only the host services (scheduler, program store, inspection writer): it announces
  // itself to their reserved slots only (BackendOptions::host_services_only) and hears no station. cellctl's
  // verbs that talk to one service set it; those that watch stations do not.
  bool host_services_only = false;
};

// Options naming the participant (and its vendor), everything else by default. (GCC 12 warns about the
// members a designated initializer leaves out.)
inline ParticipantOptions Named(std::string name, std::string backend = {}) {
  ParticipantOptions o;
  o.name = std::move(name);
  o.backend = std::move(backend);
  return o;
}

// The security identity a participant named `name` claims by default (above).
std::string DefaultIdentity(const std::string& name);

// The backend half of a Writer, Reader or Client, made again when the participant rejoins.
class Rejoinable {
 public:
  virtual ~Rejoinable() = default;
  virtual void Drop() = 0;                // release the backend endpoint
  virtual void Recreate(Backend& b) = 0;  // the same endpoint on a new backend
};

// The watch thread's test for a stuck receive thread (Backend::OldestReceiveStartNs): stuck once the same
// receive call has been running through `limit` of ticks that came on time. A tick after the process stood
// still starts the count again (a call a SIGSTOP froze is not stuck).
class StuckReceive {
 public:
  explicit StuckReceive(Millis limit) : limit_(limit) {}
  // `oldest`: the backend's oldest running receive (0: none); `tick`: the time since the last call.
  bool Observe(int64_t oldest, Millis tick, bool on_time) {
    if (!on_time || oldest == 0 || oldest != last_) {
      last_ = oldest;
      stuck_ = Millis(0);
      return false;
    }
    stuck_ += tick;
    return stuck_ >= limit_;
  }
  Millis stuck_for() const { return stuck_; }

 private:
  Millis limit_;
  Millis stuck_{0};
  int64_t last_ = 0;
};

// One DDS participant per process plus one dispatch thread that runs every user callback in
// arrival order, so callbacks never run on (or block) the DDS receive threads.
//
// Rejoin: a process stopped longer than the 3 s DDS lease (SIGSTOP, a paused VM) is dropped by its peers,
// and Fast DDS 2.9 does not always exchange endpoints again with a participant that kept its own view of
// them (eProsima/Fast-DDS #155, #457: one-sided lease expiry) — measured here, a stopped axis servo or
// interpreter could stay cut off from some peers for good. A watch thread notices that the process stood
// still (its 250 ms sleep took over 2.5 s) and replaces the DDS participant with a new one, a stranger to
// every peer, so discovery starts clean; every Writer, Reader and Client re-creates its backend endpoint on
// it, and their users see at most a lost match (re-sends and request retries cover it).
class Participant {
 public:
  explicit Participant(const ParticipantOptions& opts);
  explicit Participant(const std::string& name) : Participant(Named(name)) {}
  // With an explicit backend (the interop peer runs the typed bus over Cyclone this way).
  Participant(const std::string& name, int domain, std::unique_ptr<Backend> backend);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  const std::string& id() const { return id_; }  // unique on the domain: name/host/pid/n
  // The DDS Security identity it joined as; empty when unsecured (CELL_SECURITY off).
  const std::string& identity() const { return identity_; }
  int domain() const { return domain_; }
  bool lone_means_down() const { return lone_means_down_; }
  // The participants a client of the host services only should reckon with while it waits for a server
  // (ServerWait): the configured cell's (config::DdsParticipants), whom the services it calls answer too,
  // though it hears only those services; 0 for any other participant, which counts the peers it hears.
  int cell_participants() const { return cell_participants_; }
  const std::string& vendor() const { return vendor_; }  // "fastdds" or "cyclonedds"
  Backend& backend() { return *backend_; }
  void Post(std::function<void()> fn);

  // Held shared around every use of a backend endpoint (and while one is made or released), exclusively
  // while the participant rejoins.
  std::shared_mutex& endpoints_mu() { return ep_mu_; }
  void Register(Rejoinable* e);    // with endpoints_mu() held shared
  void Unregister(Rejoinable* e);  // with endpoints_mu() held shared
  // A new DDS participant under every endpoint (done by the watch thread; public for tests). False with
  // an injected backend, which cannot be made again.
  bool Rejoin();
  uint64_t rejoins() const { return rejoins_.load(); }
  // Backend::RemoteParticipants (-1: cannot tell).
  int RemoteParticipants() {
    std::shared_lock lk(ep_mu_);
    return backend_->RemoteParticipants();
  }

 private:
  void Run();
  void Watch();
  std::string id_;
  std::string identity_;
  int domain_;
  bool lone_means_down_ = false;
  int cell_participants_ = 0;
  std::string vendor_;
  std::function<std::unique_ptr<Backend>()> make_backend_;  // empty for an injected backend
  std::unique_ptr<Backend> backend_;
  std::shared_mutex ep_mu_;
  std::mutex reg_mu_;
  std::set<Rejoinable*> endpoints_;
  std::atomic<uint64_t> rejoins_{0};
  std::mutex watch_mu_;
  std::condition_variable watch_cv_;
  bool watch_stop_ = false;
  std::thread watch_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::function<void()>> queue_;
  bool stop_ = false;
  std::thread thread_;
};

// Polls a condition until it holds or the deadline passes (matching is asynchronous in DDS).
bool WaitUntil(const std::function<bool()>& cond, Millis timeout, Millis period = Millis(2));

// How long a Client waits for a server it has not matched yet (Client::Call): `base`, or 150 ms for each of
// the `heard` participants when that is longer (-1: the backend cannot tell), never past the call's
// `timeout`.
inline Millis ServerWait(Millis base, int heard, Millis timeout) {
  return std::min(timeout, std::max(base, Millis(150) * std::max(heard, 0)));
}

struct SampleInfo {
  int64_t received_ns = 0;  // steady clock, when the bus got it
  // The identity of the writer, from the partition it writes in (BackendOptions::partition): authenticated
  // under DDS Security (the permissions grant each identity its own partition only), claimed without it.
  // Empty when the backend could not tell.
  std::string writer;
};

// True, with one warning per writer, station and topic, when `writer` is a station's identity
// ("interpreter-KT01") and `station` another station: a Reader drops such a sample, so no station can write
// another station's key of a topic the stations share (docs/security.md, "Partitions").
bool ForeignStation(const std::string& writer, std::string_view station, const std::string& topic);

// The station of a station's identity ("interpreter-KT01" -> "KT01"); empty for any other identity.
std::string StationOfIdentity(const std::string& identity);
// Whether `name` (a station id or program store namespace) is station `own`'s: "BS01" and its memories
// ("BS01/MP3", Balt-System) are BS01's.
bool StationOwns(std::string_view own, std::string_view name);

// While a Server's handler runs: the identity that sent the request (SampleInfo::writer), so a service can
// check what only some identities may ask for. Empty elsewhere or when unknown.
const std::string& RequesterIdentity();
class RequesterScope {
 public:
  explicit RequesterScope(const std::string& identity);
  ~RequesterScope();
  RequesterScope(const RequesterScope&) = delete;
  RequesterScope& operator=(const RequesterScope&) = delete;

 private:
  const std::string* prev_;
};

// The audit trail: one journal line per accepted command, with the identity that sent it.
void LogAccepted(const std::string& service, const std::string& what, const std::string& writer,
                 bool authenticated, const std::string& client, uint64_t request_id);

template <class T>
class Writer : public Rejoinable {
 public:
  Writer(Participant& p, const std::string& topic, QosKind qos) : p_(p), topic_(topic), qos_(qos) {
    std::shared_lock lk(p_.endpoints_mu());
    w_ = p_.backend().CreateWriter(topic_, TypeSupportFor<T>(), qos_);
    p_.Register(this);
  }
  ~Writer() override {
    std::shared_lock lk(p_.endpoints_mu());
    p_.Unregister(this);
    w_.reset();
  }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  // Throws cell::Error(kInvalidArgument) when a sequence exceeds its IDL bound: Fast CDR would
  // send it and a Cyclone reader would drop it.
  void Write(const T& v) { WriteRaw(Serialize(v)); }
  // Write in two steps: the sample as it goes on the wire (bounds checked as above), and sending it, again
  // if need be (a Server's reply cache keeps replies serialized: a T with a bounded string<65536> is a 64 KiB
  // array in memory, whatever its text).
  RawSample Serialize(const T& v) const {
    std::string why;
    if (!cell::idl::CheckBounds(v, why)) throw Error(Errc::kInvalidArgument, topic_ + ": " + why);
    return RawSample{ToCdr(v), KeyCdr(v)};
  }
  void WriteRaw(const RawSample& s) {
    std::shared_lock lk(p_.endpoints_mu());
    if (qos_ != QosKind::kState) {
      w_->Write(s);
      return;
    }
    std::lock_guard last(last_mu_);  // what last_ keeps is what went out last
    RawSample& kept = last_[s.key];
    kept.cdr.assign(s.cdr.begin(), s.cdr.end());
    kept.key = s.key;
    w_->Write(s);
  }
  int Matched() const {
    std::shared_lock lk(p_.endpoints_mu());
    return w_->Matched();
  }
  // Counts on across a rejoin (the new endpoint's matches are added to the old one's).
  uint64_t TotalMatched() const {
    std::shared_lock lk(p_.endpoints_mu());
    return base_matches_ + w_->TotalMatched();
  }
  bool WaitForMatched(int n, Millis timeout) const {
    return WaitUntil([&] { return Matched() >= n; }, timeout);
  }
  // Before a process exits: everything written reached every matched reader.
  bool WaitForAcked(Millis timeout) {
    std::shared_lock lk(p_.endpoints_mu());
    return w_->WaitForAcked(static_cast<int>(timeout.count()));
  }

  void Drop() override {
    base_matches_ += w_->TotalMatched() + 1;  // +1: the rejoin itself is a lost match
    w_.reset();
  }
  // A state writer made anew has an empty history, and a state often goes out only when it changes (a
  // station's status): it writes each key's last sample again, so that a reader that joins after the rejoin
  // gets the state too. Events (kEvent) are not written again: a reader that had them would get them twice.
  void Recreate(Backend& b) override {
    w_ = b.CreateWriter(topic_, TypeSupportFor<T>(), qos_);
    std::lock_guard last(last_mu_);
    for (const auto& [key, sample] : last_) w_->Write(sample);
  }

 private:
  Participant& p_;
  std::string topic_;
  QosKind qos_;
  uint64_t base_matches_ = 0;
  std::unique_ptr<RawWriter> w_;
  std::mutex last_mu_;
  std::map<std::vector<uint8_t>, RawSample> last_;  // kState: the last sample written of each key
};

// With a callback, samples are delivered on the participant's dispatch thread. Without one,
// they queue for Take().
template <class T>
class Reader : public Rejoinable {
 public:
  using Callback = std::function<void(const T&, const SampleInfo&)>;

  Reader(Participant& p, const std::string& topic, QosKind qos, Callback cb = nullptr)
      : p_(p), topic_(topic), qos_(qos), state_(std::make_shared<State>()) {
    state_->cb = std::move(cb);
    state_->topic = topic;
    std::weak_ptr<State> weak = state_;
    Participant* part = &p;
    raw_cb_ = [weak, part](const RawSample& s, const RawInfo& info) {
      auto st = weak.lock();
      if (st) st->Deliver(*part, weak, s, info);
    };
    std::shared_lock lk(p_.endpoints_mu());
    r_ = p_.backend().CreateReader(topic_, TypeSupportFor<T>(), qos_, raw_cb_);
    p_.Register(this);
  }
  ~Reader() override {
    {
      std::shared_lock lk(p_.endpoints_mu());
      p_.Unregister(this);
      r_.reset();  // no more backend callbacks after this
    }
    {
      std::lock_guard lk(state_->mu);
      state_->cb = nullptr;
    }
    // A callback already running on the participant's thread finishes before the reader (and whatever its
    // owner destroys next) is gone: a service's destructor no longer races its own callbacks. Recursive, so a
    // callback may destroy its own reader.
    std::lock_guard call(state_->call_mu);
  }
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  int Matched() const {
    std::shared_lock lk(p_.endpoints_mu());
    return r_->Matched();
  }
  bool WaitForMatched(int n, Millis timeout) const {
    return WaitUntil([&] { return Matched() >= n; }, timeout);
  }
  void Drop() override { r_.reset(); }
  void Recreate(Backend& b) override { r_ = b.CreateReader(topic_, TypeSupportFor<T>(), qos_, raw_cb_); }

  std::optional<T> Take(Millis timeout) {
    std::unique_lock lk(state_->mu);
    // A zero timeout is a poll (hot loops such as the servo tick): no timed wait, no syscall.
    if (timeout.count() <= 0 ? state_->queue.empty()
                             : !state_->cv.wait_for(lk, timeout, [&] { return !state_->queue.empty(); }))
      return std::nullopt;
    T v = std::move(state_->queue.front().first);
    state_->queue.pop_front();
    return v;
  }

  // Takes samples until one satisfies pred; drops the others.
  std::optional<T> WaitFor(const std::function<bool(const T&)>& pred, Millis timeout) {
    auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
      auto left = std::chrono::duration_cast<Millis>(deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      auto v = Take(left);
      if (!v) return std::nullopt;
      if (pred(*v)) return v;
    }
  }

 private:
  struct State {
    std::mutex mu;
    std::recursive_mutex call_mu;  // held while the callback runs
    std::condition_variable cv;
    Callback cb;
    std::string topic;
    std::deque<std::pair<T, SampleInfo>> queue;

    void Deliver(Participant& p, const std::weak_ptr<State>& weak, const RawSample& s, const RawInfo& info) {
      if (!info.valid) return;
      T v;
      if (!FromCdr(s.cdr.data(), s.cdr.size(), v)) return;  // undecodable: never crash a service
      SampleInfo si{std::chrono::duration_cast<std::chrono::nanoseconds>(
                        std::chrono::steady_clock::now().time_since_epoch())
                        .count(),
                    IdentityOfPartition(info.writer_partition)};
      if constexpr (requires { v.station().c_str(); }) {
        if (!si.writer.empty() && ForeignStation(si.writer, v.station().c_str(), topic)) return;
      }
      {
        std::lock_guard lk(mu);
        if (!cb) {
          queue.emplace_back(std::move(v), si);
          cv.notify_all();
          return;
        }
      }
      p.Post([weak, v = std::move(v), si = std::move(si)] {
        auto st = weak.lock();
        if (!st) return;
        std::lock_guard call(st->call_mu);
        Callback fn;
        {
          std::lock_guard lk(st->mu);
          fn = st->cb;
        }
        if (fn) fn(v, si);
      });
    }
  };
  Participant& p_;
  std::string topic_;
  QosKind qos_;
  RawCallback raw_cb_;
  std::shared_ptr<State> state_;
  std::unique_ptr<RawReader> r_;
};

// Topic names of a request/reply service.
inline std::string RequestTopic(const std::string& service) {
  return service + "/request";
}
inline std::string ReplyTopic(const std::string& service) {
  return service + "/reply";
}

// Throws the cell::Error a reply carries (code != 0).
template <class Rep>
void ThrowIfError(const Rep& rep) {
  if (rep.hdr().code() != 0)
    throw Error(static_cast<Errc>(rep.hdr().code() - 1), rep.hdr().error().to_string());
}

// How long a client waits for any other participant before it concludes that nothing runs on the domain.
// Fast DDS finds a running process in a median 80 ms, a third of single pairs in 0.6-1 s
// (docs/architecture.md, "Discovery latency"); a cell is several processes, and one found is enough to wait
// on.
inline constexpr Millis kLoneWindow{800};

// A request id unique in the process. A server keeps replies by (client id, request id) and the client id
// is the participant's, shared by every Client of the process: ids counted per Client from 1 made a second
// client of the same service get the first one's cached replies (`inspect ls` got page 1 again).
inline uint64_t NextRequestId() {
  static std::atomic<uint64_t> next{0};
  return ++next;
}

// Request/reply over two command topics. Requests carry (client id, request id); the client
// re-sends until answered, the server answers a duplicate from its reply cache, so a request
// written before discovery completed is not lost and never runs twice.
template <class Req, class Rep>
class Client : public Rejoinable {
 public:
  Client(Participant& p, const std::string& service)
      : p_(p),
        service_(service),
        state_(std::make_shared<State>()),
        req_(p, RequestTopic(service), QosKind::kCommand) {
    std::weak_ptr<State> weak = state_;
    std::string me = p.id();
    // Replies are matched on the receive path, not the dispatch thread, so a caller blocked in
    // Call() from a dispatch-thread callback cannot deadlock.
    const std::string topic = ReplyTopic(service);
    raw_cb_ = [weak, me, topic](const RawSample& s, const RawInfo& info) {
      auto st = weak.lock();
      if (!st || !info.valid) return;
      Rep r;
      if (!FromCdr(s.cdr.data(), s.cdr.size(), r)) return;
      if (r.hdr().client() != me) return;
      std::lock_guard lk(st->mu);
      auto it = st->pending.find(r.hdr().request_id());
      if (it == st->pending.end() || it->second) return;
      // A service every station serves (topics::kStationRun): only the station the request named answers
      // it, so a station identity's reply to a request for another station is dropped (docs/security.md).
      if (auto a = st->addressee.find(it->first); a != st->addressee.end()) {
        const std::string writer = IdentityOfPartition(info.writer_partition);
        if (!writer.empty() && ForeignStation(writer, a->second, topic)) return;
      }
      it->second = std::move(r);
      st->cv.notify_all();
    };
    std::shared_lock lk(p_.endpoints_mu());
    Recreate(p_.backend());
    p_.Register(this);
  }
  ~Client() override {
    std::shared_lock lk(p_.endpoints_mu());
    p_.Unregister(this);
    rep_raw_.reset();
  }
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  bool WaitForServer(Millis timeout) const {
    return WaitUntil(
        [&] {
          if (req_.Matched() == 0) return false;
          std::shared_lock lk(p_.endpoints_mu());
          return rep_raw_->Matched() > 0;
        },
        timeout);
  }
  void Drop() override { rep_raw_.reset(); }
  void Recreate(Backend& b) override {
    rep_raw_ = b.CreateReader(ReplyTopic(service_), TypeSupportFor<Rep>(), QosKind::kCommand, raw_cb_);
  }

  // Sends req and waits for its reply. Throws cell::Error: kUnavailable when no server was
  // matched within the timeout, kTimeout when it never answered. A reply with an error code is
  // returned as is (see ThrowIfError). `abandon`, asked at every re-send, ends a long wait for a server
  // known to be gone (a request that runs for minutes, whose server was killed): kUnavailable with its text.
  Rep Call(Req req, Millis timeout, Millis resend = Millis(250),
           const std::function<std::string()>& abandon = nullptr) {
    auto deadline = std::chrono::steady_clock::now() + timeout;
    // Discovery takes milliseconds (1 s across vendors); a server missing after 5 s is down. When no other
    // participant at all has answered after kLoneWindow, nothing runs on the domain: say so at once.
    const Millis lone = p_.lone_means_down() ? std::min(timeout, kLoneWindow) : Millis(0);
    if (!WaitForServer(lone)) {
      const std::string none = "no " + service_ + " service on DDS domain " + std::to_string(p_.domain());
      if (p_.lone_means_down() && p_.RemoteParticipants() == 0)
        throw Error(Errc::kUnavailable, none + " (nothing else runs on the domain: is the cell up?)");
      // A secured participant must also pass each peer's authentication handshake (signatures, key
      // exchange): in a sanitized build on a loaded host that took over 5 s (issue 44), so it gets 15 s.
      // A newcomer to a large cell hears its peers' endpoints over seconds (a 32-station cell, 68 other
      // participants: `cellctl job ls` took 0.6-3.3 s on Fast DDS, and across four hosts a verb found no
      // scheduler in 5 s), so the wait grows with the participants heard so far: 150 ms each, counted
      // again whenever the wait runs out. A client of the host services only hears just those services,
      // which answer it amid the whole cell: it counts the configured cell's participants.
      const Millis base(p_.identity().empty() ? 5000 : 15000);
      const auto start = deadline - timeout;
      while (true) {
        const Millis limit =
            ServerWait(base, std::max(p_.RemoteParticipants(), p_.cell_participants()), timeout);
        const auto left = std::chrono::ceil<Millis>(start + limit - std::chrono::steady_clock::now());
        if (left <= Millis(0)) throw Error(Errc::kUnavailable, none);
        if (WaitForServer(left)) break;
      }
    }
    uint64_t id = NextRequestId();
    req.hdr().client(p_.id());
    req.hdr().request_id(id);
    {
      std::lock_guard lk(state_->mu);
      state_->pending[id] = std::nullopt;
      if constexpr (requires { req.station().c_str(); }) state_->addressee[id] = req.station().c_str();
    }
    std::unique_lock lk(state_->mu);
    while (true) {
      lk.unlock();
      try {
        req_.Write(req);
      } catch (const Error& e) {  // a request over an IDL bound fails now; a transient failure is re-sent
        if (e.code() == Errc::kInvalidArgument) {
          std::lock_guard g(state_->mu);
          state_->pending.erase(id);
          state_->addressee.erase(id);
          throw;
        }
      }
      lk.lock();
      auto next = std::min(deadline, std::chrono::steady_clock::now() + resend);
      if (state_->cv.wait_until(lk, next, [&] { return state_->pending[id].has_value(); })) {
        Rep r = std::move(*state_->pending[id]);
        state_->pending.erase(id);
        state_->addressee.erase(id);
        return r;
      }
      if (std::chrono::steady_clock::now() >= deadline) {
        state_->pending.erase(id);
        state_->addressee.erase(id);
        throw Error(Errc::kTimeout,
                    service_ + " did not answer within " + std::to_string(timeout.count()) + " ms");
      }
      if (abandon) {
        lk.unlock();
        std::string why = abandon();
        lk.lock();
        if (!why.empty() && !state_->pending[id]) {
          state_->pending.erase(id);
          state_->addressee.erase(id);
          throw Error(Errc::kUnavailable, why);
        }
      }
    }
  }

 private:
  struct State {
    std::mutex mu;
    std::recursive_mutex call_mu;  // held while the callback runs
    std::condition_variable cv;
    std::map<uint64_t, std::optional<Rep>> pending;
    std::map<uint64_t, std::string> addressee;  // the station a pending request names (Req.station)
  };
  Participant& p_;
  std::string service_;
  std::shared_ptr<State> state_;
  Writer<Req> req_;
  RawCallback raw_cb_;
  std::unique_ptr<RawReader> rep_raw_;
};

template <class Req, class Rep>
class Server {
 public:
  using Handler = std::function<Rep(const Req&)>;
  // The audit trail: names a request that changes something ("program put HOST:O1000"); empty for a
  // query, which is not logged. An accepted request it names is logged with its sender's identity.
  using Describe = std::function<std::string(const Req&)>;

  // Which requests are this server's: on a service every station serves (topics::kStationRun) a station
  // answers only those naming it, and leaves the others to their station (no reply, nothing cached).
  using Accept = std::function<bool(const Req&)>;

  Server(Participant& p, const std::string& service, Handler h, Describe describe = nullptr,
         Accept accept = nullptr)
      : p_(p),
        service_(service),
        handler_(std::move(h)),
        describe_(std::move(describe)),
        accept_(std::move(accept)),
        rep_(p, ReplyTopic(service), QosKind::kCommand),
        req_(p, RequestTopic(service), QosKind::kCommand,
             [this](const Req& r, const SampleInfo& si) { Handle(r, si); }) {}

  int Matched() const { return req_.Matched(); }
  // The reply cache as it stands (tests): entries and their serialized bytes.
  std::pair<size_t, size_t> CacheUse() const {
    std::lock_guard lk(cache_mu_);
    return {cache_.size(), cache_bytes_};
  }

  // A re-sent request is answered from the cache only while its requester may still re-send (every 250 ms
  // until its Call times out): the newest replies are kept, up to kCacheSize entries and kCacheBytes, as the
  // CDR they were sent as. Kept as Rep objects, each was the IDL type's full size (a string<65536> field is a
  // 64 KiB array): 4096 cached replies were 268 MB, whatever their text (issue 39 item 1).
  static constexpr size_t kCacheSize = 4096;
  static constexpr size_t kCacheBytes = size_t{4} << 20;

 private:
  void Remember(const std::pair<std::string, uint64_t>& key, RawSample s) {
    std::lock_guard lk(cache_mu_);
    const size_t bytes = s.cdr.size() + s.key.size();
    auto [it, inserted] = cache_.try_emplace(key);
    if (inserted) {
      order_.push_back(key);
    } else {
      cache_bytes_ -= it->second.cdr.size() + it->second.key.size();
    }
    it->second = std::move(s);
    cache_bytes_ += bytes;
    while (order_.size() > 1 && (order_.size() > kCacheSize || cache_bytes_ > kCacheBytes)) {
      auto old = cache_.find(order_.front());
      cache_bytes_ -= old->second.cdr.size() + old->second.key.size();
      cache_.erase(old);
      order_.pop_front();
    }
  }
  std::optional<RawSample> Cached(const std::pair<std::string, uint64_t>& key) const {
    std::lock_guard lk(cache_mu_);
    auto it = cache_.find(key);
    if (it == cache_.end()) return std::nullopt;
    return it->second;
  }

  void Handle(const Req& r, const SampleInfo& si) {
    if (accept_ && !accept_(r)) return;
    auto key = std::make_pair(std::string(r.hdr().client()), r.hdr().request_id());
    if (std::optional<RawSample> cached = Cached(key)) {  // a re-sent request: answer again, do not run again
      rep_.WriteRaw(*cached);
      return;
    }
    Rep rep;
    try {
      RequesterScope scope(si.writer);
      rep = handler_(r);
      if (describe_ && rep.hdr().code() == 0) {
        const std::string what = describe_(r);
        if (!what.empty())
          LogAccepted(service_, what, si.writer, !p_.identity().empty(), r.hdr().client().to_string(),
                      r.hdr().request_id());
      }
    } catch (const Error& e) {
      rep = Rep();
      rep.hdr().code(static_cast<int32_t>(e.code()) + 1);
      rep.hdr().error(std::string(e.what()).substr(0, 511));
    } catch (const std::exception& e) {
      rep = Rep();
      rep.hdr().code(static_cast<int32_t>(Errc::kInternal) + 1);
      rep.hdr().error(std::string(e.what()).substr(0, 511));
    }
    rep.hdr().client(r.hdr().client());
    rep.hdr().request_id(r.hdr().request_id());
    try {
      Send(key, rep_.Serialize(rep));
    } catch (const Error& e) {
      // A reply that can never be sent (over an IDL bound, found here or by the DDS stack) becomes an error
      // reply; a transient failure (a writer that could not queue it) is answered from the cache on re-send.
      if (e.code() != Errc::kInvalidArgument) return;
      Rep err;
      err.hdr() = rep.hdr();
      err.hdr().code(static_cast<int32_t>(e.code()) + 1);
      err.hdr().error(std::string(e.what()).substr(0, 511));
      try {
        Send(key, rep_.Serialize(err));
      } catch (const Error&) {  // as above: the re-sent request gets it from the cache
      }
    }
  }
  // Remembers the reply, then writes it (to a vanished requester this goes nowhere, which is fine).
  void Send(const std::pair<std::string, uint64_t>& key, RawSample s) {
    Remember(key, s);
    rep_.WriteRaw(s);
  }

  Participant& p_;
  std::string service_;
  Handler handler_;
  Describe describe_;
  Accept accept_;
  mutable std::mutex cache_mu_;                                  // CacheUse() reads from another thread
  std::map<std::pair<std::string, uint64_t>, RawSample> cache_;  // the reply as sent
  std::deque<std::pair<std::string, uint64_t>> order_;
  size_t cache_bytes_ = 0;
  Writer<Rep> rep_;
  Reader<Req> req_;
};

}  // namespace cell::bus
