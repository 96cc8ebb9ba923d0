#include "context.h"

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include <fmt/format.h>

#include "cell/bus/topics.h"

namespace cellctl {

bus::Participant& Context::Bus() {
  if (!bus_) bus_ = std::make_unique<bus::Participant>("cellctl");
  return *bus_;
}

cell::program_store::Client& Context::Programs() {
  if (!programs_) programs_ = std::make_unique<cell::program_store::Client>(Bus());
  return *programs_;
}

cell::SchedulerReply Context::Scheduler(cell::SchedulerRequest req, bus::Millis timeout) {
  if (!scheduler_)
    scheduler_ = std::make_unique<bus::Client<cell::SchedulerRequest, cell::SchedulerReply>>(
        Bus(), bus::topics::kScheduler);
  auto rep = scheduler_->Call(std::move(req), timeout);
  bus::ThrowIfError(rep);
  return rep;
}

std::optional<cell::ToolTable> Context::Tools(const std::string& station, bus::Millis timeout) {
  bus::Reader<cell::ToolTable> r(Bus(), bus::topics::kToolTable, bus::QosKind::kState);
  return r.WaitFor([&](const cell::ToolTable& t) { return t.station() == station; }, timeout);
}

std::optional<cell::StationVariables> Context::Variables(const std::string& station, bus::Millis timeout) {
  bus::Reader<cell::StationVariables> r(Bus(), bus::topics::kVariables, bus::QosKind::kState);
  return r.WaitFor([&](const cell::StationVariables& t) { return t.station() == station; }, timeout);
}

cell::StationReply Context::StationCommand(const std::string& station, cell::StationRequest req) {
  bus::Client<cell::StationRequest, cell::StationReply> c(Bus(), bus::topics::StationCommand(station));
  req.station(station);
  cell::StationReply rep;
  try {
    rep = c.Call(std::move(req), bus::Millis(5000));
  } catch (const cell::Error& e) {
    if (e.code() == cell::Errc::kUnavailable)
      throw cell::Error(cell::Errc::kUnavailable, "station " + station + " is not online");
    throw;
  }
  bus::ThrowIfError(rep);
  return rep;
}

std::string Context::IdempotencyKey(const std::string& what) const {
  // CELLCTL_IDEMPOTENCY_KEY lets a supervisor retry a command after a crash without running it twice.
  if (const char* k = std::getenv("CELLCTL_IDEMPOTENCY_KEY"); k && *k) return std::string(k) + ":" + what;
  std::random_device rd;
  return fmt::format("cellctl-{}-{:08x}{:08x}:{}", getpid(), rd(), rd(), what);
}

std::string ReadLocalFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Exit{1, "cannot read " + path};
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void PrintWarnings(const nlohmann::json& reply) {
  for (auto& w : reply.value("warnings", nlohmann::json::array()))
    std::cerr << "warning: " << w.get<std::string>() << "\n";
}

void Print(const Context& ctx, const nlohmann::json& j, const std::vector<std::string>& columns) {
  if (ctx.json) {
    std::cout << j.dump(2) << "\n";
    return;
  }
  auto cell_text = [](const nlohmann::json& v) -> std::string {
    if (v.is_null()) return "-";
    if (v.is_string()) return v.get<std::string>();
    if (v.is_number_float()) return fmt::format("{:g}", v.get<double>());
    return v.dump();
  };
  if (j.is_array()) {
    std::vector<size_t> w(columns.size());
    for (size_t c = 0; c < columns.size(); ++c) w[c] = columns[c].size();
    for (auto& row : j)
      for (size_t c = 0; c < columns.size(); ++c)
        w[c] = std::max(w[c], cell_text(row.value(columns[c], nlohmann::json())).size());
    for (size_t c = 0; c < columns.size(); ++c) std::cout << fmt::format("{:<{}}  ", columns[c], w[c]);
    std::cout << "\n";
    for (auto& row : j) {
      for (size_t c = 0; c < columns.size(); ++c)
        std::cout << fmt::format("{:<{}}  ", cell_text(row.value(columns[c], nlohmann::json())), w[c]);
      std::cout << "\n";
    }
    return;
  }
  for (auto& [k, v] : j.items()) std::cout << fmt::format("{:<14} {}\n", k + ":", cell_text(v));
}

}  // namespace cellctl
