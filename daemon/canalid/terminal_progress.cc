#include "daemon/canalid/terminal_progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <utility>

namespace canalid::cli {

TerminalProgress::TerminalProgress(std::string label)
    : label_(std::move(label)), enabled_(::isatty(STDERR_FILENO) == 1) {}

TerminalProgress::~TerminalProgress() { Done(); }

void TerminalProgress::Update(double fraction, const std::string& detail) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (shown_ && now - last_ < std::chrono::milliseconds(200)) return;
  last_ = now;
  shown_ = true;
  const int percent = static_cast<int>(100.0 * std::clamp(fraction, 0.0, 1.0));
  std::fprintf(stderr, "\r\033[K%s: %3d %%%s%s", label_.c_str(), percent,
               detail.empty() ? "" : "  ", detail.c_str());
  std::fflush(stderr);
}

void TerminalProgress::Show(const std::string& text) {
  if (!enabled_) return;
  shown_ = true;
  std::fprintf(stderr, "\r\033[K%s: %s", label_.c_str(), text.c_str());
  std::fflush(stderr);
}

void TerminalProgress::Done() {
  if (!shown_) return;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
  shown_ = false;
}

}  // namespace canalid::cli
