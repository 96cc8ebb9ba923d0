#include <unistd.h>

#include <cstdlib>
#include <random>

#include <fmt/format.h>

#include "cell/bus/bus.h"
#include "cell/config/config.h"

namespace cell::bus {

bool WaitUntil(const std::function<bool()>& cond, Millis timeout) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!cond()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(Millis(2));
  }
  return true;
}

namespace {
std::string EnvOr(const char* name, const std::string& dflt) {
  const char* v = std::getenv(name);
  return v && *v ? std::string(v) : dflt;
}
}  // namespace

Participant::Participant(const ParticipantOptions& opts) {
  domain_ = opts.domain ? *opts.domain : cell::config::Domain();
  std::string backend = opts.backend.empty() ? EnvOr("CELL_DDS", "fastdds") : opts.backend;
  std::string profile = opts.profile_path.empty() ? EnvOr("CELL_DDS_PROFILE", "") : opts.profile_path;
  char host[64] = {0};
  gethostname(host, sizeof host - 1);
  std::random_device rd;
  id_ = fmt::format("{}@{}/{}/{:x}", opts.name.empty() ? "cell" : opts.name, host, getpid(), rd() & 0xffffff);
  if (id_.size() > 63) id_ = id_.substr(id_.size() - 63);
  BackendOptions bo{domain_, profile, opts.name};
  if (backend == "fastdds") {
    backend_ = MakeFastDdsBackend(bo);
  } else if (backend == "cyclonedds") {
    throw Error(Errc::kUnimplemented,
                "CELL_DDS=cyclonedds: the Cyclone DDS backend of the bus is not built yet");
  } else {
    throw Error(Errc::kInvalidArgument, "CELL_DDS=" + backend + ": expected fastdds or cyclonedds");
  }
  thread_ = std::thread([this] { Run(); });
}

Participant::Participant(const std::string& name, int domain, std::unique_ptr<Backend> backend)
    : domain_(domain), backend_(std::move(backend)) {
  char host[64] = {0};
  gethostname(host, sizeof host - 1);
  std::random_device rd;
  id_ = fmt::format("{}@{}/{}/{:x}", name, host, getpid(), rd() & 0xffffff);
  if (id_.size() > 63) id_ = id_.substr(id_.size() - 63);
  thread_ = std::thread([this] { Run(); });
}

Participant::~Participant() {
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
