#include "processes.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstddef>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <thread>

#include "cell/config/config.h"
#include "context.h"

extern char** environ;

namespace cellctl {

namespace fs = std::filesystem;

nlohmann::json ToJson(const CellProcess& p) {
  return {{"service", p.service}, {"unit", p.unit}, {"pid", p.pid}, {"log", p.log},
          {"argv", p.argv},       {"env", p.env},   {"exe", p.exe}, {"start_time", p.start_time}};
}

CellProcess FromJson(const nlohmann::json& j) {
  CellProcess p;
  p.service = j.at("service").get<std::string>();
  p.unit = j.at("unit").get<std::string>();
  p.pid = j.at("pid").get<pid_t>();
  p.log = j.value("log", std::string());
  p.argv = j.value("argv", std::vector<std::string>());
  p.env = j.value("env", std::vector<std::string>());
  p.exe = j.value("exe", std::string());
  p.start_time = j.value("start_time", std::uint64_t{0});
  return p;
}

fs::path RecordFile() {
  return cell::config::DataDir() / "cell-up.json";
}

std::vector<CellProcess> LoadRecord() {
  std::ifstream in(RecordFile());
  if (!in) return {};
  auto j = nlohmann::json::parse(in, nullptr, false);
  std::vector<CellProcess> out;
  try {
    if (!j.is_array()) throw std::runtime_error("not an array");
    for (auto& e : j) out.push_back(FromJson(e));
  } catch (const std::exception&) {
    throw Exit{1, RecordFile().string() + " is not a cellctl process list"};
  }
  return out;
}

void SaveRecord(const std::vector<CellProcess>& procs) {
  nlohmann::json j = nlohmann::json::array();
  for (auto& p : procs) j.push_back(ToJson(p));
  fs::path file = RecordFile(), tmp = file;
  tmp += ".tmp";
  {
    int fd = open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd < 0) throw Exit{1, "cannot write " + tmp.string() + ": " + std::strerror(errno)};
    std::string text = j.dump(2) + "\n";
    bool ok = write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
    ok = fsync(fd) == 0 && ok;
    close(fd);
    if (!ok) throw Exit{1, "cannot write " + tmp.string()};
  }
  fs::rename(tmp, file);
}

RecordLock::RecordLock() {
  fs::path lock = RecordFile();
  lock += ".lock";
  fd_ = open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  if (fd_ >= 0) flock(fd_, LOCK_EX);
}

RecordLock::~RecordLock() {
  if (fd_ >= 0) close(fd_);  // releases the lock
}

namespace {

// The domain in a NUL-separated environment block: CELL_DOMAIN's value, 101 (config::Domain's default)
// without it, nullopt when it is not a number.
std::optional<int> DomainIn(const std::string& environ) {
  std::size_t at = 0;
  while (at < environ.size()) {
    std::size_t end = environ.find('\0', at);
    if (end == std::string::npos) end = environ.size();
    if (environ.compare(at, 12, "CELL_DOMAIN=") == 0) {
      try {
        return std::stoi(environ.substr(at + 12, end - at - 12));
      } catch (const std::exception&) {
        return std::nullopt;
      }
    }
    at = end + 1;
  }
  return 101;
}

// Whether the process of /proc/PID is exiting or a zombie: /proc/PID/stat (readable by anyone) gives its
// state (field 3) and its flags (field 9), PF_EXITING being 0x4.
bool Exiting(const fs::path& proc_pid) {
  std::string stat;
  std::getline(std::ifstream(proc_pid / "stat"), stat);
  const std::size_t paren = stat.rfind(')');
  if (paren == std::string::npos) return true;  // gone between the calls
  std::istringstream fields(stat.substr(paren + 1));
  std::string state, skip;
  unsigned long flags = 0;
  fields >> state >> skip >> skip >> skip >> skip >> skip >> flags;
  constexpr unsigned long kPfExiting = 0x4;
  return state == "Z" || state == "X" || (flags & kPfExiting) != 0;
}

}  // namespace

