#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <random>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "cell/bus/bus.h"
#include "cell/config/config.h"
#include "cell/config/dds.h"
#include "cell/security/permissions.h"
#include "cell/security/pki.h"
#include "cell/stacks/stacks.h"

namespace cell::bus {

std::string DefaultIdentity(const std::string& name) {
  if (name == "cellctl") return "operator";
  if (name == "cell-dashboard") return "viewer";
  std::string id = name.rfind("cell-", 0) == 0 ? name.substr(5) : name;
  if (auto slash = id.find('/'); slash != std::string::npos) id[slash] = '-';
  return id;
}

int HostServiceSlot(const std::string& participant_name) {
  // One of each per cell (the identity claim refuses a second), so each can own a slot.
  if (participant_name == "cell-scheduler") return 0;
  if (participant_name == "cell-program-store") return 1;
  if (participant_name == "cell-inspection-writer") return 2;
  return -1;
}

std::string StationPartner(const std::string& participant_name) {
  static const std::string kInterpreter = "cell-interpreter/", kServo = "cell-axis-servo/";
  if (participant_name.rfind(kInterpreter, 0) == 0)
    return kServo + participant_name.substr(kInterpreter.size());
  if (participant_name.rfind(kServo, 0) == 0) return kInterpreter + participant_name.substr(kServo.size());
  return {};
}

bool IsStationProcess(const std::string& participant_name) {
  return !StationPartner(participant_name).empty();
}

std::string IdentityOfPartition(const std::string& partition) {
  return cell::security::IdentityOfPartition(partition);
}

std::string StationOfIdentity(const std::string& identity) {
  const auto id = cell::security::ParseIdentity(identity);
  return id && cell::security::IsStationRole(id->role) ? id->station : std::string();
}

bool StationOwns(std::string_view own, std::string_view name) {
  return name.substr(0, own.size()) == own && (name.size() == own.size() || name[own.size()] == '/');
}

bool ForeignStation(const std::string& writer, std::string_view station, const std::string& topic) {
  if (station.empty()) return false;
  const std::string own = StationOfIdentity(writer);
  if (own.empty() || StationOwns(own, station)) return false;
  static std::mutex mu;
  static std::set<std::string> told;  // one warning per writer, station and topic
  std::lock_guard lk(mu);
  if (told.size() < 1024 && told.insert(writer + "|" + std::string(station) + "|" + topic).second)
    spdlog::warn(
        "{}: dropped a sample about station {} written by identity '{}' (a station writes only its own "
        "station's data; docs/security.md)",
        topic, station, writer);
  return true;
}

namespace {
thread_local const std::string* requester = nullptr;
}  // namespace

const std::string& RequesterIdentity() {
  static const std::string none;
  return requester ? *requester : none;
}

RequesterScope::RequesterScope(const std::string& identity) : prev_(requester) {
  requester = &identity;
}
RequesterScope::~RequesterScope() {
  requester = prev_;
}

void LogAccepted(const std::string& service, const std::string& what, const std::string& writer,
                 bool authenticated, const std::string& client, uint64_t request_id) {
  spdlog::info("{}: accepted {} from identity '{}' ({}; client {}, request {})", service, what,
               writer.empty() ? "unknown" : writer, authenticated ? "authenticated" : "claimed, unsecured",
               client, request_id);
}

namespace {

// The identity a participant claims: the option, else CELL_IDENTITY, else derived from its name.
std::string ClaimedIdentity(const ParticipantOptions& opts) {
  if (!opts.identity.empty()) return opts.identity;
  std::string identity = cell::config::IdentityOverride();
  return identity.empty() ? DefaultIdentity(opts.name) : identity;
}

// With CELL_SECURITY=on, the files of the identity this participant claims; throws cell::Error with a
// one-line reason (the missing file, or a name that is no identity).
SecurityFiles SecurityFor(const ParticipantOptions& opts) {
  if (!cell::config::SecurityOn()) return {};
  const std::string identity = ClaimedIdentity(opts);
  const std::filesystem::path dir =
      opts.security_dir.empty() ? cell::security::SecurityDir() : std::filesystem::path(opts.security_dir);
  try {
    const auto f = cell::security::FindIdentityFiles(dir, identity);
    return {identity,       f.ca.string(),          f.governance.string(), f.certificate.string(),
            f.key.string(), f.permissions.string(), f.crl.string()};
  } catch (const Error& e) {
    throw Error(e.code(), "CELL_SECURITY=on: " + std::string(e.what()));
  }
}

}  // namespace

bool WaitUntil(const std::function<bool()>& cond, Millis timeout, Millis period) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!cond()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(period);
  }
  return true;
}

