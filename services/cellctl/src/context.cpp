#include "context.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include <fmt/format.h>

#include "cell/bus/topics.h"
#include "cell/config/config.h"
#include "cell/error/error.h"
#include "cell/names/names.h"
#include "processes.h"

namespace cellctl {

bus::Participant& Context::Bus() {
  if (!bus_) {
    bus::ParticipantOptions o = bus::Named("cellctl");
    // A cell that is down is said so at once (issue 39 item 6), unless one of its services runs here: then
    // discovery, however slow, is waited out.
    local_service_ = LocalServiceOn(cell::config::Domain());
    o.lone_means_down = !local_service_;
    o.host_services_only = host_services_only;
    bus_ = std::make_unique<bus::Participant>(o);
  }
  return *bus_;
}

void ServicesOnly(CLI::App* noun, Context& ctx) {
  noun->preparse_callback([&ctx](std::size_t) { ctx.host_services_only = true; });
}

std::string Context::Explain(const cell::Error& e) {
  std::string what = e.what();
  // A service missing after the whole discovery bound: say what kept the answer from coming at once.
  if (e.code() != cell::Errc::kUnavailable || !bus_ || what.find("is the cell up?") != std::string::npos)
    return what;
  if (local_service_) return what + " (" + *local_service_ + " runs on this host on the domain)";
  const int others = bus_->RemoteParticipants();
  if (others > 0)
    return what + fmt::format(" ({} other participant{} on the domain)", others, others == 1 ? "" : "s");
  return what;
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

bool Context::SchedulerUp(bus::Millis timeout) {
  if (!scheduler_)
    scheduler_ = std::make_unique<bus::Client<cell::SchedulerRequest, cell::SchedulerReply>>(
        Bus(), bus::topics::kScheduler);
  return scheduler_->WaitForServer(timeout);
}

cell::InspectionReply Context::Inspection(cell::InspectionRequest req, bus::Millis timeout) {
  if (!inspection_)
    inspection_ = std::make_unique<bus::Client<cell::InspectionRequest, cell::InspectionReply>>(
        Bus(), bus::topics::kInspection);
  auto rep = inspection_->Call(std::move(req), timeout);
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

std::string Context::IdempotencyKey(const std::string& verb) const {
  // CELLCTL_IDEMPOTENCY_KEY lets a supervisor retry a command after a crash without running it twice.
  if (const char* k = std::getenv("CELLCTL_IDEMPOTENCY_KEY")) {
    // An empty key is a mistake (a variable set from nothing), not "no key": the retry would run twice.
    if (*k == '\0') {
      throw cell::Error(cell::Errc::kInvalidArgument,
                        "CELLCTL_IDEMPOTENCY_KEY is set but empty: give a key or unset the variable");
    }
    return cell::names::WireKey(k, verb);
  }
  std::random_device rd;
  return fmt::format("cellctl-{}-{:08x}{:08x}:{}", getpid(), rd(), rd(), verb);
}

std::string ReadLocalFile(const std::string& path, std::uint64_t max_bytes, const std::string& what) {
  auto fail = [&](const std::string& why) { return Exit{1, "cannot read " + path + ": " + why}; };
  int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw fail(std::strerror(errno));
  struct Closer {
    int fd;
    ~Closer() { close(fd); }
  } closer{fd};
  struct stat st {};
  if (fstat(fd, &st) != 0) throw fail(std::strerror(errno));
  if (S_ISDIR(st.st_mode)) throw fail("it is a directory");
  auto too_large = [&](std::uint64_t n, bool at_least) {
    return Exit{1, fmt::format("{} is {}{} bytes; {} takes at most {} bytes", path,
                               at_least ? "more than " : "", n, what, max_bytes)};
  };
  // From the size alone when the system knows it: nothing is read, nothing is sent.
  if (S_ISREG(st.st_mode) && static_cast<std::uint64_t>(st.st_size) > max_bytes)
    throw too_large(static_cast<std::uint64_t>(st.st_size), false);
  std::string out;
  char buf[65536];
  for (;;) {
    ssize_t n = read(fd, buf, sizeof buf);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw fail(std::strerror(errno));
    }
    if (n == 0) break;
    if (out.size() + static_cast<std::size_t>(n) > max_bytes) throw too_large(max_bytes, true);
    out.append(buf, static_cast<std::size_t>(n));
  }
  if (out.empty()) throw Exit{1, path + " is empty: nothing to send"};
  return out;
}

CLI::Validator Decimal() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        if (s.empty() || s.size() > 9 ||
            !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
          return "expected a decimal integer (digits only), got " + cell::names::Shown(s);
        // CLI11 converts with base detection: without its leading zeros "010" stays ten, not octal eight.
        s.erase(0, std::min(s.find_first_not_of('0'), s.size() - 1));
        return "";
      },
      "DECIMAL");
}

CLI::Validator Real() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        int dots = 0, digits = 0;
        for (char c : s) {
          if (c == '.')
            ++dots;
          else if (c >= '0' && c <= '9')
            ++digits;
          else
            digits = -1000;
        }
        if (digits <= 0 || dots > 1 || s.size() > 16)
          return "expected a decimal number (digits and at most one '.'), got " + cell::names::Shown(s);
        return "";
      },
      "NUMBER");
}

void AddPaging(CLI::App* verb, Paging& paging, bool numeric_cursor) {
  verb->add_option("--limit", paging.limit, "at most N rows (default 1000)")
      ->transform(Decimal())
      ->check(CLI::Range(1u, 999999999u));
  auto* after = verb->add_option("--after", paging.after,
                                 numeric_cursor ? "rows after this job id (the last of the previous page)"
                                                : "rows after this name (the last of the previous page)");
  if (numeric_cursor) after->transform(Decimal());
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