std::optional<std::string> LocalServiceOn(int domain) {
  // /proc/PID/comm holds the first 15 characters of the executable's name.
  static const char* const kServices[] = {"cell-scheduler",  "cell-program-st", "cell-interprete",
                                          "cell-axis-servo", "cell-inspection", "cell-dashboard",
                                          "cell-dnc"};
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator("/proc", ec)) {
    const std::string pid = entry.path().filename().string();
    if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string comm;
    std::getline(std::ifstream(entry.path() / "comm"), comm);
    if (std::none_of(std::begin(kServices), std::end(kServices), [&](const char* s) { return comm == s; }))
      continue;
    const std::string what = comm + " (pid " + pid + ")";
    // A process that exits between the listing and here is no service (a test tearing its cell down next
    // to ours made every verb wait out discovery); one whose environment is not ours to read may be on our
    // domain. Briefly unreadable (mid-exec), it is read again. An exiting process has released its memory:
    // its environment reads empty or fails, and it is skipped too.
    std::optional<std::string> block;
    for (int attempt = 0; attempt < 3 && !block; ++attempt) {
      if (attempt > 0) usleep(2000);
      int fd = open((entry.path() / "environ").c_str(), O_RDONLY | O_CLOEXEC);
      if (fd < 0 && (errno == ENOENT || errno == ESRCH)) break;
      if (fd < 0) continue;
      std::string text;
      char buf[4096];
      ssize_t n;
      while ((n = read(fd, buf, sizeof buf)) > 0) text.append(buf, static_cast<std::size_t>(n));
      close(fd);
      if (n == 0) block = std::move(text);
    }
    if (!block || block->empty()) {
      struct stat st {};
      if (stat(entry.path().c_str(), &st) != 0) continue;  // gone
      // Without its memory (exiting, a zombie) a process's /proc files belong to root, so its environment
      // cannot be read even by its owner (issue 44's flake: a test's service on its way out made `route
      // show` wait out discovery). A process on its way out is no service.
      if (Exiting(entry.path())) continue;
      // A live process with an empty environment runs on the default domain (DomainIn below).
      if (!block) return what + ", whose environment cannot be read";
    }
    const std::optional<int> d = DomainIn(*block);
    if (!d || *d == domain) return what;
  }
  return std::nullopt;
}

bool IsRunning(const CellProcess& p) {
  auto t = StartTime(p.pid);
  if (!t || (p.start_time != 0 && *t != p.start_time)) return false;
  if (p.exe.empty()) return true;  // a record written before exe and start_time were kept
  std::error_code ec;
  std::string exe = fs::read_symlink("/proc/" + std::to_string(p.pid) + "/exe", ec).string();
  if (ec) return false;
  const std::string deleted = " (deleted)";
  if (exe.size() > deleted.size() && exe.compare(exe.size() - deleted.size(), deleted.size(), deleted) == 0)
    exe.resize(exe.size() - deleted.size());
  return exe == p.exe;
}

std::vector<std::string> CurrentEnvironment() {
  std::vector<std::string> env;
  for (char** e = environ; e && *e; ++e) env.emplace_back(*e);
  return env;
}

void Launch(CellProcess& p, const std::vector<std::string>& extra_env) {
  std::error_code ec;
  p.exe = fs::canonical(p.argv.at(0), ec).string();
  if (ec) throw Exit{1, "cannot start " + p.unit + ": " + p.argv[0] + ": " + ec.message()};
  // Everything the child needs is prepared before fork(): after it only async-signal-safe calls.
  std::vector<char*> args, envp;
  for (auto& a : p.argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  for (auto& e : p.env) envp.push_back(const_cast<char*>(e.c_str()));
  for (auto& e : extra_env) envp.push_back(const_cast<char*>(e.c_str()));
  envp.push_back(nullptr);
  const std::string log = p.log;
  pid_t pid = fork();
  if (pid < 0) throw Exit{1, std::string("fork failed: ") + std::strerror(errno)};
  if (pid == 0) {
    setsid();    // its own session: survives cellctl, stopped by `cellctl down`
    umask(077);  // a local cell's state and logs are its owner's only (the units use UMask=0027)
    int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0600);
    int null = open("/dev/null", O_RDONLY);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
    }
    if (null >= 0) dup2(null, 0);
    // Nothing of cellctl's beyond stdin, stdout and stderr reaches the service (a DDS socket nobody reads
    // would fill its receive queue for ever).
    syscall(SYS_close_range, 3U, UINT_MAX, 0U);
    execve(args[0], args.data(), envp.data());
    _exit(127);
  }
  p.pid = pid;
  p.start_time = StartTime(pid).value_or(0);
}