Participant::Participant(const ParticipantOptions& opts) {
  domain_ = opts.domain ? *opts.domain : cell::config::Domain();
  lone_means_down_ = opts.lone_means_down;
  vendor_ = opts.backend.empty() ? cell::config::DdsVendor().vendor : opts.backend;
  if (!cell::config::IsDdsVendor(vendor_))
    throw Error(Errc::kInvalidArgument,
                "DDS backend '" + vendor_ + "': expected one of " + cell::config::DdsVendorList());
  std::filesystem::path profile = opts.profile_path.empty() ? cell::config::DdsProfile(vendor_)
                                                            : std::filesystem::path(opts.profile_path);
  char host[64] = {0};
  gethostname(host, sizeof host - 1);
  std::random_device rd;
  id_ = fmt::format("{}@{}/{}/{:x}", opts.name.empty() ? "cell" : opts.name, host, getpid(), rd() & 0xffffff);
  if (id_.size() > 63) id_ = id_.substr(id_.size() - 63);
  BackendOptions bo{domain_, profile.string(),  opts.name,
                    {},      SecurityFor(opts), cell::security::WritePartition(ClaimedIdentity(opts))};
  identity_ = bo.security.identity;
  bo.participants = cell::config::DdsParticipants();
  bo.preferred_slot = HostServiceSlot(opts.name);
  bo.host_services_only = opts.host_services_only;
  if (opts.host_services_only) cell_participants_ = bo.participants;
  bo.station_process = IsStationProcess(opts.name);
  if (!profile.empty()) bo.profile_xml = cell::config::LoadDdsProfile(profile);  // ${VAR}s expanded once
  if (vendor_ == "fastdds")
    make_backend_ = [bo] { return MakeFastDdsBackend(bo); };
  else
    make_backend_ = [bo] { return MakeCycloneBackend(bo); };
  try {
    backend_ = make_backend_();
  } catch (const Error& e) {
    if (bo.security.identity.empty()) throw;
    // The stack says little (Fast DDS logs, Cyclone returns an error code): check the documents ourselves.
    const std::string why = cell::security::DiagnoseIdentity(
        bo.security.identity, bo.security.ca, bo.security.governance, bo.security.certificate,
        bo.security.key, bo.security.permissions, bo.security.crl);
    throw Error(Errc::kPermissionDenied,
                fmt::format("DDS Security refused identity '{}' ({}): {}", bo.security.identity,
                            std::filesystem::path(bo.security.ca).parent_path().string(),
                            why.empty() ? std::string(e.what()) : why));
  }
  spdlog::debug("{}: joined DDS domain {} with {} ({}{})", id_, domain_, vendor_,
                profile.empty() ? "built-in loopback profile" : profile.string(),
                identity_.empty() ? "" : ", secured as " + identity_);
  thread_ = std::thread([this] { Run(); });
  watch_ = std::thread([this] { Watch(); });
}

Participant::Participant(const std::string& name, int domain, std::unique_ptr<Backend> backend)
    : domain_(domain), vendor_(backend->Name()), backend_(std::move(backend)) {
  char host[64] = {0};
  gethostname(host, sizeof host - 1);
  std::random_device rd;
  id_ = fmt::format("{}@{}/{}/{:x}", name, host, getpid(), rd() & 0xffffff);
  if (id_.size() > 63) id_ = id_.substr(id_.size() - 63);
  thread_ = std::thread([this] { Run(); });
}

