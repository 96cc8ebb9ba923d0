#include "cell/testing/webdriver.h"

#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "cell/testing/process.h"

namespace cell::testing {

namespace {

int FreePort() {
  int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  if (fd < 0 || bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
      getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0)
    throw std::runtime_error("no free port for chromedriver");
  int port = ntohs(a.sin_port);
  close(fd);
  return port;
}

std::string Base64Decode(const std::string& in) {
  static const std::string chars = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  int val = 0, bits = -8;
  for (unsigned char c : in) {
    auto p = chars.find(static_cast<char>(c));
    if (p == std::string::npos) continue;  // '=' and line breaks
    val = (val << 6) + static_cast<int>(p);
    bits += 6;
    if (bits >= 0) {
      out.push_back(static_cast<char>((val >> bits) & 0xFF));
      bits -= 8;
    }
  }
  return out;
}

}  // namespace

Browser::Browser(int width, int height) {
  port_ = FreePort();
  profile_ = MakeTempDir("cell-chromium-");
  driver_ = std::make_unique<Process>(
      std::vector<std::string>{"/usr/bin/chromedriver", "--port=" + std::to_string(port_)},
      std::map<std::string, std::string>{}, profile_ + "/chromedriver.out", profile_ + "/chromedriver.err");
  httplib::Client c("127.0.0.1", port_);
  bool up = false;
  for (int i = 0; i < 200 && !up; ++i) {
    auto r = c.Get("/status");
    up = r && r->status == 200;
    if (!up) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (!up)
    throw std::runtime_error("chromedriver did not start: " + ReadFile(profile_ + "/chromedriver.err"));
  nlohmann::json args = {"--headless",
                         "--no-sandbox",
                         "--disable-gpu",
                         "--disable-background-networking",
                         "--disable-component-update",
                         "--disable-sync",
                         "--no-first-run",
                         "--disable-dev-shm-usage",
                         "--user-data-dir=" + profile_ + "/profile",
                         "--window-size=" + std::to_string(width) + "," + std::to_string(height)};
  auto r = Call("POST", "/session",
                {{"capabilities",
                  {{"alwaysMatch",
                    {{"browserName", "chrome"},
                     {"goog:chromeOptions", {{"binary", "/usr/bin/chromium"}, {"args", args}}}}}}}});
  session_ = r["sessionId"].get<std::string>();
}

Browser::~Browser() {
  if (!session_.empty()) {
    try {
      Call("DELETE", "/session/" + session_, nullptr);
    } catch (const std::exception&) {
    }
  }
  driver_.reset();  // kills chromedriver's process group (and a browser left behind)
  std::error_code ec;
  std::filesystem::remove_all(profile_, ec);
}

nlohmann::json Browser::Call(const std::string& method, const std::string& path, const nlohmann::json& body) {
  httplib::Client c("127.0.0.1", port_);
  c.set_read_timeout(60, 0);
  httplib::Result r = method == "GET"      ? c.Get(path)
                      : method == "DELETE" ? c.Delete(path)
                                           : c.Post(path, body.dump(), "application/json");
  if (!r) throw std::runtime_error("chromedriver " + method + " " + path + ": no answer");
  auto j = nlohmann::json::parse(r->body, nullptr, false);
  if (r->status != 200 || j.is_discarded())
    throw std::runtime_error("chromedriver " + method + " " + path + ": " + std::to_string(r->status) + " " +
                             r->body);
  return j["value"];
}

void Browser::Navigate(const std::string& url) {
  Call("POST", "/session/" + session_ + "/url", {{"url", url}});
}

nlohmann::json Browser::Exec(const std::string& script, const nlohmann::json& args) {
  return Call("POST", "/session/" + session_ + "/execute/sync", {{"script", script}, {"args", args}});
}

bool Browser::WaitTrue(const std::string& script, std::chrono::milliseconds timeout) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    auto v = Exec(script);
    if (!v.is_null() && v != false && v != 0 && v != "") return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

void Browser::Screenshot(const std::string& path) {
  auto png = Base64Decode(Call("GET", "/session/" + session_ + "/screenshot", nullptr).get<std::string>());
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << png;
}

}  // namespace cell::testing
