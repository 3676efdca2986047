#pragma once
// Debian's chromium, headless, driven over the DevTools protocol from the test: it loads a page
// and the test evaluates JavaScript in it (to read the live DOM) and takes screenshots.  The
// browser is started with its own profile folder under the test's scratch folder and stopped by
// pid.  Without /usr/bin/chromium the test fails, naming the package: it never passes silently.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "tests/support/child_process.h"
#include "tests/support/http_client.h"

namespace canalid::testing {

class HeadlessChromium {
 public:
  /// Starts the browser on `url`; false (with `error`) when it cannot.
  bool Start(const std::string& url, const std::filesystem::path& scratch, std::string* error) {
    if (!std::filesystem::exists("/usr/bin/chromium")) {
      *error = "/usr/bin/chromium is missing (Debian package chromium; scripts/setup installs it)";
      return false;
    }
    std::vector<std::string> argv = {"/usr/bin/chromium",
                                     "--headless",
                                     "--disable-gpu",
                                     "--no-first-run",
                                     "--disable-dev-shm-usage",
                                     "--window-size=1400,1800",
                                     "--remote-debugging-port=0",
                                     "--user-data-dir=" + (scratch / "chromium-profile").string()};
    if (geteuid() == 0) argv.push_back("--no-sandbox");  // its sandbox refuses to run as root
    argv.push_back(url);
    browser_ = std::make_unique<ChildProcess>(
        argv, std::vector<std::string>{"HOME=" + scratch.string()}, scratch / "chromium.log");
    const std::string line = browser_->WaitForLine("DevTools listening on ws://", 60000);
    std::smatch match;
    static const std::regex kPort(R"(ws://127\.0\.0\.1:(\d+)/)");
    if (!std::regex_search(line, match, kPort)) {
      *error = "chromium did not start its DevTools server: " + browser_->output();
      return false;
    }
    const int devtools_port = std::stoi(match[1]);
    std::string page_path;
    // The page target appears once the browser has opened its first tab.
    browser_->WaitUntil(
        [&] {
          const std::string body = HttpBody(HttpGet(devtools_port, "/json/list"));
          const auto targets = nlohmann::json::parse(body, nullptr, false);
          if (!targets.is_array()) return false;
          for (const auto& target : targets) {
            if (target.value("type", "") == "page") {
              const std::string ws = target.value("webSocketDebuggerUrl", "");
              const std::size_t at = ws.find("/devtools/");
              if (at != std::string::npos) page_path = ws.substr(at);
            }
          }
          return !page_path.empty();
        },
        30000, 100);
    if (page_path.empty()) {
      *error = "chromium opened no page target";
      return false;
    }
    return page_.Connect(devtools_port, page_path, error, 30.0);
  }

  /// The value of `expression` evaluated in the page (JSON null when it threw or nothing came).
  nlohmann::json Evaluate(const std::string& expression) {
    const nlohmann::json reply =
        Call("Runtime.evaluate", {{"expression", expression}, {"returnByValue", true}});
    if (!reply.contains("result") || reply["result"].contains("exceptionDetails")) return nullptr;
    return reply["result"]["result"].value("value", nlohmann::json());
  }

  /// Writes a PNG of the page as shown (its whole height); false when it could not.
  bool Screenshot(const std::filesystem::path& path) {
    const nlohmann::json reply =
        Call("Page.captureScreenshot", {{"format", "png"}, {"captureBeyondViewport", true}});
    if (!reply.contains("result") || !reply["result"].contains("data")) return false;
    const std::string png = Base64Decode(reply["result"]["data"].get<std::string>());
    std::ofstream(path, std::ios::binary) << png;
    return !png.empty();
  }

  ~HeadlessChromium() {
    page_.Close();
    if (browser_) browser_->Stop(SIGTERM, 10000);
  }

 private:
  nlohmann::json Call(const std::string& method, const nlohmann::json& params) {
    const int id = ++last_id_;
    if (!page_.Write(nlohmann::json{{"id", id}, {"method", method}, {"params", params}}.dump())) {
      return nlohmann::json::object();
    }
    std::string text;
    while (page_.Read(&text)) {
      auto reply = nlohmann::json::parse(text, nullptr, false);
      if (reply.is_object() && reply.value("id", -1) == id) return reply;
    }
    return nlohmann::json::object();
  }

  static std::string Base64Decode(const std::string& text) {
    static const std::string kAlphabet =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    int bits = 0;
    unsigned value = 0;
    for (const char c : text) {
      const std::size_t at = kAlphabet.find(c);
      if (at == std::string::npos) continue;  // '=' padding
      value = (value << 6U) | static_cast<unsigned>(at);
      bits += 6;
      if (bits >= 8) {
        bits -= 8;
        out += static_cast<char>((value >> static_cast<unsigned>(bits)) & 0xFFU);
      }
    }
    return out;
  }

  std::unique_ptr<ChildProcess> browser_;
  WebSocketClient page_;
  int last_id_ = 0;
};

}  // namespace canalid::testing
