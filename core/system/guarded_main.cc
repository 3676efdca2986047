#include "core/system/guarded_main.h"

#include <cstdio>
#include <exception>

namespace canalid::core {

int GuardedMain(const char* program, int (*body)(int, char**), int argc, char** argv) noexcept {
  try {
    return body(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: internal error: %s\n", program, e.what());
  } catch (...) {
    std::fprintf(stderr, "%s: internal error: an exception of unknown type\n", program);
  }
  return kExitInternalError;
}

}  // namespace canalid::core