ReadyListener::ReadyListener()
    : name_("cellctl-ready/" + std::to_string(getpid()) + "/" +
            std::to_string(std::chrono::steady_clock::now().time_since_epoch().count())) {
  fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw Exit{1, std::string("cannot make a notify socket: ") + std::strerror(errno)};
  const int on = 1;
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::memcpy(a.sun_path + 1, name_.data(), name_.size());  // sun_path[0] = 0: the abstract namespace
  const auto len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + 1 + name_.size());
  if (setsockopt(fd_, SOL_SOCKET, SO_PASSCRED, &on, sizeof on) != 0 ||
      bind(fd_, reinterpret_cast<const sockaddr*>(&a), len) != 0) {
    const std::string why = std::strerror(errno);
    close(fd_);
    throw Exit{1, "cannot make a notify socket: " + why};
  }
}

ReadyListener::~ReadyListener() {
  if (fd_ >= 0) close(fd_);
}

std::vector<std::string> ReadyListener::Env() const {
  return {"NOTIFY_SOCKET=@" + name_, "CELL_NOTIFY=ready"};
}

bool ReadyListener::Wait(const CellProcess& p, std::chrono::steady_clock::time_point deadline) {
  // Alive (not a zombie) by its PID: IsRunning's executable check would fail between fork and exec.
  while (std::chrono::steady_clock::now() < deadline && StartTime(p.pid)) {
    pollfd pfd{fd_, POLLIN, 0};
    if (poll(&pfd, 1, 100) <= 0) continue;
    char buf[4096];
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(ucred))];
    iovec iov{buf, sizeof buf - 1};
    msghdr m{};
    m.msg_iov = &iov;
    m.msg_iovlen = 1;
    m.msg_control = control;
    m.msg_controllen = sizeof control;
    const ssize_t n = recvmsg(fd_, &m, MSG_DONTWAIT);
    if (n <= 0) continue;
    buf[n] = '\0';
    pid_t from = 0;
    for (cmsghdr* c = CMSG_FIRSTHDR(&m); c; c = CMSG_NXTHDR(&m, c))
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_CREDENTIALS) {
        ucred cred{};
        std::memcpy(&cred, CMSG_DATA(c), sizeof cred);
        from = cred.pid;
      }
    if (from != p.pid) continue;  // a message of another process that found the name
    std::istringstream lines(buf);
    for (std::string line; std::getline(lines, line);)
      if (line == "READY=1") return true;
  }
  return false;
}

std::vector<std::string> Stop(const std::vector<CellProcess>& procs, std::chrono::seconds grace) {
  std::vector<std::string> foreign;
  std::vector<const CellProcess*> ours;
  for (auto& p : procs) {
    if (IsRunning(p)) {
      kill(p.pid, SIGTERM);
      ours.push_back(&p);
    } else if (p.pid > 0 && kill(p.pid, 0) == 0 && StartTime(p.pid)) {
      foreign.push_back("pid " + std::to_string(p.pid) + " is no longer " + p.service + ": left alone");
    }
  }
  auto deadline = std::chrono::steady_clock::now() + grace;
  for (auto* p : ours) {
    while (IsRunning(*p) && std::chrono::steady_clock::now() < deadline) {
      waitpid(p->pid, nullptr, WNOHANG);  // our own children (a failed `up`) are reaped here
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (IsRunning(*p)) kill(p->pid, SIGKILL);
    waitpid(p->pid, nullptr, WNOHANG);
  }
  return foreign;
}

std::string LastLine(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

}  // namespace cellctl