Participant::~Participant() {
  {
    std::lock_guard lk(watch_mu_);
    watch_stop_ = true;
  }
  watch_cv_.notify_all();
  if (watch_.joinable()) watch_.join();
  {
    std::lock_guard lk(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
  // Entities owned by Writers/Readers must already be gone; the backend deletes the participant.
  backend_.reset();
}

void Participant::Post(std::function<void()> fn) {
  {
    std::lock_guard lk(mu_);
    if (stop_) return;
    queue_.push_back(std::move(fn));
  }
  cv_.notify_one();
}

void Participant::Register(Rejoinable* e) {
  std::lock_guard lk(reg_mu_);
  endpoints_.insert(e);
}

void Participant::Unregister(Rejoinable* e) {
  std::lock_guard lk(reg_mu_);
  endpoints_.erase(e);
}

bool Participant::Rejoin() {
  if (!make_backend_) return false;
  std::unique_lock lk(ep_mu_);  // no endpoint is used, made or released meanwhile
  std::lock_guard rl(reg_mu_);
  for (Rejoinable* e : endpoints_) e->Drop();
  backend_.reset();
  for (int attempt = 1;; ++attempt) {
    try {
      backend_ = make_backend_();
      break;
    } catch (const std::exception& e) {
      // Without a participant every endpoint is gone: better a restart (systemd) than a deaf service.
      if (attempt == 3) {
        spdlog::critical("{}: cannot join the bus again: {}", id_, e.what());
        std::abort();
      }
      std::this_thread::sleep_for(Millis(200));
    }
  }
  for (Rejoinable* e : endpoints_) e->Recreate(*backend_);
  ++rejoins_;
  return true;
}

// Sleeps 250 ms at a time; a sleep that took over 2.5 s means the process stood still (stopped or starved)
// long enough for peers to let its 3 s lease run out.
//
// It also watches the stack's receive threads: Fast DDS 2.9.1 can deadlock one against its timer thread (a
// peer's endpoint removed on the receive thread under the discovery lock, waiting for the timer thread, which
// waits for that lock in a participant's lease check: seen in a scheduler of a 68-process cell, which then
// heard nothing and answered nobody). A receive call that runs 30 s is that: the process ends (abort), as
// when it cannot rejoin, so that systemd starts it again instead of leaving a deaf service. Before it ends,
// it writes every thread's stack to the log: the stuck call and the thread it waits for, which nobody could
// attach gdb to in time (a scheduler of a 32-station week, 2026-12-04, with the bus's own lease check).
void Participant::Watch() {
  constexpr auto kTick = Millis(250);
  constexpr auto kStoodStill = Millis(2500);
  constexpr auto kStuck = Millis(30000);
  StuckReceive stuck(kStuck);
  stacks::Prepare();
  std::unique_lock lk(watch_mu_);
  auto last = std::chrono::steady_clock::now();
  while (!watch_cv_.wait_for(lk, kTick, [&] { return watch_stop_; })) {
    const auto now = std::chrono::steady_clock::now();
    const bool on_time = now - last <= kStoodStill;
    int64_t oldest = 0;
    {
      std::shared_lock el(ep_mu_);
      if (backend_) oldest = backend_->OldestReceiveStartNs();
    }
    if (stuck.Observe(oldest, std::chrono::duration_cast<Millis>(now - last), on_time)) {
      spdlog::critical(
          "{}: a {} receive thread has been stuck in one call for {:.0f} s, so this process hears nothing "
          "(Fast DDS 2.9.1 deadlocks a receive thread against its timer thread; docs/operations.md §11): "
          "ending it so that it is started again",
          id_, vendor_, std::chrono::duration<double>(stuck.stuck_for()).count());
      spdlog::default_logger()->flush();
      stacks::WriteThreadStacks(2);
      std::abort();
    }
    if (!on_time) {  // (only started when the backend can be made again)
      spdlog::warn(
          "{}: this process stood still for {:.1f} s (longer than the DDS lease): joining the bus anew", id_,
          std::chrono::duration<double>(now - last).count());
      lk.unlock();
      Rejoin();
      lk.lock();
    }
    last = std::chrono::steady_clock::now();
  }
}

void Participant::Run() {
  std::unique_lock lk(mu_);
  while (true) {
    cv_.wait(lk, [&] { return stop_ || !queue_.empty(); });
    if (stop_) return;
    auto fn = std::move(queue_.front());
    queue_.pop_front();
    lk.unlock();
    fn();
    lk.lock();
  }
}

}  // namespace cell::bus
