#include "openssl.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "cell/error/error.h"

namespace cell::security::detail {

namespace fs = std::filesystem;

namespace {

bool IsExecutableFile(const fs::path& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(p.c_str(), X_OK) == 0;
}

// The last non-empty line of `text`, trimmed.
std::string LastLine(const std::string& text) {
  std::string last;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (!line.empty()) last = line;
  }
  return last;
}

}  // namespace

fs::path FindProgram(const std::string& program) {
  if (program.find('/') != std::string::npos) {
    if (IsExecutableFile(program)) return program;
    throw Error(
        Errc::kFailedPrecondition,
        fmt::format("openssl not found: {} is no executable file (install the openssl package)", program));
  }
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "");
  for (std::string d; std::getline(dirs, d, ':');) {
    if (d.empty()) continue;
    fs::path candidate = fs::path(d) / program;
    if (IsExecutableFile(candidate)) return candidate;
  }
  throw Error(Errc::kFailedPrecondition,
              fmt::format("openssl not found: no '{}' in PATH (install the openssl package)", program));
}

void RunOpenssl(const fs::path& program, const std::vector<std::string>& args) {
  // argv is built before fork: the child of a threaded process may only make async-signal-safe calls.
  std::vector<std::string> all{program.string()};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  const std::string what = args.empty() ? "openssl" : "openssl " + args.front();

  int err[2];
  if (::pipe2(err, O_CLOEXEC) != 0)
    throw Error(Errc::kIo, fmt::format("{}: cannot make a pipe: {}", what, std::strerror(errno)));
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int e = errno;
    ::close(err[0]);
    ::close(err[1]);
    throw Error(Errc::kIo, fmt::format("{}: cannot fork: {}", what, std::strerror(e)));
  }
  if (pid == 0) {
    ::umask(077);  // keys are created owner-only, never readable for a moment
    const int null = ::open("/dev/null", O_RDWR);
    if (null < 0 || ::dup2(null, STDIN_FILENO) < 0 || ::dup2(null, STDOUT_FILENO) < 0 ||
        ::dup2(err[1], STDERR_FILENO) < 0)
      ::_exit(126);
    ::execv(argv[0], argv.data());
    static const char kMsg[] = "exec failed\n";
    [[maybe_unused]] auto n = ::write(STDERR_FILENO, kMsg, sizeof kMsg - 1);
    ::_exit(127);
  }
  ::close(err[1]);
  std::string text;
  char buf[4096];
  for (;;) {
    const ssize_t n = ::read(err[0], buf, sizeof buf);
    if (n > 0) {
      text.append(buf, static_cast<size_t>(n));
    } else if (n == 0 || errno != EINTR) {
      break;
    }
  }
  ::close(err[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  const std::string how = WIFEXITED(status) ? fmt::format("exit {}", WEXITSTATUS(status))
                                            : fmt::format("signal {}", WTERMSIG(status));
  const std::string line = LastLine(text);
  throw Error(Errc::kInternal,
              fmt::format("{} failed ({}): {}", what, how, line.empty() ? "no message" : line));
}

}  // namespace cell::security::detail
