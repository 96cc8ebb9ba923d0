// A headless Chromium driven through chromedriver's W3C WebDriver protocol (HTTP + JSON, cpp-httplib):
// open a page, run a script in it and read the live DOM, take a screenshot. For the dashboard's browser
// test and its DOM-latency benchmark. Chromium runs with the flags a CI host needs (--headless
// --no-sandbox --disable-gpu ...), no network service of its own and a fresh profile directory.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

namespace cell::testing {

class Process;

class Browser {
 public:
  // Starts chromedriver on a free loopback port and a browser session (window width x height).
  // Throws std::runtime_error with chromedriver's message when either fails.
  explicit Browser(int width = 1600, int height = 1200);
  ~Browser();
  Browser(const Browser&) = delete;
  Browser& operator=(const Browser&) = delete;

  void Navigate(const std::string& url);
  // Runs `script` (a function body: `return ...;`) in the page and returns its value.
  nlohmann::json Exec(const std::string& script, const nlohmann::json& args = nlohmann::json::array());
  // Polls Exec(script) every 50 ms until it returns true (or something truthy); false at the deadline.
  bool WaitTrue(const std::string& script, std::chrono::milliseconds timeout);
  // A PNG of the viewport, written to `path`.
  void Screenshot(const std::string& path);

 private:
  nlohmann::json Call(const std::string& method, const std::string& path, const nlohmann::json& body);
  int port_ = 0;
  std::string profile_;
  std::string session_;
  std::unique_ptr<Process> driver_;
};

}  // namespace cell::testing
