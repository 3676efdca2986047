#include "daemon/canalid/report_progress.h"

#include <unistd.h>

namespace canalid::cli {

void Progress::Show(const std::string& text) {
  if (!enabled_) return;
  // Carriage return and erase-to-end-of-line: the line is rewritten, not appended.
  out_ << "\rcanalid report: " << text << "\x1b[K" << std::flush;
  shown_ = true;
}

void Progress::Finish() {
  if (!shown_) return;
  out_ << "\r\x1b[K" << std::flush;
  shown_ = false;
}

bool StderrIsTerminal() { return isatty(STDERR_FILENO) == 1; }

}  // namespace canalid::cli
