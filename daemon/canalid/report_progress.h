#pragma once
#include <ostream>
#include <string>

namespace canalid::cli {

/// One status line on a terminal, rewritten in place ("canalid report: plotting 3/7..."); silent
/// when disabled (stderr is not a terminal), so logs and pipes stay clean.
class Progress {
 public:
  Progress(std::ostream& out, bool enabled) : out_(out), enabled_(enabled) {}
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  ~Progress() { Finish(); }
  /// Replaces the status line.
  void Show(const std::string& text);
  /// Clears the status line (also done by the destructor).
  void Finish();

 private:
  std::ostream& out_;
  bool enabled_;
  bool shown_ = false;
};

/// True when file descriptor 2 is a terminal.
bool StderrIsTerminal();

}  // namespace canalid::cli
