#pragma once
#include <chrono>
#include <string>

namespace canalid::cli {

/// Progress of long work on stderr, only when stderr is a terminal (logs and pipes stay clean):
/// one line rewritten in place (percentages at most every 200 ms), cleared by Done().
class TerminalProgress final {
 public:
  explicit TerminalProgress(std::string label);
  ~TerminalProgress();
  TerminalProgress(const TerminalProgress&) = delete;
  TerminalProgress& operator=(const TerminalProgress&) = delete;

  /// `fraction` in [0, 1]; `detail` follows the percentage.
  void Update(double fraction, const std::string& detail = "");
  /// Shows "label: text" now (for steps: "identifying arx (2/4)...").
  void Show(const std::string& text);
  /// Clears the line (also done by the destructor).
  void Done();
  bool enabled() const { return enabled_; }

 private:
  std::string label_;
  bool enabled_ = false;
  bool shown_ = false;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace canalid::cli
